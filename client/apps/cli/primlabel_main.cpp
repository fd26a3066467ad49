// primlabel: talk to a primlabel server from the shell.
//
//   primlabel --server HOST:PORT health
//   primlabel --server HOST:PORT models
//   primlabel --server HOST:PORT info MODEL
//   primlabel --server HOST:PORT label scan.pcd [-o scan_labeled.pcd] [--png] [--descriptors]

#include <CLI/CLI.hpp>
#include <cstdio>
#include <exception>
#include <memory>
#include <string>
#include <vector>

#include "commands.hpp"
#include "common/client_flags.hpp"
#include "common/units_flag.hpp"
#include "primlabel/build_version.hpp"
#include "primlabel/cli/subcommands.hpp"
#include "status_exit_codes.hpp"

using namespace primlabel::client;
using namespace primlabel::client::tools;

int main(int argc, char** argv) {
  CLI::App app{"primlabel: label point clouds with a primlabel server, list its models, check it.",
               "primlabel"};
  // Every option with a default shows it in --help ("[0.025]").
  app.option_defaults()->always_capture_default();
  app.set_version_flag("--version", primlabel::version_line("primlabel"));
  app.footer(kExitCodesHelp);
  app.require_subcommand(1);
  ConnectionFlags connection;
  connection.add_to(app);
  bool quiet = false;
  app.add_flag("-q,--quiet", quiet, "No progress on stderr");

  std::string health_service;
  CLI::App* health = app.add_subcommand("health", "Is the server serving? (grpc.health.v1)");
  health->add_option("--service", health_service, "One service, e.g. primlabel.v1.Labeler");

  CLI::App* models = app.add_subcommand("models", "The models the server serves");

  std::string info_model, info_version;
  CLI::App* info = app.add_subcommand("info", "One model's classes, features and scores");
  info->add_option("MODEL", info_model, "Model name")->required();
  info->add_option("--model-version", info_version, "Version (default: the latest loaded)");

  LabelCommand label_args;
  CLI::App* label = app.add_subcommand("label", "Label PCD/PLY files and write labeled clouds");
  label
      ->add_option("FILE", label_args.inputs,
                   "Input .pcd or .ply files, or folders: every .pcd and .ply directly in one, "
                   "by name (not subfolders, hidden files or *_labeled.* outputs)")
      ->required();
  label->add_option("-o,--output", label_args.output,
                    "Output file (one input) or directory (several, or a folder); default: "
                    "<input>_labeled.pcd beside the input");
  label->add_flag("--png", label_args.png,
                  "Also write a PNG picture beside each output (with --tabletop: the table and "
                  "each object's box and id drawn over the points)");
  label
      ->add_option("--view", label_args.view,
                   "The PNG's view: auto (sensor for an organised camera frame, else oblique), "
                   "sensor (from the VIEWPOINT), top or oblique")
      ->check(CLI::IsMember({"auto", "sensor", "top", "oblique"}));
  label->add_flag("--descriptors", label_args.descriptors, "Add the FPFH descriptors (fpfh)");
  label->add_flag(
      "--probabilities", label_args.probabilities,
      "Add the per-class probabilities (one field per class, prob_<class>, e.g. prob_plane)");
  label->add_option("--primitives", label_args.primitives,
                    "Also fit primitive instances and write them as JSON (as primlabel-eval "
                    "--primitives): a file (one input) or directory (several, "
                    "<input>_primitives.json)");
  label->add_option("--objects", label_args.objects,
                    "With --tabletop: also write the table and its objects as JSON (table "
                    "plane, hull; per object id, points, centroid, bounds, height, primitive "
                    "ids) to a file (one input) or directory (several, <input>_objects.json), "
                    "and each point's object id as the field `object` (0 table, k object, -1 "
                    "neither)");
  label->add_option("--model", label_args.options.model, "Model (default: the server's)");
  label->add_option("--model-version", label_args.options.model_version, "Model version");
  label->add_flag("--tabletop", label_args.options.tabletop_only,
                  "Label only the table and the objects on it");
  label->add_option("--voxel-size", label_args.options.voxel_size, "Downsample first (m)");
  add_units_flag(*label, label_args.options.metres_per_unit);
  label->add_flag("--every-point", label_args.options.every_point,
                  "Describe and infer every point: no plane cascade, the model's exact labels "
                  "everywhere (slower)");
  label->add_option("--chunk-points", label_args.options.chunk_points, "Points per message")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  label->add_flag("--unary", label_args.unary, "One message (LabelCloud) instead of a stream");

  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForVersion& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    // "primlabel lable x.pcd": the word taken for a command, and the nearest command.
    const std::string unknown = primlabel::cli::unknown_command_message(app);
    std::fprintf(stderr, "primlabel: %s (see --help)\n",
                 unknown.empty() ? e.what() : unknown.c_str());
    return kExitUsage;
  }

  ClientOptions options;
  try {
    options = connection.options();
  } catch (const std::exception& e) {
    std::fprintf(stderr, "primlabel: %s\n", e.what());
    return kExitFile;
  }
  std::unique_ptr<Client> client;
  try {
    client = std::make_unique<Client>(options);
  } catch (const ClientError& e) {  // unreadable TLS files
    std::fprintf(stderr, "primlabel: %s\n", e.what());
    return kExitFile;
  }
  try {
    if (*health) return run_health(*client, health_service);
    if (*models) return run_models(*client);
    if (*info) return run_info(*client, info_model, info_version);
    label_args.quiet = quiet;
    return run_label(*client, label_args);
  } catch (const ClientError& e) {
    // The client's own deadline is the usual cause for a large scan or a busy server.
    char hint[160] = "";
    if (e.code() == grpc::StatusCode::DEADLINE_EXCEEDED)
      std::snprintf(hint, sizeof hint,
                    " (--deadline is %g s, retries included; raise it for large scans or a busy "
                    "server)",
                    connection.deadline_s);
    std::fprintf(stderr, "primlabel: %s%s\n", e.what(), hint);
    return exit_code_for(e.code());
  }
}
