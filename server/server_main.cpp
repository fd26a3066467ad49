// primlabel-server: serves the labeling API until SIGTERM or SIGINT, then drains and exits 0.
// Exit codes (exit_codes.hpp): 0 clean shutdown, 1 could not start (e.g. the
// address is in use), 2 bad usage (including a --default-model or --pin that names no loaded
// model).

#include <signal.h>

#include <chrono>
#include <cstdio>

#include "primlabel/ops/logging.hpp"
#include "primlabel/ops/server_config.hpp"
#include "primlabel/rpc/label_server.hpp"

int main(int argc, char** argv) {
  using namespace primlabel;
  ops::ServerConfig config;
  try {
    config = ops::parse_server_config(argc, argv);
  } catch (const ops::ConfigError& error) {
    std::fputs(error.message.c_str(), error.exit_code == 0 ? stdout : stderr);
    if (!error.message.empty() && error.message.back() != '\n') std::fputc('\n', stderr);
    return error.exit_code;
  }
  ops::set_log_level(ops::parse_log_level(config.log_level));

  // Signals are taken synchronously by this thread; block them before any thread starts so no
  // other thread receives them.
  sigset_t signals;
  sigemptyset(&signals);
  sigaddset(&signals, SIGTERM);
  sigaddset(&signals, SIGINT);
  pthread_sigmask(SIG_BLOCK, &signals, nullptr);

  std::unique_ptr<rpc::LabelServer> server;
  try {
    server = std::make_unique<rpc::LabelServer>(config);
  } catch (const ops::ConfigError& error) {
    // Settings that contradict the repository: as bad usage.
    std::fprintf(stderr, "%s\n", error.message.c_str());
    return error.exit_code;
  } catch (const std::exception& e) {
    ops::log_error("startup_failed").kv("error", e.what());
    return kExitFailure;
  }
  int signal_number = 0;
  sigwait(&signals, &signal_number);
  ops::log_info("signal").kv("signal", signal_number == SIGTERM ? "SIGTERM" : "SIGINT");
  server->shutdown(std::chrono::milliseconds(static_cast<long long>(config.drain_seconds * 1e3)));
  server.reset();
  return kExitOk;
}
