// primlabel-upload: the robot computer's scan uploader. Scans come from files, a watched
// directory or a framed stream on stdin; each is kept in a durable spool until its labels are in
// the output directory, so crashes, server restarts and network outages lose nothing.

#include <signal.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <atomic>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <sstream>
#include <thread>

#include "common/client_flags.hpp"
#include "common/units_flag.hpp"
#include "directory_watch.hpp"
#include "framing.hpp"
#include "primlabel/build_version.hpp"
#include "primlabel/cli/exit_codes.hpp"
#include "primlabel/geometry/cloud_io.hpp"
#include "unreadable_files.hpp"
#include "uploader.hpp"

using namespace primlabel::client;
using namespace primlabel::client::upload;
namespace fs = std::filesystem;

namespace {

// The shared scheme (exit_codes.hpp), then the uploader's own codes.
using primlabel::kExitOk;
using primlabel::kExitUsage;
constexpr int kExitInput = primlabel::kExitFailure;  // an input, the spool or the output failed
constexpr int kExitTimedOut = 3;
constexpr int kExitRefused = 4;
constexpr int kExitNotAccepted = 5;  // full spool, full disk or a failed spool write
constexpr int kExitStopped = 6;      // files/stdin: a signal ended the run before every scan

constexpr const char* kFooter =
    "Each scan is acknowledged on stdout as '<state> <id> <source> -> <output>' (state: "
    "accepted, queued = already in the spool, labeled = its output exists, rejected = the spool "
    "could not take it; id = content hash) and labeled into OUT/<file stem>.<key>.pcd, the key "
    "covering the content and the labeling options (--model, --probabilities, ...): the same "
    "scan with other options is labeled anew. Scans already spooled are uploaded "
    "before new input is read. Exit codes (the highest that applies): 0 every scan labeled (or "
    "--watch stopped by a signal), 1 an input could not be read, 2 usage, 3 --timeout passed "
    "with scans still spooled, 4 scans were moved to SPOOL/failed (refused by the server for "
    "good, e.g. a --model it does not serve, or corrupt in the spool), 5 scans were not accepted: "
    "the spool was full, its disk "
    "short of --spool-min-free-mb, or the write failed (one line on stderr names the file and "
    "the reason), 6 a signal stopped a run of files or --stdin before every scan was labeled "
    "(those spooled resume on the next run; one line on stderr says how many).";

std::atomic<bool> g_stop{false};
void on_signal(int) { g_stop = true; }

void install_signal_handlers() {
  struct sigaction action {};
  action.sa_handler = on_signal;
  sigemptyset(&action.sa_mask);
  sigaction(SIGINT, &action, nullptr);
  sigaction(SIGTERM, &action, nullptr);
}

std::string read_file(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error(path.string() + ": cannot open");
  std::stringstream bytes;
  bytes << in.rdbuf();
  if (!in) throw std::runtime_error(path.string() + ": cannot read");
  return bytes.str();
}

struct Intake {
  Uploader& uploader;
  bool remove_source = false;
  bool quiet = false;
  int exit_code = kExitOk;
  std::size_t files_not_read = 0;  // input files a signal left unread

  void raise(int code) { exit_code = std::max(exit_code, code); }

  // Submits one scan and acknowledges it on stdout; false when the spool could not take it.
  bool submit(std::string_view bytes, const std::string& ext, const std::string& source,
              const std::string& source_name = {}) {
    std::string id, reason;
    const auto result = uploader.submit(bytes, ext, &id, &reason, source, source_name);
    static const char* const kState[] = {"accepted", "queued", "labeled", "rejected", "rejected"};
    const bool taken =
        result != Uploader::Submitted::kSpoolFull && result != Uploader::Submitted::kWriteFailed;
    std::printf("%s %s %s%s\n", kState[static_cast<int>(result)], id.c_str(), source.c_str(),
                taken ? (" -> " + uploader.output_path(id, source_name).string()).c_str() : "");
    std::fflush(stdout);
    if (!taken) {
      std::fprintf(stderr, "primlabel-upload: %s: %s\n", source.c_str(), reason.c_str());
      return false;
    }
    return true;
  }

