#include "primlabel/ops/server_metrics.hpp"

#include <prometheus/text_serializer.h>

#include "primlabel/build_version.hpp"
#include "primlabel/ops/process_collector.hpp"
#include "primlabel/ops/stage_times.hpp"

namespace primlabel::ops {

namespace {

using prometheus::BuildCounter;
using prometheus::BuildGauge;
using prometheus::BuildHistogram;

// 1 ms .. ~2 min, roughly x2.5 per bucket: a table scene takes tens of ms, a 5M-point scan tens
// of seconds.
const prometheus::Histogram::BucketBoundaries& seconds_buckets() {
  static const prometheus::Histogram::BucketBoundaries buckets{
      0.001, 0.0025, 0.005, 0.01, 0.025, 0.05, 0.1, 0.25, 0.5, 1, 2.5, 5, 10, 25, 60, 120};
  return buckets;
}

}  // namespace

ServerMetrics::ServerMetrics()
    : registry_(std::make_shared<prometheus::Registry>()),
      process_(std::make_shared<ProcessCollector>()),
      requests_(BuildCounter()
                    .Name("primlabel_requests_total")
                    .Help("RPCs finished, by method, model and gRPC status")
                    .Register(*registry_)),
      points_(BuildCounter()
                  .Name("primlabel_points_total")
                  .Help("Points labeled, by model")
                  .Register(*registry_)),
      choices_(BuildCounter()
                   .Name("primlabel_model_choices_total")
                   .Help("Labeling requests by the model that labeled them and how it was chosen "
                         "(named by the request, by the domain its cloud fits, the default)")
                   .Register(*registry_)),
      dropped_(BuildCounter()
                   .Name("primlabel_points_dropped_total")
                   .Help("Points not labeled because of bad input, by reason")
                   .Register(*registry_)),
      inflight_(BuildGauge()
                    .Name("primlabel_inflight_requests")
                    .Help("Labeling requests admitted and not finished")
                    .Register(*registry_)
                    .Add({})),
      queue_depth_(BuildGauge()
                       .Name("primlabel_queue_depth")
                       .Help("Labeling requests waiting for a worker")
                       .Register(*registry_)
                       .Add({})),
      stage_seconds_(BuildHistogram()
                         .Name("primlabel_stage_seconds")
                         .Help("Time per labeling stage")
                         .Register(*registry_)),
      request_seconds_(BuildHistogram()
                           .Name("primlabel_request_seconds")
                           .Help("Time per RPC, by method")
                           .Register(*registry_)),
      model_info_(BuildGauge()
                      .Name("primlabel_model_info")
                      .Help("1 for every served model version")
                      .Register(*registry_)),
      models_loaded_(BuildGauge()
                         .Name("primlabel_models_loaded")
                         .Help("Model versions loaded")
                         .Register(*registry_)
                         .Add({})),
      reloads_(BuildCounter()
                   .Name("primlabel_model_reloads_total")
                   .Help("Model versions loaded or replaced")
                   .Register(*registry_)
                   .Add({})),
      reload_failures_(BuildCounter()
                           .Name("primlabel_model_reload_failures_total")
                           .Help("Model versions that failed to load (the old one kept serving)")
                           .Register(*registry_)
                           .Add({})) {
  for (const StageField& stage : kStages)
    stage_seconds_.Add({{"stage", stage.name}}, seconds_buckets());
  dropped_.Add({{"reason", "non_finite"}});
  BuildGauge()
      .Name("primlabel_build_info")
      .Help("1, labeled with the version and the git description the server was built from")
      .Register(*registry_)
      .Add({{"version", std::string(kBuildVersion)}, {"git", std::string(kBuildGitDescribe)}})
      .Set(1);
}

std::vector<std::weak_ptr<prometheus::Collectable>> ServerMetrics::collectables() const {
  return {registry_, process_};
}

std::string ServerMetrics::serialize() const {
  std::vector<prometheus::MetricFamily> families = registry_->Collect();
  std::vector<prometheus::MetricFamily> process = process_->Collect();
  families.insert(families.end(), process.begin(), process.end());
  return prometheus::TextSerializer().Serialize(families);
}

void ServerMetrics::model_chosen(const std::string& model, const std::string& reason) {
  choices_.Add({{"model", model_label(model)}, {"reason", reason}}).Increment();
}

std::string ServerMetrics::model_label(const std::string& model) const {
  std::shared_lock lock(loaded_models_mutex_);
  return loaded_models_.contains(model) ? model : kUnknownModelLabel;
}

void ServerMetrics::request_finished(const std::string& method, const std::string& model,
                                     const std::string& status, double seconds) {
  requests_.Add({{"method", method}, {"model", model_label(model)}, {"status", status}})
      .Increment();
  request_seconds_.Add({{"method", method}}, seconds_buckets()).Observe(seconds);
}

void ServerMetrics::points_labeled(const std::string& model, double points) {
  points_.Add({{"model", model_label(model)}}).Increment(points);
}

void ServerMetrics::points_dropped(const std::string& reason, double points) {
  dropped_.Add({{"reason", reason}}).Increment(points);
}

void ServerMetrics::stage(const std::string& stage, double seconds) {
  stage_seconds_.Add({{"stage", stage}}, seconds_buckets()).Observe(seconds);
}

void ServerMetrics::set_admission(int admitted, int queued) {
  inflight_.Set(admitted);
  queue_depth_.Set(queued);
}

void ServerMetrics::set_models(const std::vector<std::pair<std::string, std::string>>& served,
                               std::size_t loaded_versions) {
  std::set<std::string, std::less<>> names;
  for (const auto& entry : served) names.insert(entry.first);
  {
    std::unique_lock lock(loaded_models_mutex_);
    loaded_models_ = std::move(names);
  }
  std::lock_guard lock(model_info_mutex_);
  for (prometheus::Gauge* series : model_info_series_) model_info_.Remove(series);
  model_info_series_.clear();
  for (const auto& [model, version] : served) {
    prometheus::Gauge& series = model_info_.Add({{"model", model}, {"version", version}});
    series.Set(1);
    model_info_series_.push_back(&series);
  }
  models_loaded_.Set(double(loaded_versions));
}

void ServerMetrics::reloads(unsigned loaded, unsigned failed) {
  reloads_.Increment(loaded);
  reload_failures_.Increment(failed);
}

}  // namespace primlabel::ops
