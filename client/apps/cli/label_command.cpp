// primlabel label: read each file, label it on the server, write the labeled cloud (and a PNG).
// A bad file or a rejected request is reported and the next file goes on; an unreachable server
// ends the run at once (the remaining files would fail the same way).

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <initializer_list>
#include <tuple>

#include "commands.hpp"
#include "common/labeled_output.hpp"
#include "common/object_json.hpp"
#include "common/primitive_json.hpp"
#include "input_files.hpp"
#include "primlabel/cli/cli_common.hpp"
#include "primlabel/geometry/atomic_file.hpp"
#include "primlabel/geometry/cloud_io.hpp"
#include "primlabel/overlays/object_overlays.hpp"
#include "server_wait_progress.hpp"
#include "status_exit_codes.hpp"

namespace primlabel::client::tools {

namespace fs = std::filesystem;

namespace {

std::string default_name(const fs::path& input) { return input.stem().string() + "_labeled.pcd"; }

// Where the labeled version of `input` goes, per the -o rules in --help.
std::string output_path(const LabelCommand& command, const fs::path& input) {
  if (command.output.empty()) return (input.parent_path() / default_name(input)).string();
  const fs::path out(command.output);
  if (command.into_directory || fs::is_directory(out)) return (out / default_name(input)).string();
  return out.string();
}

// Where the JSON `what` ("primitives", "objects") of `input` goes: `target` itself, or inside it
// for several inputs.
std::string json_path(const LabelCommand& command, const std::string& target, const fs::path& input,
                      const char* what) {
  const fs::path out(target);
  if (command.into_directory || fs::is_directory(out))
    return (out / (input.stem().string() + "_" + what + ".json")).string();
  return out.string();
}

// For several inputs the JSON goes into a directory: false (and said) when it cannot be made.
bool make_json_directory(const LabelCommand& command, const std::string& target, const char* what) {
  if (!command.into_directory || target.empty()) return true;
  std::error_code ec;
  fs::create_directories(target, ec);
  if (!ec) return true;
  std::fprintf(stderr, "primlabel: %s: cannot create the %s directory: %s\n", target.c_str(), what,
               ec.message().c_str());
  return false;
}

// Several inputs write into a directory: a target that is a file, or that names one by its
// extension (`-o single.pcd`), would silently become a directory. The one-line reason, or "".
std::string not_a_directory_target(const LabelCommand& command, const std::string& flag,
                                   const std::string& target,
                                   std::initializer_list<const char*> file_extensions) {
  if (!command.into_directory || target.empty()) return {};
  const fs::path path(target);
  std::error_code ec;
  const bool exists = fs::exists(path, ec);
  std::string ext = path.extension().string();
  for (char& c : ext) c = char(std::tolower(static_cast<unsigned char>(c)));
  const bool looks_like_a_file = std::any_of(file_extensions.begin(), file_extensions.end(),
                                             [&](const char* e) { return ext == e; });
  if ((exists && !fs::is_directory(path, ec)) || (!exists && looks_like_a_file))
    return flag + " " + target + ": " + std::to_string(command.inputs.size()) +
           " inputs write one file each into a directory; give a directory (or one input)";
  return {};
}

}  // namespace

int run_label(Client& client, LabelCommand command) {
  int exit_code = kExitOk;
  InputFiles inputs = expand_input_folders(command.inputs);
  for (const std::string& error : inputs.errors) {
    std::fprintf(stderr, "primlabel: %s\n", error.c_str());
    exit_code = kExitFile;
  }
  if (inputs.files.empty()) return exit_code;
  command.inputs = std::move(inputs.files);
  command.into_directory = command.inputs.size() > 1 || inputs.from_folder;
  for (const auto& [flag, target, extensions] :
       {std::tuple{std::string("-o"), command.output,
                   std::initializer_list<const char*>{".pcd", ".ply"}},
        std::tuple{std::string("--primitives"), command.primitives,
                   std::initializer_list<const char*>{".json"}},
        std::tuple{std::string("--objects"), command.objects,
                   std::initializer_list<const char*>{".json"}}}) {
    if (const std::string why = not_a_directory_target(command, flag, target, extensions);
        !why.empty()) {
      std::fprintf(stderr, "primlabel: %s\n", why.c_str());
      return kExitUsage;
    }
  }
  if (command.into_directory && !command.output.empty()) {
    std::error_code ec;
    fs::create_directories(command.output, ec);
    if (ec) {
      std::fprintf(stderr, "primlabel: %s: cannot create the output directory: %s\n",
                   command.output.c_str(), ec.message().c_str());
      return kExitFile;
    }
  }
  command.options.descriptors = command.descriptors;
  command.options.probabilities = command.probabilities;
  command.options.primitives = !command.primitives.empty();
  // The picture draws the table-top objects, so it asks for them even without --objects.
  command.options.objects =
      !command.objects.empty() || (command.png && command.options.tabletop_only);
  if (!command.objects.empty() && !command.options.tabletop_only) {
    std::fprintf(stderr,
                 "primlabel: --objects needs --tabletop (the objects are the table-top "
                 "stage's)\n");
    return kExitUsage;
  }
  if (!make_json_directory(command, command.primitives, "primitives") ||
      !make_json_directory(command, command.objects, "objects"))
    return kExitFile;
  cli::ProgressPrinter progress(command.quiet);
  for (const std::string& input : command.inputs) {
    PointCloud cloud;
    try {
      cloud = read_cloud(input);
    } catch (const std::exception& e) {
      std::fprintf(stderr, "primlabel: %s\n", e.what());
      if (exit_code == kExitOk) exit_code = kExitFile;
      continue;
    }
    if (count_finite(cloud) == 0) {
      std::fprintf(stderr,
                   "primlabel: %s: no point has finite coordinates (%zu points): nothing "
                   "to label\n",
                   input.c_str(), cloud.size());
      if (exit_code == kExitOk) exit_code = kExitFile;
      continue;
    }
    LabelOptions options = command.options;
    if (options.scan_id.empty()) options.scan_id = fs::path(input).stem().string();
    const auto start = std::chrono::steady_clock::now();
    LabelResult result;
    ServerWaitProgress waiting(command.quiet, input);
    try {
      if (command.unary) {
        waiting.start();  // one message: nothing to count while it goes
        result = client.label_unary(cloud, options);
      } else {
        const ProgressFn sending = progress.stage("send " + input);
        result = client.label(cloud, options, [&](std::size_t sent, std::size_t total) {
          if (sending) sending(sent, total);
          if (sent == total) {
            progress.done();
            waiting.start();
          }
        });
      }
      waiting.stop();
      progress.done();
    } catch (const ClientError& e) {
      waiting.stop();
      progress.done();
      if (exit_code_for(e.code()) == kExitUnavailable) throw;
      std::fprintf(stderr, "primlabel: %s: %s\n", input.c_str(), e.what());
      if (exit_code == kExitOk) exit_code = kExitRejected;
      continue;
    }
    const double seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    const std::string out = output_path(command, input);
    const bool had_labels = cloud.has_labels();
    std::string histogram;
    try {
      PointCloud labeled = labeled_cloud(std::move(cloud), result);
      histogram = label_histogram(labeled);
      if (!command.objects.empty() && !result.object_ids.empty())
        labeled.set_field("object", 1).values = object_field(result.object_ids);
      write_labeled_cloud(out, labeled, result);
      if (command.png) {
        LabelPicture picture;
        picture.title = fs::path(input).filename().string() + " - " + result.summary.model() + " " +
                        result.summary.model_version();
        picture.view = render_view(command.view);
        if (command.options.objects) picture.overlays = object_overlays(objects_of(result.summary));
        write_label_png(labeled, fs::path(out).replace_extension(".png").string(), picture);
      }
      if (!command.primitives.empty())
        atomic_write_file(json_path(command, command.primitives, input, "primitives"),
                          summary_primitives_json(result.summary));
      if (!command.objects.empty())
        atomic_write_file(json_path(command, command.objects, input, "objects"),
                          summary_objects_json(result.summary));
    } catch (const std::exception& e) {
      std::fprintf(stderr, "primlabel: %s\n", e.what());
      if (exit_code == kExitOk) exit_code = kExitFile;
      continue;
    }
    // Even with --quiet: labels from a model of another sensor look plausible and are not.
    if (!result.summary.domain_warning().empty())
      std::fprintf(stderr, "primlabel: warning: %s: %s\n", input.c_str(),
                   result.summary.domain_warning().c_str());
    if (result.summary.points_isolated() > 0 && !command.quiet)
      std::fprintf(stderr,
                   "primlabel: %s: %llu points have no neighbour within the model's radii "
                   "(far outliers or lonely returns): labeled unknown\n",
                   input.c_str(),
                   static_cast<unsigned long long>(result.summary.points_isolated()));
    if (had_labels && !command.quiet)
      std::fprintf(stderr,
                   "primlabel: %s: its own label field is kept as '%s'; 'label' now holds "
                   "the predicted classes\n",
                   input.c_str(), kInputLabelField);
    if (!command.quiet)
      std::fprintf(stderr, "%s: %zu points -> %s in %.2f s, model %s %s %s (%s)\n", input.c_str(),
                   result.size(), out.c_str(), seconds, result.summary.model().c_str(),
                   result.summary.model_version().c_str(),
                   model_choice_text(result.summary).c_str(), histogram.c_str());
  }
  return exit_code;
}

}  // namespace primlabel::client::tools