  // A file input; false when the spool could not take it (the file is left alone). When
  // `unreadable` is given, a file that cannot be read or parsed is not an error yet: the reason
  // goes there and the caller decides (a watched file may still be being written).
  bool submit_file(const fs::path& path, std::string* unreadable = nullptr) {
    std::string bytes;
    try {
      bytes = read_file(path);
    } catch (const std::exception& e) {
      if (unreadable) {
        *unreadable = e.what();
        return true;
      }
      std::fprintf(stderr, "primlabel-upload: %s\n", e.what());
      raise(kExitInput);
      return true;
    }
    std::string ext = path.extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(), ::tolower);
    if (ext != ".pcd" && ext != ".ply") {
      std::fprintf(stderr, "primlabel-upload: %s: not a .pcd or .ply file\n", path.c_str());
      raise(kExitInput);
      return true;
    }
    // A file that does not parse is the caller's input error (exit 1), found here before it is
    // spooled, not a scan the server refused (exit 4) once the upload parses it.
    // So is a cloud with no finite point (a covered lens): nothing in it can be labeled.
    std::string why;
    try {
      const primlabel::PointCloud cloud = primlabel::read_cloud(path.string());
      if (primlabel::count_finite(cloud) == 0)
        why = "no point has finite coordinates (" + std::to_string(cloud.size()) +
              " points): nothing to label";
    } catch (const std::exception& e) {
      why = e.what();
    }
    if (!why.empty()) {
      if (unreadable) {
        *unreadable = why;
        return true;
      }
      std::fprintf(stderr, "primlabel-upload: %s: not spooled, unreadable: %s\n", path.c_str(),
                   why.c_str());
      raise(kExitInput);
      return true;
    }
    if (!submit(bytes, ext, path.string(), path.stem().string())) return false;
    if (remove_source) {
      std::error_code ec;
      fs::remove(path, ec);
    }
    return true;
  }

  void from_files(const std::vector<std::string>& files) {
    for (std::size_t i = 0; i < files.size(); ++i) {
      if (g_stop) {
        files_not_read = files.size() - i;
        return;
      }
      if (!submit_file(files[i])) raise(kExitNotAccepted);
    }
  }

  void from_stdin(std::uint64_t max_frame_bytes) {
    std::ios::sync_with_stdio(false);
    std::cin.exceptions(std::ios::goodbit);
    for (std::uint64_t n = 0; !g_stop; ++n) {
      std::optional<std::string> scan;
      try {
        scan = read_frame(std::cin, max_frame_bytes);
      } catch (const FrameError& e) {
        if (!g_stop) {
          std::fprintf(stderr, "primlabel-upload: stdin frame %llu: %s\n",
                       static_cast<unsigned long long>(n), e.what());
          raise(kExitInput);
        }
        return;
      }
      if (!scan) return;
      if (!submit(*scan, scan_extension(*scan), "stdin#" + std::to_string(n)))
        raise(kExitNotAccepted);
    }
  }

  // Until a signal: files that do not fit wait in the watched directory and are retried. A file
  // that cannot be read or parsed may be one still being written (closed between writes): it is
  // retried whenever it changes, and an error only if it is still unreadable when the run ends.
  void watch(const fs::path& dir) {
    DirectoryWatch watch(dir);
    std::vector<fs::path> deferred;
    UnreadableFiles unreadable;
    auto offer = [&](const std::vector<fs::path>& files) {
      for (const auto& f : files) {
        if (!fs::exists(f)) continue;
        std::string reason;
        if (!submit_file(f, &reason)) deferred.push_back(f);
        if (reason.empty()) {
          unreadable.forget(f);
        } else if (unreadable.note(f, reason) && !quiet) {
          std::fprintf(stderr,
                       "primlabel-upload: %s: unreadable for now, retried when it changes: %s\n",
                       f.c_str(), reason.c_str());
        }
      }
    };
    offer(watch.existing());
    while (!g_stop) {
      offer(watch.next(std::chrono::milliseconds(500)));
      offer(unreadable.changed());
      if (!deferred.empty() && uploader.queued() == 0) {
        std::vector<fs::path> again;
        again.swap(deferred);
        std::sort(again.begin(), again.end());
        again.erase(std::unique(again.begin(), again.end()), again.end());
        offer(again);
      }
    }
    offer(unreadable.changed());  // one last look: a writer may have finished meanwhile
    for (const auto& [path, reason] : unreadable.remaining()) {
      std::fprintf(stderr, "primlabel-upload: %s: not spooled, unreadable: %s\n", path.c_str(),
                   reason.c_str());
      raise(kExitInput);
    }
  }
};

