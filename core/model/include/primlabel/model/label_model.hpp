#pragma once
// A trained labeling model as the tools and the service use it, and its file. Everything needed to
// label a cloud travels in the file: class list, how descriptors are computed, the CRF graph, the
// weights, inference settings, and where the model came from and how well it did.
//
// File layout: the 16-byte magic "PRIMLABEL-MODEL\n", then a primlabel.v1.ModelEnvelope
// (proto/primlabel/v1/model.proto) holding the format version and a CRC-32 of the serialised
// primlabel.v1.Model. A file that is not a model, truncated, corrupt, from a newer format or
// inconsistent with itself is rejected with a ModelError naming the file and the reason.

#include <cstdint>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include "primlabel/crf/graph.hpp"
#include "primlabel/crf/inference.hpp"
#include "primlabel/crf/model.hpp"
#include "primlabel/geometry/features.hpp"

namespace primlabel {

inline constexpr std::uint32_t kModelFormatVersion = 1;

class ModelError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

enum class ModelKind { kCrf, kNodeOnly, kSvm };

// Further descriptor radii a model may ask for (each costs one more FPFH pass per cloud).
inline constexpr std::size_t kMaxExtraFeatureRadii = 4;
enum class DescriptorKind { kFpfh, kPfh };
// Shape evidence values a point (FeatureSettings::shape_evidence): one per taxonomy class but
// unknown, in taxonomy id order (column c is class id c + 1).
inline constexpr int kShapeEvidenceDim = 10;

// How a cloud is described before labeling; the labels are only meaningful for the same settings.
struct FeatureSettings {
  DescriptorKind descriptor = DescriptorKind::kFpfh;
  FpfhVariant fpfh_variant = FpfhVariant::kPcl;
  Neighborhood normals = Neighborhood::Radius(0.01f);
  Neighborhood features = Neighborhood::Radius(0.025f);
  float voxel_size = 0.0f;  // downsampling before features; 0 = none
  // > 0: FPFH neighbourhoods hold one point per voxel of this edge (every point is still
  // described, against the sample): fewer pairs per point on dense scans; 0 = every neighbour.
  float feature_sample_size = 0.0f;
  bool radii_overridable = false;  // whether a request may change the radii
  // Multi-scale model input (FPFH only): the same descriptor at these further radii (m), and,
  // with surface_variation_features, each point's surface variation (PCA smallest eigenvalue
  // over the sum) at the normal radius, the feature radius and every further radius. Clients
  // still get the descriptor at the feature radius; the CRF sees all of it (model_input_dim).
  std::vector<float> extra_feature_radii;
  bool surface_variation_features = false;
  // Shape evidence (pipeline/shape_evidence.hpp): the table-top stage's objects are fitted with
  // boxes and cylinders, and every point a fitted surface explains gets, as kShapeEvidenceDim
  // more input values, the class the taxonomy's rule gives it on that surface (hidden faces
  // included). The model learns how far to trust it; points of unfitted objects get zeros.
  bool shape_evidence = false;

