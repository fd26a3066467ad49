#pragma once
// The baseline the paper compares the CRF against: an RBF-kernel SVM (libsvm) on the same node
// features x_i = s * descriptor_i, one point at a time, with probability outputs.

#include <Eigen/Core>
#include <cstdint>
#include <memory>
#include <span>
#include <stop_token>
#include <string>
#include <vector>

#include "primlabel/crf/training.hpp"

namespace primlabel::svm {

struct SvmOptions {
  double c = 10.0;
  // RBF width; 0 = 1 / (mean squared distance between training features), which adapts to the
  // descriptor's scale (libsvm's 1 / num_features does not).
  double gamma = 0.0;
  // libsvm training is O(n^2): train on at most this many labelled points (a seeded random,
  // otherwise deterministic subsample).
  std::size_t max_training_points = 20000;
  std::uint32_t seed = 1;  // subsample, and libsvm's internal cross-validation (via srand)
  bool probability = true;
  double cache_mb = 200.0;
  float feature_scale = 0.01f;
};

struct SvmPrediction {
  std::vector<std::uint32_t> labels;  // class id per point; unknown_label without a descriptor
  Eigen::MatrixXf probabilities;      // num_points x K, model class order
};

class SvmClassifier {
 public:
  // Trains on the labelled points (label >= 0) of the scenes' active nodes. Throws
  // std::invalid_argument for inconsistent data or fewer than one labelled point.
  static SvmClassifier train(std::span<const crf::LabeledGraph> scenes,
                             const std::vector<std::uint32_t>& class_ids,
                             const SvmOptions& options = {});

  // A classifier from libsvm's text model format (as to_libsvm_text writes it, or libsvm's
  // svm_save_model for a C-SVC RBF model whose labels index `class_ids`). gamma travels in the
  // text; the class ids, descriptor size and feature scale do not. Throws std::invalid_argument
  // naming the line and the reason when the text is not such a model.
  static SvmClassifier from_libsvm_text(const std::string& text,
                                        const std::vector<std::uint32_t>& class_ids,
                                        int descriptor_dim, float feature_scale);

  // libsvm's text model format, values at full precision: from_libsvm_text of it predicts
  // bit-identically, and libsvm's svm_load_model reads it.
  std::string to_libsvm_text() const;

  // `descriptors` is row-major points x descriptor_dim; rows that are not finite get
  // `unknown_label` (and NaN probabilities). Parallel over points; same result for any threads.
  // Without a probability model (or with one class) the probabilities are one-hot. Once `stop` is
  // requested the remaining points are skipped and primlabel::Cancelled is thrown (an RBF SVM
  // labels only ~35k points/s, so a large cloud would otherwise run on for minutes).
  SvmPrediction predict(std::span<const float> descriptors, std::uint32_t unknown_label = 0,
                        int threads = 0, const std::stop_token& stop = {}) const;
  // The same for typed descriptors, whose dimension must be descriptor_dim().
  SvmPrediction predict(const Descriptors& descriptors, std::uint32_t unknown_label = 0,
                        int threads = 0, const std::stop_token& stop = {}) const;

  double gamma() const;
  float feature_scale() const;
  int descriptor_dim() const;
  bool has_probabilities() const;
  std::size_t training_points() const;  // 0 for a classifier read from text
  std::size_t support_vectors() const;
  const std::vector<std::uint32_t>& class_ids() const;

  SvmClassifier(SvmClassifier&&) noexcept;
  SvmClassifier& operator=(SvmClassifier&&) noexcept;
  ~SvmClassifier();

 private:
  struct Impl;
  explicit SvmClassifier(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace primlabel::svm
