#pragma once
// What the RPC handlers share: configuration, the model registry, admission (compute slots),
// the receiving-stream budget, the request gauge, the timer thread and the idle memory trim,
// metrics, the RPC edge's authenticator (declared only: the service layer never calls it) and
// whether the server is draining. Owned by LabelServer, which outlives every handler.

#include <atomic>

#include "admission.hpp"
#include "free_memory.hpp"
#include "model_registry.hpp"
#include "request_gauge.hpp"
#include "server_config.hpp"
#include "server_metrics.hpp"
#include "slot_budget.hpp"
#include "timer_service.hpp"

namespace primlabel::server {

class TokenAuth;  // auth.hpp, at the RPC edge

struct ServiceEnvironment {
  const ServerConfig* config = nullptr;
  ModelRegistry* registry = nullptr;
  Admission* admission = nullptr;
  SlotBudget* receiving = nullptr;
  RequestGauge* requests = nullptr;
  TimerService* timers = nullptr;
  IdleMemoryTrimmer* trimmer = nullptr;
  ServerMetrics* metrics = nullptr;
  const TokenAuth* auth = nullptr;
  const std::atomic<bool>* draining = nullptr;
  int threads_per_job = 1;
};

}  // namespace primlabel::server
