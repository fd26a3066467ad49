#pragma once
// The service's Prometheus metrics (names are a contract: the deployment's alerts use them).
//   primlabel_requests_total{method,model,status}     counter
//   primlabel_points_total{model}                      counter, points labeled
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

#include <memory>
#include <mutex>
#include <string>
#include <utility>
#include <vector>

#include "primlabel/metrics/metrics.hpp"

namespace primlabel::server {

class ServerMetrics {
 public:
  ServerMetrics();

  std::shared_ptr<metrics::Registry> registry() const { return registry_; }

  void request_finished(const std::string& method, const std::string& model,
                        const std::string& status, double seconds);
  void points_labeled(const std::string& model, double points);
  void points_dropped(const std::string& reason, double points);
  void stage(const std::string& stage, double seconds);
  void set_admission(int admitted, int queued);
  // The served (model, version) pairs and the number of loaded versions.
  void set_models(const std::vector<std::pair<std::string, std::string>>& served,
                  std::size_t loaded_versions);
  void reloads(unsigned loaded, unsigned failed);

 private:
  std::shared_ptr<metrics::Registry> registry_;
  metrics::Family<metrics::Counter>& requests_;
  metrics::Family<metrics::Counter>& points_;
  metrics::Family<metrics::Counter>& dropped_;
  metrics::Gauge& inflight_;
  metrics::Gauge& queue_depth_;
  metrics::Family<metrics::Histogram>& stage_seconds_;
  metrics::Family<metrics::Histogram>& request_seconds_;
  metrics::Family<metrics::Gauge>& model_info_;
  metrics::Gauge& models_loaded_;
  metrics::Counter& reloads_;
  metrics::Counter& reload_failures_;
  std::mutex model_info_mutex_;
  std::vector<metrics::Gauge*> model_info_series_;
};

}  // namespace primlabel::server