std::string summary_line(const UploadCounters& c, std::size_t left) {
  char line[400];
  std::snprintf(
      line, sizeof line,
      "summary: accepted %llu new, %llu already spooled, %llu already labeled; uploaded "
      "%llu (%llu points), failed %llu, corrupt %llu, rejected %llu (spool full), %llu (spool "
      "write failed), retries %llu, left in spool %zu",
      static_cast<unsigned long long>(c.accepted),
      static_cast<unsigned long long>(c.already_queued),
      static_cast<unsigned long long>(c.already_labeled),
      static_cast<unsigned long long>(c.uploaded), static_cast<unsigned long long>(c.points),
      static_cast<unsigned long long>(c.failed), static_cast<unsigned long long>(c.corrupt),
      static_cast<unsigned long long>(c.rejected_full),
      static_cast<unsigned long long>(c.rejected_write), static_cast<unsigned long long>(c.retries),
      left);
  return line;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"primlabel-upload: upload scans to a primlabel server through a durable spool.",
               "primlabel-upload"};
  // Every option with a default shows it in --help ("[0.025]").
  app.option_defaults()->always_capture_default();
  app.set_version_flag("--version", primlabel::version_line("primlabel-upload"));
  app.footer(kFooter);
  tools::ConnectionFlags connection;
  connection.retries = 2;  // the uploader's own backoff takes over after these
  connection.add_to(app);
  UploaderOptions options;
  std::string spool, out, watch_dir;
  std::vector<std::string> files, frame_files;
  bool from_stdin = false, quiet = false, remove_source = false;
  double spool_mb = 1024, spool_min_free_mb = 16, status_s = 10, timeout_s = 0, backoff_max_s = 30;
  std::uint64_t max_scans = 10'000;
  app.add_option("FILE", files, "Scan files (.pcd / .ply) to upload");
  app.add_option("--spool", spool, "Spool directory (created)");
  app.add_option("-o,--out", out, "Output directory for labeled scans (created)");
  app.add_option("--watch", watch_dir, "Upload scans appearing in this directory until a signal");
  app.add_flag("--stdin", from_stdin, "Read framed scans from stdin (see --frame)");
  app.add_option("--frame", frame_files,
                 "Write these files as a framed stream to stdout and exit (for --stdin)");
  app.add_flag("--remove-source", remove_source, "Delete input files once spooled");
  app.add_option("--spool-max-mb", spool_mb, "Spool size limit (MB)")->capture_default_str();
  app.add_option("--spool-max-scans", max_scans, "Spool scan count limit")->capture_default_str();
  app.add_option("--spool-min-free-mb", spool_min_free_mb,
                 "Free space (MB) the spool's filesystem must keep after a new scan")
      ->capture_default_str()
      ->check(CLI::NonNegativeNumber);
  app.add_option("--workers", options.workers, "Uploads in parallel")->capture_default_str();
  app.add_option("--status-interval", status_s, "Seconds between status lines (0 = none)")
      ->capture_default_str();
  app.add_option("--timeout", timeout_s,
                 "Give up waiting for the server after S seconds (0 = never); scans stay spooled")
      ->capture_default_str();
  app.add_option("--backoff-max", backoff_max_s, "Longest pause while the server is away (s)")
      ->capture_default_str();
  app.add_option("--model", options.label.model, "Model (default: the server's)");
  app.add_option("--model-version", options.label.model_version, "Model version");
  app.add_flag("--descriptors", options.label.descriptors, "Keep the FPFH descriptors");
  app.add_flag("--probabilities", options.label.probabilities, "Keep the class probabilities");
  app.add_flag("--tabletop", options.label.tabletop_only, "Label only the table top");
  tools::add_units_flag(app, options.label.metres_per_unit);
  app.add_flag("--every-point", options.label.every_point,
               "Describe and infer every point: no plane cascade (slower)");
  app.add_flag("-q,--quiet", quiet, "Only errors and the summary on stderr");
  try {
    app.parse(argc, argv);
    if (frame_files.empty() && (spool.empty() || out.empty()))
      throw CLI::ValidationError("--spool and --out are required");
    if (!watch_dir.empty() && from_stdin)
      throw CLI::ValidationError("--watch and --stdin exclude each other");
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForVersion& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    std::fprintf(stderr, "primlabel-upload: %s (see --help)\n", e.what());
    return kExitUsage;
  }

  if (!frame_files.empty()) {
    for (const auto& f : frame_files) {
      try {
        const std::string frame = encode_frame(read_file(f));
        std::fwrite(frame.data(), 1, frame.size(), stdout);
      } catch (const std::exception& e) {
        std::fprintf(stderr, "primlabel-upload: %s\n", e.what());
        return kExitInput;
      }
    }
    return kExitOk;
  }

  install_signal_handlers();
  options.spool_dir = spool;
  options.output_dir = out;
  options.limits.max_bytes = static_cast<std::uint64_t>(spool_mb * 1e6);
  options.limits.max_scans = max_scans;
  options.limits.min_free_bytes = static_cast<std::uint64_t>(spool_min_free_mb * 1e6);
  options.backoff.max = std::chrono::milliseconds(static_cast<long long>(backoff_max_s * 1000));
  std::unique_ptr<Client> client;
  std::unique_ptr<Uploader> uploader;
  try {
    client = std::make_unique<Client>(connection.options());
    uploader = std::make_unique<Uploader>(*client, options);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "primlabel-upload: %s\n", e.what());
    return kExitInput;
  }
  for (const CorruptEntry& entry : uploader->corrupt_entries())
    std::fprintf(stderr, "primlabel-upload: %s: %s; %s\n", entry.path.c_str(), entry.reason.c_str(),
                 entry.moved ? ("moved to " + (fs::path(spool) / "failed").string()).c_str()
                             : "not uploaded (moving it to failed/ failed too)");
  const std::size_t resuming = uploader->queued();
  if (!quiet && resuming > 0)
    std::fprintf(stderr, "primlabel-upload: resuming %zu scans from the spool\n", resuming);
  uploader->start();
  auto deadline = [&]() -> std::optional<std::chrono::steady_clock::time_point> {
    if (timeout_s <= 0) return std::nullopt;
    return std::chrono::steady_clock::now() +
           std::chrono::milliseconds(static_cast<long long>(timeout_s * 1000));
  };

  // The operator's status line, on its own thread so a blocked intake does not silence it.
  std::atomic<bool> status_done{false};
  std::thread status([&] {
    if (quiet || status_s <= 0) return;
    auto next = std::chrono::steady_clock::now();
    while (!status_done) {
      next += std::chrono::milliseconds(static_cast<long long>(status_s * 1000));
      while (!status_done && std::chrono::steady_clock::now() < next)
        std::this_thread::sleep_for(std::chrono::milliseconds(50));
      if (!status_done)
        std::fprintf(stderr, "primlabel-upload: status: %s\n", uploader->status_line().c_str());
    }
  });

  Intake intake{*uploader, remove_source, quiet};
  // What is already spooled goes first: new input could fill the disk and strand it.
  if (resuming > 0 && !uploader->wait_idle(g_stop, deadline()) && !g_stop)
    std::fprintf(stderr,
                 "primlabel-upload: --timeout passed with %zu scans still spooled from the last "
                 "run; taking new input anyway\n",
                 uploader->queued());
  try {
    if (!g_stop) {
      intake.from_files(files);
      if (!watch_dir.empty()) {
        intake.watch(watch_dir);
      } else if (from_stdin) {
        intake.from_stdin(options.limits.max_bytes);
      }
    }
  } catch (const std::exception& e) {  // e.g. the watched directory vanished
    std::fprintf(stderr, "primlabel-upload: %s\n", e.what());
    intake.raise(kExitInput);
  }
  // Files and stdin: wait for the uploads (a watch ends only by signal, so it does not wait).
  if (watch_dir.empty() && !uploader->wait_idle(g_stop, deadline()) && !g_stop)
    intake.raise(kExitTimedOut);
  uploader->stop();
  status_done = true;
  status.join();
  const UploadCounters counters = uploader->counters();
  if (counters.failed > 0 || counters.corrupt > 0) intake.raise(kExitRefused);
  // Files and stdin promise every scan labeled on exit 0; a watch ends by signal anyway.
  if (watch_dir.empty() && g_stop && (uploader->queued() > 0 || intake.files_not_read > 0)) {
    std::string unread;
    if (intake.files_not_read > 0)
      unread = "; " + std::to_string(intake.files_not_read) + " input files were not read";
    std::fprintf(stderr,
                 "primlabel-upload: stopped by signal with %zu scans still spooled; they resume "
                 "on the next run%s\n",
                 uploader->queued(), unread.c_str());
    intake.raise(kExitStopped);
  }
  std::fprintf(stderr, "primlabel-upload: %s\n",
               summary_line(counters, uploader->queued()).c_str());
  return intake.exit_code;
}
