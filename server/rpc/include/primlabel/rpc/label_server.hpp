#pragma once
// The whole service in one object: the model registry and its poller, admission, metrics and
// their /metrics endpoint, the Labeler and ModelAdmin services, gRPC health and reflection.
// Health is SERVING (overall and for primlabel.v1.Labeler) exactly while at least one model is
// loaded and the server is not shutting down.

#include <grpcpp/server.h>

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <memory>
#include <mutex>
#include <thread>

#include "primlabel/ops/metrics_endpoint.hpp"
#include "primlabel/ops/server_config.hpp"
#include "primlabel/rpc/admin_service.hpp"
#include "primlabel/rpc/auth.hpp"
#include "primlabel/rpc/labeler_service.hpp"
#include "primlabel/service/service_environment.hpp"

namespace primlabel::rpc {

inline constexpr const char* kLabelerServiceName = "primlabel.v1.Labeler";

class LabelServer {
 public:
  // Loads the models (failures are logged and counted; an empty repository is allowed) and
  // binds both ports, the gRPC one exclusively (no SO_REUSEPORT). Throws ConfigError (exit code
  // 2) when --default-model or a --pin names no loaded model or version, std::runtime_error
  // when the repository is not a directory or an address cannot be bound.
  explicit LabelServer(ops::ServerConfig config);
  ~LabelServer();  // shutdown(0) if still running
  LabelServer(const LabelServer&) = delete;
  LabelServer& operator=(const LabelServer&) = delete;

  int port() const { return port_; }
  int metrics_port() const;  // 0 without metrics endpoint

  // Health NOT_SERVING, new calls refused, in-flight calls get `drain` to finish and are then
  // cancelled; returns when every handler has returned. Idempotent.
  void shutdown(std::chrono::milliseconds drain);

  service::ModelRegistry& registry() { return registry_; }
  ops::ServerMetrics& metrics() { return metrics_; }
  const ops::ServerConfig& config() const { return config_; }

 private:
  void models_changed();
  void poll_models(std::stop_token stop);

  ops::ServerConfig config_;
  ops::ServerMetrics metrics_;
  service::ModelRegistry registry_;
  TokenAuth auth_;
  std::atomic<bool> draining_{false};
  // Before admission_: jobs still stopping when the workers are joined may touch them.
  service::TimerService timers_;
  service::IdleMemoryTrimmer trimmer_{timers_};
  std::unique_ptr<service::SlotBudget> receiving_;
  ops::RequestGauge requests_{metrics_};
  std::unique_ptr<service::Admission> admission_;
  service::ServiceEnvironment env_;
  std::unique_ptr<LabelerService> labeler_;
  std::unique_ptr<AdminService> admin_;
  std::unique_ptr<grpc::Server> server_;
  std::unique_ptr<ops::MetricsEndpoint> metrics_endpoint_;
  int port_ = 0;
  std::mutex health_mutex_;
  std::mutex shutdown_mutex_;
  bool shut_down_ = false;
  std::jthread poller_;
};

}  // namespace primlabel::rpc
