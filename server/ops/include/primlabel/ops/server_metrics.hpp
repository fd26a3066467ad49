#pragma once
// The service's Prometheus metrics (names are a contract: the deployment's alerts use them).
//   primlabel_requests_total{method,model,status}     counter
//   primlabel_points_total{model}                      counter, points labeled
//   primlabel_model_choices_total{model,reason}        counter, how each labeled request's
//                                                      model was chosen: named, domain, default
//   primlabel_points_dropped_total{reason}             counter, e.g. reason="non_finite"
//   primlabel_inflight_requests                        gauge, admitted requests
//   primlabel_queue_depth                              gauge, requests waiting for a worker
//   primlabel_stage_seconds{stage}                     histogram: receive, prefilter, normals,
//                                                      features, inference, send
//   primlabel_request_seconds{method}                  histogram
//   primlabel_model_info{model,version}                gauge = 1 per served version
//   primlabel_models_loaded                            gauge, loaded versions
//   primlabel_model_reloads_total                      counter, versions (re)loaded
//   primlabel_model_reload_failures_total              counter
//   primlabel_build_info{version,git}                  gauge = 1
// plus the process_* metrics of ProcessCollector. The `model` label only ever holds the name of
// a model loaded at the time, or "unknown": clients choose the names they send, and every
// distinct label value is a series kept for the life of the process.

#include <prometheus/collectable.h>
#include <prometheus/counter.h>
#include <prometheus/family.h>
#include <prometheus/gauge.h>
#include <prometheus/histogram.h>
#include <prometheus/registry.h>

#include <memory>
#include <mutex>
#include <set>
#include <shared_mutex>
#include <string>
#include <utility>
#include <vector>

namespace primlabel::ops {

inline constexpr const char* kUnknownModelLabel = "unknown";

class ServerMetrics {
 public:
  ServerMetrics();

  // What /metrics serves: the service's registry and the process metrics.
  std::vector<std::weak_ptr<prometheus::Collectable>> collectables() const;
  // All of it in the text exposition format, as /metrics answers (benchmarks, tests).
  std::string serialize() const;

  void request_finished(const std::string& method, const std::string& model,
                        const std::string& status, double seconds);
  void points_labeled(const std::string& model, double points);
  // `reason` is one of pipeline::choice_reason_name's three values.
  void model_chosen(const std::string& model, const std::string& reason);
  void points_dropped(const std::string& reason, double points);
  void stage(const std::string& stage, double seconds);
  void set_admission(int admitted, int queued);
  // The served (model, version) pairs and the number of loaded versions. The served model names
  // become the values the `model` label may take.
  void set_models(const std::vector<std::pair<std::string, std::string>>& served,
                  std::size_t loaded_versions);
  void reloads(unsigned loaded, unsigned failed);

  // `model` when it is loaded, else kUnknownModelLabel.
  std::string model_label(const std::string& model) const;

 private:
  std::shared_ptr<prometheus::Registry> registry_;
  std::shared_ptr<prometheus::Collectable> process_;
  prometheus::Family<prometheus::Counter>& requests_;
  prometheus::Family<prometheus::Counter>& points_;
  prometheus::Family<prometheus::Counter>& choices_;
  prometheus::Family<prometheus::Counter>& dropped_;
  prometheus::Gauge& inflight_;
  prometheus::Gauge& queue_depth_;
  prometheus::Family<prometheus::Histogram>& stage_seconds_;
  prometheus::Family<prometheus::Histogram>& request_seconds_;
  prometheus::Family<prometheus::Gauge>& model_info_;
  prometheus::Gauge& models_loaded_;
  prometheus::Counter& reloads_;
  prometheus::Counter& reload_failures_;
  std::mutex model_info_mutex_;
  std::vector<prometheus::Gauge*> model_info_series_;
  mutable std::shared_mutex loaded_models_mutex_;
  std::set<std::string, std::less<>> loaded_models_;
};

}  // namespace primlabel::ops
