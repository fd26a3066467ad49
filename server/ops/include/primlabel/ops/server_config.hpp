#pragma once
// Server configuration from flags, environment variables (PRIMLABEL_*) and an optional config
// file of `key = value` lines named like the flags (without "--"); flags win over the
// environment, which wins over the file, which wins over the defaults.

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "primlabel/cli/exit_codes.hpp"

namespace primlabel::ops {

struct ServerConfig {
  std::string models_dir;                         // <dir>/<model>/<version>/<file>.plm
  std::string listen = "127.0.0.1:50051";         // gRPC; port 0 picks a free port
  std::string metrics_listen = "127.0.0.1:9464";  // Prometheus /metrics; empty = off
  std::string default_model;                      // served when a request names none
  std::map<std::string, std::string> pins;        // model -> version served by default
  double reload_seconds = 30.0;                   // poll the models directory; 0 = never
  unsigned unload_after_missing_polls = 3;        // scans a version may be missing before it goes

  int workers = 0;          // concurrent labeling jobs; 0 = half the cores, at least 1
  int queue = 4;            // admitted requests beyond the workers; more get RESOURCE_EXHAUSTED
  int threads_per_job = 0;  // OpenMP threads of one job; 0 = cores / workers, at least 1
  std::uint64_t max_points = 10'000'000;          // per request
  std::uint64_t max_request_bytes = 512u << 20;   // per request, all point arrays together
  int max_message_bytes = 16 << 20;               // gRPC receive and send limit
  std::uint64_t response_chunk_bytes = 2u << 20;  // target size of one LabelChunk
  double drain_seconds = 20.0;  // on SIGTERM/SIGINT, in-flight requests get this long

  // Streams against slow or hostile clients (service/stream_limits.hpp).
  int max_receiving_streams = 64;               // streams receiving points at once
  double stream_idle_seconds = 10.0;            // longest wait for a stream's next message
  double min_receive_bytes_per_second = 32768;  // a receiving stream's rate over each window
  double receive_rate_window_seconds = 5.0;     // the window, also the grace before the first
  double send_timeout_seconds = 30.0;           // longest wait for a client to take one message
  double max_request_seconds = 120.0;           // the deadline of a request that sets none

  std::string tls_cert;  // PEM; with tls_key enables TLS
  std::string tls_key;
  std::string tls_client_ca;    // PEM; requires and verifies client certificates (mutual TLS)
  std::string token;            // bearer token for admin RPCs (from --token-file or env)
  bool token_for_all = false;   // also require the token on labeling and model queries
  bool insecure_admin = false;  // allow admin RPCs without a token (warned at start-up)

  std::string log_level = "info";
};

// Thrown for bad usage (unknown flag, bad value, unreadable file); the message says what.
struct ConfigError {
  std::string message;
  int exit_code = kExitUsage;  // kExitOk for --help (message is the help text)
};

// Parses argv (and the environment and the config file). Throws ConfigError.
ServerConfig parse_server_config(int argc, const char* const* argv);

// Resolved worker and thread counts for this machine.
int effective_workers(const ServerConfig& config);
int effective_threads_per_job(const ServerConfig& config);

}  // namespace primlabel::ops
