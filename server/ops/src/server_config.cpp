#include "primlabel/ops/server_config.hpp"

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <thread>

#include "primlabel/build_version.hpp"

namespace primlabel::server {

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

std::string trim(const std::string& text) {
  const auto first = text.find_first_not_of(" \t\r");
  if (first == std::string::npos) return {};
  const auto last = text.find_last_not_of(" \t\r");
  return text.substr(first, last - first + 1);
}

bool given_on_command_line(const std::vector<std::string>& args, const std::string& flag) {
  for (const std::string& arg : args)
    if (arg == flag || arg.rfind(flag + "=", 0) == 0) return true;
  return false;
}

// The command line with the config file's settings put in front of it, leaving out every
// setting that a flag or an environment variable gives: flags > environment > file.
std::vector<std::string> with_config_file(CLI::App& app, int argc, const char* const* argv) {
  std::vector<std::string> args(argv + 1, argv + argc);
  std::string path;
  for (std::size_t i = 0; i < args.size(); ++i) {
    if (args[i] == "--config" && i + 1 < args.size()) path = args[i + 1];
    if (args[i].rfind("--config=", 0) == 0) path = args[i].substr(9);
  }
  if (const char* env = std::getenv("PRIMLABEL_CONFIG"); path.empty() && env) path = env;
  std::vector<std::string> out{argv[0]};
  if (!path.empty()) {
    std::ifstream in(path);
    if (!in) throw ConfigError{"cannot read the config file '" + path + "'", kExitUsage};
    std::string line;
    for (int number = 1; std::getline(in, line); ++number) {
      line = trim(line);
      if (line.empty() || line[0] == '#' || line[0] == ';') continue;
      const auto eq = line.find('=');
      const std::string where = path + ":" + std::to_string(number);
      if (eq == std::string::npos)
        throw ConfigError{where + ": expected `key = value`", kExitUsage};
      std::string key = trim(line.substr(0, eq)), value = trim(line.substr(eq + 1));
      if (key.rfind("--", 0) == 0) key = key.substr(2);
      if (value.size() >= 2 && (value.front() == '"' || value.front() == '\'') &&
          value.back() == value.front())
        value = value.substr(1, value.size() - 2);
      const std::string flag = "--" + key;
      const CLI::Option* option = app.get_option_no_throw(flag);
      if (!option || key == "config" || key == "help")
        throw ConfigError{where + ": unknown setting '" + key + "'", kExitUsage};
      const std::string env = option->get_envname();
      if (given_on_command_line(args, flag) || (!env.empty() && std::getenv(env.c_str()))) continue;
      out.push_back(flag + "=" + value);
    }
  }
  out.insert(out.end(), args.begin(), args.end());
  return out;
}

int hardware_threads() { return std::max(1u, std::thread::hardware_concurrency()); }

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
  std::string config_file;  // read before parsing, see with_config_file
  app.add_option("--config", config_file,
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
  std::vector<std::string> pins;
  app.add_option("--pin", pins, "MODEL=VERSION: serve this version by default, not the latest")
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
  // Streams against slow or hostile clients.
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
  std::string token_file;
  app.add_option("--token-file", token_file,
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
  app.add_option("--log-level", config.log_level, "debug, info, warn or error")
      ->envname("PRIMLABEL_LOG_LEVEL")
      ->check(CLI::IsMember({"debug", "info", "warn", "error"}))
      ->capture_default_str();

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

  for (const std::string& pin : pins) {
    const auto eq = pin.find('=');
    if (eq == std::string::npos || eq == 0 || eq + 1 == pin.size())
      throw ConfigError{"--pin expects MODEL=VERSION, got '" + pin + "'", kExitUsage};
    config.pins[pin.substr(0, eq)] = pin.substr(eq + 1);
  }
  if (config.tls_cert.empty() != config.tls_key.empty())
    throw ConfigError{"--tls-cert and --tls-key go together", kExitUsage};
  if (!config.tls_client_ca.empty() && config.tls_cert.empty())
    throw ConfigError{"--tls-client-ca needs --tls-cert and --tls-key", kExitUsage};
  if (!token_file.empty()) {
    config.token = read_token_file(token_file);
  } else if (const char* token = std::getenv("PRIMLABEL_TOKEN"); token && *token) {
    config.token = token;
  }
  if (config.token_for_all && config.token.empty())
    throw ConfigError{"--token-for-all needs a token (--token-file or PRIMLABEL_TOKEN)",
                      kExitUsage};
  return config;
}

}  // namespace primlabel::server
