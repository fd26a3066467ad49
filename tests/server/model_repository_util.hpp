#pragma once
// What the transport-free service tests share with the in-process server tests: a temporary
// model repository, a model written into it and a server configuration on 127.0.0.1:0.

#include <unistd.h>

#include <atomic>
#include <filesystem>
#include <string>

#include "loopback_server_config.hpp"
#include "primlabel/model/label_model.hpp"
#include "primlabel/ops/server_config.hpp"

namespace primlabel::servertest {

namespace fs = std::filesystem;

class TempDir {
 public:
  explicit TempDir(const std::string& tag) {
    static std::atomic<int> counter{0};
    path_ = fs::temp_directory_path() / ("primlabel_" + tag + "_" + std::to_string(::getpid()) +
                                         "_" + std::to_string(counter++));
    fs::remove_all(path_);
    fs::create_directories(path_);
  }
  ~TempDir() {
    std::error_code ignored;
    fs::remove_all(path_, ignored);
  }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  const fs::path& path() const { return path_; }

 private:
  fs::path path_;
};

// <root>/<model.name>/<model.version>/model.plm
inline fs::path write_model(const fs::path& root, const LabelModel& model) {
  const fs::path dir = root / model.name / model.version;
  fs::create_directories(dir);
  save_model((dir / "model.plm").string(), model);
  return dir / "model.plm";
}

inline ops::ServerConfig test_config(const fs::path& models) {
  ops::ServerConfig config = test::loopback_server_config(models.string());
  config.metrics_listen = "127.0.0.1:0";
  config.queue = 2;
  config.threads_per_job = 2;
  return config;
}

}  // namespace primlabel::servertest
