#pragma once
// The paper's Fig. 4 (Rusu et al. 2009): the mean FPFH signature of each primitive class over
// labeled scenes, and the histogram-intersection-kernel (HIK) distance between the classes'
// signatures,
//
//   d(a, b) = 1 - sum_b min(a_b, b_b) / min(sum_b a_b, sum_b b_b),
//
// 0 for identical histograms, 1 for histograms with no mass in common, symmetric, and for FPFH
// (three sub-histograms of 100 each) the share of the 300 that the two do not share.

#include <Eigen/Core>
#include <cstdint>
#include <functional>
#include <span>
#include <string>
#include <vector>

#include "primlabel/geometry/descriptors.hpp"
#include "primlabel/model/label_model.hpp"
#include "primlabel/synth/generate.hpp"

namespace primlabel::research {

struct ClassSignatures {
  std::vector<std::uint32_t> class_ids;  // taxonomy ids with at least one point, id order
  Eigen::MatrixXd mean;                  // classes x descriptor bins
  std::vector<std::uint64_t> points;     // per class
};

// Sums descriptors per class over any number of labeled scenes.
class SignatureAccumulator {
 public:
  explicit SignatureAccumulator(int descriptor_dim);
  // `labels` are taxonomy ids per point; unknown points and rows that are not finite are skipped.
  void add(std::span<const std::uint32_t> labels, const Descriptors& descriptors);
  ClassSignatures result() const;

 private:
  int dim_;
  Eigen::MatrixXd sums_;               // kPrimitiveClassCount x dim
  std::vector<std::uint64_t> counts_;  // per taxonomy id
};

// d(a, b) above; 0 when both are empty.
double hik_distance(std::span<const double> a, std::span<const double> b);
// Classes x classes.
Eigen::MatrixXd hik_distance_matrix(const ClassSignatures& signatures);

struct Fig4Options {
  int scenes = 3;  // synthetic training scenes (the training set's seeds)
  synth::SensorKind sensor = synth::SensorKind::kLms400;
  FeatureSettings features;  // FPFH, normals r = 0.01, features r = 0.025
  int threads = 0;
  std::function<void(const std::string&)> progress;
};

struct Fig4 {
  ClassSignatures signatures;
  Eigen::MatrixXd hik;
};

Fig4 run_fig4(const Fig4Options& options);

// fig4_signatures.csv (class,bin0..binN-1), fig4_hik.csv (class,<class names...>),
// fig4_signatures.png (one panel per class) and fig4_hik.png (heat map) in `directory`, which is
// created when missing. Throws std::runtime_error naming a file that cannot be written.
void write_fig4(const Fig4& fig4, const std::string& directory);

// The distance matrix as fixed-width text.
std::string hik_text(const Fig4& fig4);

}  // namespace primlabel::research
