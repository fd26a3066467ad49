#include "primlabel/ops/server_config.hpp"

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <thread>

#include "config_file.hpp"
#include "primlabel/build_version.hpp"

namespace primlabel::ops {

namespace {

std::string read_token_file(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw ConfigError{"cannot read the token file '" + path + "'", kExitUsage};
  std::stringstream text;
  text << in.rdbuf();
  std::string token = text.str();
  while (!token.empty() && (token.back() == '\n' || token.back() == '\r' || token.back() == ' '))
    token.pop_back();
  if (token.empty()) throw ConfigError{"the token file '" + path + "' is empty", kExitUsage};
  return token;
}

int hardware_threads() { return std::max(1u, std::thread::hardware_concurrency()); }

// What a flag gives before it is checked and put into the ServerConfig.
struct RawSettings {
  std::string config_file;  // read before parsing, see with_config_file
  std::vector<std::string> pins;
  std::string token_file;
};

// Where the models are, where the server listens, which model and version a request gets.
void add_service_options(CLI::App& app, ServerConfig& config, RawSettings& raw) {
  app.add_option("--config", raw.config_file,
                 "config file of `key = value` lines, keys named like the flags; "
                 "flags and environment variables win over it")
      ->envname("PRIMLABEL_CONFIG");

  app.add_option("--models", config.models_dir, "model repository: DIR/<model>/<version>/*.plm")
      ->envname("PRIMLABEL_MODELS")
      ->required();
  app.add_option("--listen", config.listen, "gRPC address HOST:PORT (port 0: any free port)")
      ->envname("PRIMLABEL_LISTEN")
      ->capture_default_str();
  app.add_option("--metrics-listen", config.metrics_listen,
                 "Prometheus /metrics address HOST:PORT; empty turns it off")
      ->envname("PRIMLABEL_METRICS_LISTEN")
      ->capture_default_str();
  app.add_option("--default-model", config.default_model,
                 "model for requests that name none and whose cloud no model's domain decides "
                 "(default: the repository's default_model file, else the only model)")
      ->envname("PRIMLABEL_DEFAULT_MODEL");
  app.add_option("--pin", raw.pins, "MODEL=VERSION: serve this version by default, not the latest")
      ->envname("PRIMLABEL_PIN");
  app.add_option("--reload-seconds", config.reload_seconds,
                 "poll the model repository this often (0: only on ReloadModels)")
      ->envname("PRIMLABEL_RELOAD_SECONDS")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  app.add_option("--unload-after-missing-polls", config.unload_after_missing_polls,
                 "a loaded version whose directory is missing keeps serving until it has been "
                 "missing at this many scans in a row (1: at once)")
      ->envname("PRIMLABEL_UNLOAD_AFTER_MISSING_POLLS")
      ->check(CLI::Range(1u, 1000000u))
      ->capture_default_str();
}

// How much the server takes on: jobs, threads, request and message sizes, the drain.
void add_capacity_options(CLI::App& app, ServerConfig& config) {
  app.add_option("--workers", config.workers,
                 "concurrent labeling jobs (0: half the cores, at least 1)")
      ->envname("PRIMLABEL_WORKERS")
      ->check(CLI::NonNegativeNumber);
  app.add_option("--queue", config.queue, "requests admitted beyond the workers")
      ->envname("PRIMLABEL_QUEUE")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  app.add_option("--threads-per-job", config.threads_per_job,
                 "OpenMP threads per job (0: cores / workers)")
      ->envname("PRIMLABEL_THREADS_PER_JOB")
      ->check(CLI::NonNegativeNumber);
  app.add_option("--max-points", config.max_points, "points per request")
      ->envname("PRIMLABEL_MAX_POINTS")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  app.add_option("--max-request-bytes", config.max_request_bytes,
                 "point bytes per request (xyz, normals, intensity)")
      ->envname("PRIMLABEL_MAX_REQUEST_BYTES")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  app.add_option("--max-message-bytes", config.max_message_bytes,
                 "largest gRPC message received or sent")
      ->envname("PRIMLABEL_MAX_MESSAGE_BYTES")
      ->check(CLI::Range(64 << 10, 1 << 30))
      ->capture_default_str();
  app.add_option("--response-chunk-bytes", config.response_chunk_bytes,
                 "target size of one streamed label chunk")
      ->envname("PRIMLABEL_RESPONSE_CHUNK_BYTES")
      ->check(CLI::Range(std::uint64_t(1024), std::uint64_t(1) << 30))
      ->capture_default_str();
  app.add_option("--drain-seconds", config.drain_seconds,
                 "on SIGTERM/SIGINT, how long in-flight requests may finish")
      ->envname("PRIMLABEL_DRAIN_SECONDS")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
}

// Streams against slow or hostile clients.
void add_stream_limit_options(CLI::App& app, ServerConfig& config) {
  app.add_option("--max-receiving-streams", config.max_receiving_streams,
                 "Label streams receiving points at once (apart from --workers + --queue)")
      ->envname("PRIMLABEL_MAX_RECEIVING_STREAMS")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  app.add_option("--stream-idle-seconds", config.stream_idle_seconds,
                 "a receiving stream without a message for this long is finished")
      ->envname("PRIMLABEL_STREAM_IDLE_SECONDS")
      ->check(CLI::Range(0.01, 86400.0))
      ->capture_default_str();
  app.add_option("--min-receive-bytes-per-second", config.min_receive_bytes_per_second,
                 "a receiving stream slower than this over a window is finished (0: no minimum)")
      ->envname("PRIMLABEL_MIN_RECEIVE_BYTES_PER_SECOND")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  app.add_option("--receive-rate-window-seconds", config.receive_rate_window_seconds,
                 "the window of --min-receive-bytes-per-second, also its grace period")
      ->envname("PRIMLABEL_RECEIVE_RATE_WINDOW_SECONDS")
      ->check(CLI::Range(0.01, 86400.0))
      ->capture_default_str();
  app.add_option("--send-timeout-seconds", config.send_timeout_seconds,
                 "a client that takes no answer message for this long is cancelled")
      ->envname("PRIMLABEL_SEND_TIMEOUT_SECONDS")
      ->check(CLI::Range(0.01, 86400.0))
      ->capture_default_str();
  app.add_option("--max-request-seconds", config.max_request_seconds,
                 "the deadline of a labeling request whose client sets none (or a later one)")
      ->envname("PRIMLABEL_MAX_REQUEST_SECONDS")
      ->check(CLI::Range(0.01, 1e7))
      ->capture_default_str();
}

// TLS, the bearer token and who may administer models.
void add_security_options(CLI::App& app, ServerConfig& config, RawSettings& raw) {
  app.add_option("--tls-cert", config.tls_cert, "server certificate chain (PEM): enables TLS")
      ->envname("PRIMLABEL_TLS_CERT")
      ->check(CLI::ExistingFile);
  app.add_option("--tls-key", config.tls_key, "server private key (PEM)")
      ->envname("PRIMLABEL_TLS_KEY")
      ->check(CLI::ExistingFile);
  app.add_option("--tls-client-ca", config.tls_client_ca,
                 "CA bundle (PEM): require and verify client certificates (mutual TLS)")
      ->envname("PRIMLABEL_TLS_CLIENT_CA")
      ->check(CLI::ExistingFile);
  app.add_option("--token-file", raw.token_file,
                 "file holding the bearer token required on admin RPCs "
                 "(or the token itself in PRIMLABEL_TOKEN)")
      ->envname("PRIMLABEL_TOKEN_FILE");
  app.add_flag("--token-for-all", config.token_for_all,
               "require the token on every RPC, not only on admin ones")
      ->envname("PRIMLABEL_TOKEN_FOR_ALL");
  app.add_flag("--insecure-admin", config.insecure_admin,
               "allow admin RPCs (load, unload, reload models) without a token; without a token "
               "and without this flag they are refused")
      ->envname("PRIMLABEL_INSECURE_ADMIN");
}

// Parses the command line below the config file; --help and --version, and every bad flag, come
// back as a ConfigError carrying the text CLI11 would print.
void parse_command_line(CLI::App& app, int argc, const char* const* argv) {
  try {
    const std::vector<std::string> args = with_config_file(app, argc, argv);
    std::vector<const char*> pointers;
    for (const std::string& arg : args) pointers.push_back(arg.c_str());
    app.parse(int(pointers.size()), pointers.data());
  } catch (const CLI::ParseError& e) {
    std::ostringstream out, err;
    app.exit(e, out, err);
    throw ConfigError{e.get_exit_code() == 0 ? out.str() : err.str(),
                      e.get_exit_code() == 0 ? kExitOk : kExitUsage};
  }
}

// MODEL=VERSION pins into config.pins.
void apply_pins(const std::vector<std::string>& pins, ServerConfig& config) {
  for (const std::string& pin : pins) {
    const auto eq = pin.find('=');
    if (eq == std::string::npos || eq == 0 || eq + 1 == pin.size())
      throw ConfigError{"--pin expects MODEL=VERSION, got '" + pin + "'", kExitUsage};
    config.pins[pin.substr(0, eq)] = pin.substr(eq + 1);
  }
}

// TLS files that go together, and the token from its file or the environment.
void check_security(const RawSettings& raw, ServerConfig& config) {
  if (config.tls_cert.empty() != config.tls_key.empty())
    throw ConfigError{"--tls-cert and --tls-key go together", kExitUsage};
  if (!config.tls_client_ca.empty() && config.tls_cert.empty())
    throw ConfigError{"--tls-client-ca needs --tls-cert and --tls-key", kExitUsage};
  if (!raw.token_file.empty()) {
    config.token = read_token_file(raw.token_file);
  } else if (const char* token = std::getenv("PRIMLABEL_TOKEN"); token && *token) {
    config.token = token;
  }
  if (config.token_for_all && config.token.empty())
    throw ConfigError{"--token-for-all needs a token (--token-file or PRIMLABEL_TOKEN)",
                      kExitUsage};
}

}  // namespace

int effective_workers(const ServerConfig& config) {
  return config.workers > 0 ? config.workers : std::max(1, hardware_threads() / 2);
}

int effective_threads_per_job(const ServerConfig& config) {
  if (config.threads_per_job > 0) return config.threads_per_job;
  return std::max(1, hardware_threads() / effective_workers(config));
}

ServerConfig parse_server_config(int argc, const char* const* argv) {
  ServerConfig config;
  CLI::App app{"primlabel-server: the gRPC point labeling service."};
  // Every option with a default shows it in --help ("[0.025]").
  app.option_defaults()->always_capture_default();
  app.set_version_flag("--version", primlabel::version_line("primlabel-server"));
  app.name("primlabel-server");
  RawSettings raw;
  add_service_options(app, config, raw);
  add_capacity_options(app, config);
  add_stream_limit_options(app, config);
  add_security_options(app, config, raw);
  app.add_option("--log-level", config.log_level, "debug, info, warn or error")
      ->envname("PRIMLABEL_LOG_LEVEL")
      ->check(CLI::IsMember({"debug", "info", "warn", "error"}))
      ->capture_default_str();

  parse_command_line(app, argc, argv);
  apply_pins(raw.pins, config);
  check_security(raw, config);
  return config;
}

}  // namespace primlabel::ops
