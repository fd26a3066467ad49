#include "primlabel/rpc/label_server.hpp"

#include <grpcpp/ext/proto_server_reflection_plugin.h>
#include <grpcpp/health_check_service_interface.h>
#include <grpcpp/server_builder.h>

#include <stdexcept>

#include "primlabel/ops/logging.hpp"
#include "primlabel/rpc/auth.hpp"
#include "primlabel/service/user_text.hpp"

namespace primlabel::rpc {

namespace {

constexpr auto kShutdownGrace = std::chrono::milliseconds(250);

service::ModelRegistry::Options registry_options(const ops::ServerConfig& config) {
  service::ModelRegistry::Options options;
  options.root = config.models_dir;
  options.default_model = config.default_model;
  options.pins = config.pins;
  options.missing_scans_before_unload = config.unload_after_missing_polls;
  return options;
}

// "host:port" with the port replaced by the bound one.
std::string with_port(const std::string& address, int port) {
  const auto colon = address.rfind(':');
  return (colon == std::string::npos ? address : address.substr(0, colon)) + ":" +
         std::to_string(port);
}

}  // namespace

LabelServer::LabelServer(ops::ServerConfig config)
    : config_(std::move(config)),
      registry_(registry_options(config_)),
      auth_(config_.token, config_.token_for_all, config_.insecure_admin) {
  receiving_ = std::make_unique<service::SlotBudget>(config_.max_receiving_streams);
  admission_ = std::make_unique<service::Admission>(
      ops::effective_workers(config_), config_.queue,
      [this](int, int queued) { requests_.set_queued(queued); });
  env_.config = &config_;
  env_.registry = &registry_;
  env_.admission = admission_.get();
  env_.receiving = receiving_.get();
  env_.requests = &requests_;
  env_.timers = &timers_;
  env_.trimmer = &trimmer_;
  env_.metrics = &metrics_;
  env_.draining = &draining_;
  env_.threads_per_job = ops::effective_threads_per_job(config_);
  // Every change of the registry, whoever made it (poller, admin RPC), reaches health and the
  // model gauges.
  registry_.set_observer([this] { models_changed(); });

  try {
    const service::ReloadReport report = registry_.rescan();
    metrics_.reloads(report.loaded, report.failed);
  } catch (const service::RegistryError& error) {
    throw std::runtime_error(error.what());
  }
  // A default or pin naming nothing loaded is a typo that would otherwise only show as failed
  // requests (or a silently different version) in production.
  if (std::string problem = registry_.configuration_problem(); !problem.empty())
    throw ops::ConfigError{std::move(problem), kExitUsage};
  // Requests naming no model go by their cloud's domain; this one takes those no domain decides.
  if (const std::string fallback = registry_.default_model(); fallback.empty())
    ops::log_info("default_model").kv("model", "").kv("source", "none");
  else
    ops::log_info("default_model")
        .kv("model", service::user_text(fallback))
        .kv("source", registry_.default_source())
        .kv("loaded", [&] {
          for (const service::ServedModel& served : registry_.list())
            if (served.name == fallback) return "yes";
          return "no";
        }());
  if (auth_.admin_open())
    ops::log_warn("insecure_admin")
        .kv("message",
            "admin RPCs (load, unload, reload models) are open to anyone who reaches the port: "
            "--insecure-admin without a token");

  labeler_ = std::make_unique<LabelerService>(env_, auth_);
  admin_ = std::make_unique<AdminService>(env_, auth_);
  grpc::EnableDefaultHealthCheckService(true);
  grpc::reflection::InitProtoReflectionServerBuilderPlugin();
  grpc::ServerBuilder builder;
  builder.AddListeningPort(
      config_.listen,
      server_credentials({config_.tls_cert, config_.tls_key, config_.tls_client_ca}), &port_);
  builder.SetMaxReceiveMessageSize(config_.max_message_bytes);
  builder.SetMaxSendMessageSize(config_.max_message_bytes);
  // gRPC sets SO_REUSEPORT by default: a second server on a port in use would start and
  // silently take a share of its connections. The port is ours alone, or start-up fails.
  builder.AddChannelArgument(GRPC_ARG_ALLOW_REUSEPORT, 0);
  builder.RegisterService(labeler_.get());
  builder.RegisterService(admin_.get());
  {
    std::unique_ptr<grpc::Server> built = builder.BuildAndStart();
    std::lock_guard lock(health_mutex_);  // the observer may run on an admin call already
    server_ = std::move(built);
  }
  if (!server_ || port_ == 0)
    throw std::runtime_error("cannot listen on " + config_.listen +
                             " (in use by another process, or not an address of this host)");

  if (!config_.metrics_listen.empty())
    metrics_endpoint_ =
        std::make_unique<ops::MetricsEndpoint>(config_.metrics_listen, metrics_.collectables());
  models_changed();
  if (config_.reload_seconds > 0)
    poller_ = std::jthread([this](std::stop_token stop) { poll_models(stop); });

  ops::LogLine line(ops::LogLevel::kInfo, "listening");
  line.kv("address", with_port(config_.listen, port_))
      .kv("port", port_)
      .kv("metrics_port", metrics_port())
      .kv("tls", !config_.tls_cert.empty())
      .kv("mtls", !config_.tls_client_ca.empty())
      .kv("token", auth_.enabled())
      .kv("admin", auth_.enabled()      ? "token"
                   : auth_.admin_open() ? "insecure"
                                        : "off")
      .kv("workers", admission_->workers())
      .kv("queue", config_.queue)
      .kv("threads_per_job", env_.threads_per_job)
      .kv("models", registry_.loaded_versions());
  if (!config_.metrics_listen.empty())
    line.kv("metrics_address", with_port(config_.metrics_listen, metrics_port()));
}

LabelServer::~LabelServer() { shutdown(std::chrono::milliseconds(0)); }

int LabelServer::metrics_port() const { return metrics_endpoint_ ? metrics_endpoint_->port() : 0; }

void LabelServer::models_changed() {
  // One at a time, reading the registry under the lock: whichever call comes last publishes the
  // latest state (the constructor's call can race with an early admin RPC's observer call).
  std::lock_guard lock(health_mutex_);
  const std::vector<service::ServedModel> models = registry_.list();
  std::vector<std::pair<std::string, std::string>> served;
  for (const service::ServedModel& model : models)
    served.emplace_back(model.name, model.served->version);
  metrics_.set_models(served, registry_.loaded_versions());
  if (draining_.load() || !server_) return;  // health was shut down for good
  const bool serving = !models.empty();
  grpc::HealthCheckServiceInterface* health = server_->GetHealthCheckService();
  health->SetServingStatus("", serving);
  health->SetServingStatus(kLabelerServiceName, serving);
}

void LabelServer::poll_models(std::stop_token stop) {
  std::mutex mutex;
  std::condition_variable_any wake;
  const auto interval = std::chrono::duration<double>(config_.reload_seconds);
  for (;;) {
    {
      std::unique_lock lock(mutex);
      if (wake.wait_for(lock, stop, interval, [] { return false; })) return;
      if (stop.stop_requested()) return;
    }
    try {
      const service::ReloadReport report = registry_.rescan();  // changes reach models_changed()
      metrics_.reloads(report.loaded, report.failed);
    } catch (const std::exception& e) {
      ops::log_error("model_poll_failed").kv("error", e.what());
    }
  }
}

void LabelServer::shutdown(std::chrono::milliseconds drain) {
  std::lock_guard shutdown_lock(shutdown_mutex_);
  if (shut_down_) return;
  shut_down_ = true;
  ops::log_info("shutting_down")
      .kv("drain_ms", std::int64_t(drain.count()))
      .kv("in_flight", requests_.in_flight());
  {
    std::lock_guard lock(health_mutex_);
    draining_.store(true);
    if (server_) server_->GetHealthCheckService()->Shutdown();  // NOT_SERVING from now on
  }
  poller_ = {};  // stops and joins
  // Drain ourselves: new labeling calls are refused (UNAVAILABLE) while admitted ones finish.
  // gRPC's own Shutdown deadline would also wait for idle client connections to close, which
  // clients without active calls notice only seconds later.
  const auto deadline = std::chrono::system_clock::now() + drain;
  while (requests_.in_flight() > 0 && std::chrono::system_clock::now() < deadline)
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  if (server_) {
    // Short calls (model queries) get a moment; labeling calls still running past the drain
    // deadline are cancelled and stop within a block of points.
    server_->Shutdown(std::min(deadline, std::chrono::system_clock::now() + kShutdownGrace));
    server_->Wait();
  }
  metrics_endpoint_.reset();
  ops::log_info("stopped");
}

}  // namespace primlabel::rpc
