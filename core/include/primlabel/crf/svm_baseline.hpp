#pragma once
// The baseline the paper compares the CRF against: an RBF-kernel SVM (libsvm) on the same node
// features x_i = s * descriptor_i, one point at a time, with probability outputs.

#include <Eigen/Core>
#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include "primlabel/crf/training.hpp"

namespace primlabel::crf {

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
  Eigen::MatrixXf probabilities;      // num_points x K (empty without probability outputs)
};

class SvmClassifier {
 public:
  // Trains on the labelled points (label >= 0) of the scenes' active nodes. Throws
  // std::invalid_argument for inconsistent data or fewer than one labelled point.
  static SvmClassifier train(std::span<const LabeledGraph> scenes,
                             const std::vector<std::uint32_t>& class_ids,
                             const SvmOptions& options = {});

  // `descriptors` is row-major points x descriptor_dim; rows that are not finite get
  // `unknown_label` (and NaN probabilities). Parallel over points; same result for any threads.
  SvmPrediction predict(std::span<const float> descriptors, std::uint32_t unknown_label = 0,
                        int threads = 0) const;

  double gamma() const;
  std::size_t training_points() const;
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

}  // namespace primlabel::crf
