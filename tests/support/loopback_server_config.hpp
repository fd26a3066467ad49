#pragma once
// The configuration an in-process server starts from in tests and benchmarks (include it only
// from targets that link primlabel::server_ops).

#include <string>

#include "primlabel/ops/server_config.hpp"

namespace primlabel::test {

// Serves `models_dir` on a free 127.0.0.1 port with one worker; the directory is read once, so a
// run never races the reload poll.
inline ops::ServerConfig loopback_server_config(const std::string& models_dir) {
  ops::ServerConfig config;
  config.models_dir = models_dir;
  config.listen = "127.0.0.1:0";
  config.reload_seconds = 0;
  config.workers = 1;
  return config;
}

}  // namespace primlabel::test
