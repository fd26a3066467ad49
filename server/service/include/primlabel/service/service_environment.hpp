#pragma once
// What the RPC handlers share: configuration, the model registry, admission (compute slots),
// the receiving-stream budget, the request gauge, the timer thread and the idle memory trim,
// metrics and whether the server is draining. Owned by LabelServer, which outlives every handler.

#include <atomic>

#include "primlabel/ops/request_gauge.hpp"
#include "primlabel/ops/server_config.hpp"
#include "primlabel/ops/server_metrics.hpp"
#include "primlabel/service/admission.hpp"
#include "primlabel/service/free_memory.hpp"
#include "primlabel/service/model_registry.hpp"
#include "primlabel/service/slot_budget.hpp"
#include "primlabel/service/timer_service.hpp"

namespace primlabel::service {

struct ServiceEnvironment {
  const ops::ServerConfig* config = nullptr;
  ModelRegistry* registry = nullptr;
  Admission* admission = nullptr;
  SlotBudget* receiving = nullptr;
  ops::RequestGauge* requests = nullptr;
  TimerService* timers = nullptr;
  IdleMemoryTrimmer* trimmer = nullptr;
  ops::ServerMetrics* metrics = nullptr;
  const std::atomic<bool>* draining = nullptr;
  int threads_per_job = 1;
};

}  // namespace primlabel::service
