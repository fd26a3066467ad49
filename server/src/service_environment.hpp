#pragma once
// What the RPC handlers share: configuration, the model registry, admission, metrics, auth and
// whether the server is draining. Owned by LabelServer, which outlives every handler.

#include <atomic>

#include "admission.hpp"
#include "auth.hpp"
#include "model_registry.hpp"
#include "server_config.hpp"
#include "server_metrics.hpp"

namespace primlabel::server {

struct ServiceEnvironment {
  const ServerConfig* config = nullptr;
  ModelRegistry* registry = nullptr;
  Admission* admission = nullptr;
  ServerMetrics* metrics = nullptr;
  const TokenAuth* auth = nullptr;
  const std::atomic<bool>* draining = nullptr;
  int threads_per_job = 1;
};

}  // namespace primlabel::server
