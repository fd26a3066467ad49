#include "primlabel/model/svm_baseline.hpp"

#include <libsvm/svm.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <numeric>
#include <random>
#include <stdexcept>
#include <string>

#include "libsvm_model.hpp"
#include "primlabel/geometry/cancellation.hpp"
#include "primlabel/geometry/parallel.hpp"

namespace primlabel::svm {

using primlabel::detail::parallel_for;
using primlabel::detail::Schedule;

namespace {

void quiet(const char*) {}

// libsvm's sparse row: the non-zero features (1-based indices), then the -1 terminator.
void to_nodes(const float* descriptor, int dim, float scale, std::vector<svm_node>& out) {
  out.clear();
  for (int f = 0; f < dim; ++f)
    if (descriptor[f] != 0.0f) out.push_back({f + 1, double(scale) * descriptor[f]});
  out.push_back({-1, 0.0});
}

}  // namespace

struct SvmClassifier::Impl {
  std::vector<std::uint32_t> class_ids;
  int dim = 0;
  float scale = 0.01f;
  std::size_t training_points = 0;
  std::unique_ptr<detail::LibsvmModel> model;
  std::vector<int> column_of_label;  // libsvm's label order -> our class index

  void set_model(std::unique_ptr<detail::LibsvmModel> m) {
    model = std::move(m);
    const svm_model& view = model->model();
    column_of_label.assign(view.label, view.label + view.nr_class);  // labels: class indices
  }
};

SvmClassifier::SvmClassifier(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
SvmClassifier::SvmClassifier(SvmClassifier&&) noexcept = default;
SvmClassifier& SvmClassifier::operator=(SvmClassifier&&) noexcept = default;
SvmClassifier::~SvmClassifier() = default;

SvmClassifier SvmClassifier::train(std::span<const crf::LabeledGraph> scenes,
                                   const std::vector<std::uint32_t>& class_ids,
                                   const SvmOptions& options) {
  if (scenes.empty() || class_ids.empty())
    throw std::invalid_argument("SVM: no training scenes or no classes");
  const int dim = scenes.front().descriptors.dim;
  auto impl = std::make_unique<Impl>();
  impl->class_ids = class_ids;
  impl->dim = dim;
  impl->scale = options.feature_scale;

  // Every usable labelled point, then a seeded subsample kept in data order.
  std::vector<std::pair<std::uint32_t, std::uint32_t>> samples;  // (scene, point)
  for (std::size_t s = 0; s < scenes.size(); ++s) {
    const crf::LabeledGraph& g = scenes[s];
    if (g.descriptors.dim != dim || g.labels.size() != g.graph.num_nodes() ||
        g.descriptors.size() != g.labels.size())
      throw std::invalid_argument("SVM: scene " + std::to_string(s) + " has inconsistent shapes");
    for (std::size_t i = 0; i < g.labels.size(); ++i) {
      if (g.labels[i] >= static_cast<int>(class_ids.size()))
        throw std::invalid_argument("SVM: label out of range");
      if (g.labels[i] >= 0 && g.graph.active[i])
        samples.emplace_back(static_cast<std::uint32_t>(s), static_cast<std::uint32_t>(i));
    }
  }
  if (samples.empty()) throw std::invalid_argument("SVM: no labelled points");
  if (samples.size() > options.max_training_points) {
    std::mt19937 rng(options.seed);
    for (std::size_t k = 0; k < options.max_training_points; ++k) {
      std::uniform_int_distribution<std::size_t> pick(k, samples.size() - 1);
      std::swap(samples[k], samples[pick(rng)]);
    }
    samples.resize(options.max_training_points);
    std::sort(samples.begin(), samples.end());
  }

  // The training rows; libsvm's model points into them until it is copied below.
  std::vector<svm_node> nodes;
  std::vector<svm_node*> rows;
  std::vector<double> targets;
  std::vector<std::size_t> starts;
  std::vector<svm_node> row;
  for (const auto& [s, i] : samples) {
    to_nodes(scenes[s].descriptors.row(i).data(), dim, options.feature_scale, row);
    starts.push_back(nodes.size());
    nodes.insert(nodes.end(), row.begin(), row.end());
    targets.push_back(scenes[s].labels[i]);
  }
  for (std::size_t start : starts) rows.push_back(nodes.data() + start);
  impl->training_points = rows.size();

  double gamma = options.gamma;
  if (gamma <= 0.0) {
    // Mean squared distance over a fixed set of sample pairs.
    std::mt19937 rng(options.seed + 1);
    std::uniform_int_distribution<std::size_t> pick(0, samples.size() - 1);
    double sum = 0.0;
    const int pairs = 2000;
    for (int p = 0; p < pairs; ++p) {
      const auto& [sa, ia] = samples[pick(rng)];
      const auto& [sb, ib] = samples[pick(rng)];
      const float* a = scenes[sa].descriptors.row(ia).data();
      const float* b = scenes[sb].descriptors.row(ib).data();
      for (int f = 0; f < dim; ++f) {
        const double diff = double(options.feature_scale) * (a[f] - b[f]);
        sum += diff * diff;
      }
    }
    const double mean = sum / pairs;
    gamma = mean > 0.0 ? 1.0 / mean : 1.0;
  }

  svm_parameter param{};
  param.svm_type = C_SVC;
  param.kernel_type = RBF;
  param.gamma = gamma;
  param.C = options.c;
  param.cache_size = options.cache_mb;
  param.eps = 1e-3;
  param.shrinking = 1;
  param.probability = options.probability ? 1 : 0;
  param.nr_weight = 0;
  svm_problem problem;
  problem.l = static_cast<int>(rows.size());
  problem.y = targets.data();
  problem.x = rows.data();
  if (const char* error = svm_check_parameter(&problem, &param))
    throw std::invalid_argument(std::string("SVM: ") + error);
  svm_set_print_string_function(&quiet);
  std::srand(options.seed);  // libsvm's probability cross-validation draws from rand()
  svm_model* trained = svm_train(&problem, &param);
  std::unique_ptr<detail::LibsvmModel> copy;
  try {
    copy = detail::LibsvmModel::copy_of(*trained);
  } catch (...) {
    svm_free_and_destroy_model(&trained);
    throw;
  }
  svm_free_and_destroy_model(&trained);
  impl->set_model(std::move(copy));
  return SvmClassifier(std::move(impl));
}

SvmClassifier SvmClassifier::from_libsvm_text(const std::string& text,
                                              const std::vector<std::uint32_t>& class_ids,
                                              int descriptor_dim, float feature_scale) {
  if (class_ids.empty() || descriptor_dim <= 0)
    throw std::invalid_argument("SVM: no classes or no descriptor");
  if (!std::isfinite(feature_scale) || feature_scale <= 0.0f)
    throw std::invalid_argument("SVM: the feature scale must be positive");
  auto impl = std::make_unique<Impl>();
  impl->class_ids = class_ids;
  impl->dim = descriptor_dim;
  impl->scale = feature_scale;
  impl->set_model(detail::LibsvmModel::parse(text, descriptor_dim));
  for (int label : impl->column_of_label)
    if (label < 0 || label >= static_cast<int>(class_ids.size()))
      throw std::invalid_argument("libsvm model: label " + std::to_string(label) +
                                  " is not one of the " + std::to_string(class_ids.size()) +
                                  " classes");
  return SvmClassifier(std::move(impl));
}

std::string SvmClassifier::to_libsvm_text() const { return impl_->model->to_text(); }

SvmPrediction SvmClassifier::predict(const Descriptors& descriptors, std::uint32_t unknown_label,
                                     int threads, const std::stop_token& stop) const {
  if (descriptors.dim != impl_->dim)
    throw std::invalid_argument("SVM: descriptors have dimension " +
                                std::to_string(descriptors.dim) + ", the classifier " +
                                std::to_string(impl_->dim));
  return predict(std::span<const float>(descriptors.values), unknown_label, threads, stop);
}

SvmPrediction SvmClassifier::predict(std::span<const float> descriptors,
                                     std::uint32_t unknown_label, int threads,
                                     const std::stop_token& stop) const {
  const Impl& m = *impl_;
  const svm_model* model = &m.model->model();
  const long long n = static_cast<long long>(descriptors.size() / m.dim);
  const int k_count = static_cast<int>(m.class_ids.size());
  SvmPrediction out;
  out.labels.assign(n, unknown_label);
  out.probabilities.setZero(n, k_count);
  const bool with_probability = svm_check_probability_model(model);
  struct Scratch {
    std::vector<svm_node> row;
    std::vector<double> estimates;
  };
  parallel_for(
      n, threads, Schedule::Dynamic(64),
      [&] {
        return Scratch{{}, std::vector<double>(m.column_of_label.size())};
      },
      [&](Scratch& scratch, std::ptrdiff_t i) {
        auto& [row, estimates] = scratch;
        if (stop.stop_requested()) return;  // cancelled: skip the remaining points
        const float* d = descriptors.data() + i * m.dim;
        if (!std::all_of(d, d + m.dim, [](float v) { return std::isfinite(v); })) {
          out.probabilities.row(i).setConstant(std::numeric_limits<float>::quiet_NaN());
          return;
        }
        to_nodes(d, m.dim, m.scale, row);
        double label;
        if (with_probability) {
          label = svm_predict_probability(model, row.data(), estimates.data());
          for (std::size_t c = 0; c < estimates.size(); ++c)
            out.probabilities(i, m.column_of_label[c]) = static_cast<float>(estimates[c]);
        } else {
          label = svm_predict(model, row.data());
          out.probabilities(i, static_cast<int>(label)) = 1.0f;
        }
        out.labels[i] = m.class_ids[static_cast<int>(label)];
      });
  throw_if_stopped(stop, "SVM prediction");
  return out;
}

double SvmClassifier::gamma() const { return impl_->model->model().param.gamma; }
float SvmClassifier::feature_scale() const { return impl_->scale; }
int SvmClassifier::descriptor_dim() const { return impl_->dim; }
bool SvmClassifier::has_probabilities() const {
  return svm_check_probability_model(&impl_->model->model()) != 0;
}
std::size_t SvmClassifier::training_points() const { return impl_->training_points; }
std::size_t SvmClassifier::support_vectors() const {
  return static_cast<std::size_t>(impl_->model->model().l);
}
const std::vector<std::uint32_t>& SvmClassifier::class_ids() const { return impl_->class_ids; }

}  // namespace primlabel::svm