  int descriptor_dim() const { return descriptor == DescriptorKind::kFpfh ? kFpfhSize : kPfhSize; }
  // Values per point from the descriptors: the descriptor at every radius, then the variations.
  int scale_input_dim() const {
    const int scales = 1 + static_cast<int>(extra_feature_radii.size());
    return descriptor_dim() * scales + (surface_variation_features ? scales + 1 : 0);
  }
  // Values per point the model weighs: the scale input, then the shape evidence.
  int model_input_dim() const {
    return scale_input_dim() + (shape_evidence ? kShapeEvidenceDim : 0);
  }
  bool multi_scale() const { return scale_input_dim() != descriptor_dim(); }
  // "fpfh", "fpfh_paper" or "pfh": the field name of these descriptors in written clouds.
  std::string descriptor_name() const {
    return descriptor == DescriptorKind::kPfh ? "pfh" : fpfh_field_name(fpfh_variant);
  }
};

struct ClassScore {
  double precision = 0, recall = 0, f1 = 0;
  std::uint64_t support = 0;
};

struct TrainingSummary {
  std::vector<std::string> sources;
  std::uint64_t scenes = 0, points = 0;
  std::vector<std::uint64_t> class_points;  // per model class
  std::string objective;
  double l2 = 0;
  std::uint32_t iterations = 0;
  double seconds = 0;
  // The least and greatest median point spacing (m) of the training scenes as described
  // (geometry/point_spacing.hpp); 0 in models trained before it was recorded.
  float point_spacing_min = 0, point_spacing_max = 0;
  // The greatest median surface variation of the training scenes' normals (a measure of their
  // range noise at the model's normal radius); 0 when not recorded.
  float surface_variation_max = 0;
  float surface_variation_min = 0;  // the least of the same; 0 when not recorded
  // The sensor of the training scans ("lms400", "kinect"; empty: not recorded) and, when every
  // training cloud was an organised frame of one size, that size (0 x 0 otherwise).
  std::string sensor;
  std::uint32_t image_width = 0, image_height = 0;
  // The ranges of the training scans' signatures as acquired (pipeline/cloud_signature.hpp: the
  // median point spacing and the roughness of small patches, m); 0 when not recorded.
  float acquired_spacing_min = 0, acquired_spacing_max = 0;
  float roughness_min = 0, roughness_max = 0;
  // The range of the noise growth exponent (geometry/cloud_signature.hpp); NaN: not recorded.
  float noise_growth_min = std::numeric_limits<float>::quiet_NaN();
  float noise_growth_max = std::numeric_limits<float>::quiet_NaN();
  // The range of the depth ties (geometry/cloud_signature.hpp: how quantised the depth is); NaN:
  // not recorded.
  float depth_ties_min = std::numeric_limits<float>::quiet_NaN();
  float depth_ties_max = std::numeric_limits<float>::quiet_NaN();
  // The class balance alpha of the objective (crf::class_balance_weights; 0 = unweighted, as in
  // older files) and the resulting weight per model class (empty when unweighted).
  double class_balance = 0;
  std::vector<double> class_weights;
  // Credit and licence of the training data (primlabel-train --attribution); empty: none given.
  std::string data_attribution;
};

struct EvaluationSummary {
  std::uint64_t points = 0;
  double accuracy = 0;
  std::vector<ClassScore> per_class;  // per model class
};

struct LabelModel {
  std::string name;
  std::string version;
  ModelKind kind = ModelKind::kCrf;
  FeatureSettings features;
  crf::GraphSettings graph;
  crf::CrfModel weights;  // kCrf, kNodeOnly (class_ids are the model's classes)
  // kSvm: libsvm's text model (svm::SvmClassifier::to_libsvm_text; its labels index
  // svm_class_ids), the classes, and weights.feature_scale as the SVM's feature scale.
  std::string svm_model;
  std::vector<std::uint32_t> svm_class_ids;
  crf::InferenceSettings inference;
  TrainingSummary training;
  EvaluationSummary validation;
  std::int64_t created_unix_ms = 0;
  std::string created_by;

  // Taxonomy ids of the classes this model predicts, in weight-row order.
  const std::vector<std::uint32_t>& class_ids() const {
    return kind == ModelKind::kSvm ? svm_class_ids : weights.class_ids;
  }
  // Throws ModelError (prefixed with `source`) when the parts do not fit together (for kSvm: when
  // the libsvm text does not parse or does not fit the classes and descriptor).
  void validate(const std::string& source = "model") const;
};

// Serialised file bytes, and back. `source` names the origin in error messages.
std::string serialize_model(const LabelModel& model);
LabelModel parse_model(const std::string& bytes, const std::string& source);

// Writes through atomic_write_file (temporary file, fsync, rename, directory fsync); reads with
// the checks above.
void save_model(const std::string& path, const LabelModel& model);
LabelModel load_model(const std::string& path);

}  // namespace primlabel
