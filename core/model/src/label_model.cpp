#include "primlabel/model/label_model.hpp"

#include <zlib.h>

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "primlabel/geometry/atomic_file.hpp"
#include "primlabel/geometry/taxonomy.hpp"
#include "primlabel/model/svm_baseline.hpp"
#include "primlabel/v1/model.pb.h"

namespace primlabel {

namespace {

constexpr char kMagic[] = "PRIMLABEL-MODEL\n";
constexpr std::size_t kMagicSize = sizeof(kMagic) - 1;

[[noreturn]] void fail(const std::string& source, const std::string& what) {
  throw ModelError(source + ": " + what);
}

std::uint32_t crc32_of(const std::string& bytes) {
  return static_cast<std::uint32_t>(
      crc32(0L, reinterpret_cast<const Bytef*>(bytes.data()), static_cast<uInt>(bytes.size())));
}

// ---- in-memory -> proto ----------------------------------------------------------------------

void to_proto(const Eigen::MatrixXf& m, v1::Matrix* out) {
  out->set_rows(static_cast<std::uint32_t>(m.rows()));
  out->set_cols(static_cast<std::uint32_t>(m.cols()));
  out->mutable_values()->Reserve(static_cast<int>(m.size()));
  for (Eigen::Index r = 0; r < m.rows(); ++r)
    for (Eigen::Index c = 0; c < m.cols(); ++c) out->add_values(m(r, c));
}

Eigen::MatrixXf from_proto(const v1::Matrix& m, const std::string& source, const char* what) {
  if (std::uint64_t(m.rows()) * m.cols() != std::uint64_t(m.values_size()))
    fail(source, std::string(what) + " holds " + std::to_string(m.values_size()) +
                     " values for a " + std::to_string(m.rows()) + "x" + std::to_string(m.cols()) +
                     " matrix");
  Eigen::MatrixXf out(m.rows(), m.cols());
  for (std::uint32_t r = 0; r < m.rows(); ++r)
    for (std::uint32_t c = 0; c < m.cols(); ++c) out(r, c) = m.values(int(r * m.cols() + c));
  return out;
}

v1::ModelKind to_proto(ModelKind kind) {
  switch (kind) {
    case ModelKind::kCrf:
      return v1::MODEL_KIND_CRF;
    case ModelKind::kNodeOnly:
      return v1::MODEL_KIND_NODE_ONLY;
    case ModelKind::kSvm:
      return v1::MODEL_KIND_SVM;
  }
  return v1::MODEL_KIND_UNSPECIFIED;
}

void set_neighborhood(const Neighborhood& hood, float* radius, std::uint32_t* k,
                      std::uint32_t* max_neighbors) {
  *radius = hood.radius;
  *k = static_cast<std::uint32_t>(hood.k);
  *max_neighbors = static_cast<std::uint32_t>(hood.max_neighbors);
}

Neighborhood neighborhood_from(float radius, std::uint32_t k, std::uint32_t max_neighbors,
                               const std::string& source, const char* what) {
  Neighborhood hood{radius, static_cast<int>(k), static_cast<int>(max_neighbors)};
  if (!hood.valid()) fail(source, std::string("invalid ") + what + " neighbourhood");
  return hood;
}

v1::Model to_proto(const LabelModel& m) {
  v1::Model out;
  out.set_name(m.name);
  out.set_version(m.version);
  out.set_kind(to_proto(m.kind));
  for (std::uint32_t id : m.class_ids()) {
    v1::PrimitiveClass* c = out.add_classes();
    c->set_id(id);
    if (const auto cls = class_from_id(id)) {
      c->set_name(std::string(primlabel::name(*cls)));
      c->set_rgb(color(*cls));
    }
  }
  v1::FeatureParameters* f = out.mutable_features();
  f->set_descriptor_kind(m.features.descriptor == DescriptorKind::kFpfh ? v1::DESCRIPTOR_FPFH
                                                                        : v1::DESCRIPTOR_PFH);
  f->set_fpfh_variant(m.features.fpfh_variant == FpfhVariant::kPcl
                          ? v1::FPFH_VARIANT_PCL
                          : v1::FPFH_VARIANT_WITH_OWN_SPFH);
  f->set_descriptor_dim(static_cast<std::uint32_t>(m.features.descriptor_dim()));
  float radius;
  std::uint32_t k, max_nn;
  set_neighborhood(m.features.normals, &radius, &k, &max_nn);
  f->set_normal_radius(radius), f->set_normal_k(k), f->set_normal_max_neighbors(max_nn);
  set_neighborhood(m.features.features, &radius, &k, &max_nn);
  f->set_feature_radius(radius), f->set_feature_k(k), f->set_max_neighbors(max_nn);
  f->set_voxel_size(m.features.voxel_size);
  f->set_feature_sample_size(m.features.feature_sample_size);
  f->set_radii_overridable(m.features.radii_overridable);
  for (float r : m.features.extra_feature_radii) f->add_extra_feature_radii(r);
  f->set_surface_variation_features(m.features.surface_variation_features);
  f->set_shape_evidence(m.features.shape_evidence);

  v1::GraphParameters* g = out.mutable_graph();
  set_neighborhood(m.graph.neighborhood, &radius, &k, &max_nn);
  g->set_radius(radius), g->set_k(k), g->set_max_neighbors(max_nn);

  if (m.kind == ModelKind::kSvm) {
    out.mutable_svm()->set_libsvm_model(m.svm_model);
    out.mutable_svm()->set_feature_scale(m.weights.feature_scale);
  } else {
    v1::LinearWeights* w = out.mutable_crf();
    to_proto(m.weights.node_weights, w->mutable_node_weights());
    if (m.kind == ModelKind::kCrf) to_proto(m.weights.edge_weights, w->mutable_edge_weights());
    w->set_feature_scale(m.weights.feature_scale);
    w->mutable_node_knots()->Assign(m.weights.node_knots.begin(), m.weights.node_knots.end());
  }

  v1::InferenceParameters* inf = out.mutable_inference();
  inf->set_method(m.inference.method == crf::InferenceMethod::kLoopyBp
                      ? v1::InferenceParameters::METHOD_LOOPY_BP
                      : v1::InferenceParameters::METHOD_MEAN_FIELD);
  inf->set_max_iterations(static_cast<std::uint32_t>(m.inference.max_iterations));
  inf->set_damping(m.inference.damping);
  inf->set_tolerance(m.inference.tolerance);
  inf->set_max_product(m.inference.max_product);

  v1::TrainingSummary* t = out.mutable_training();
  for (const auto& s : m.training.sources) t->add_sources(s);
  t->set_scenes(m.training.scenes), t->set_points(m.training.points);
  for (auto c : m.training.class_points) t->add_class_points(c);
  t->set_objective(m.training.objective), t->set_l2(m.training.l2);
  t->set_iterations(m.training.iterations), t->set_seconds(m.training.seconds);
  t->set_point_spacing_min(m.training.point_spacing_min);
  t->set_point_spacing_max(m.training.point_spacing_max);
  t->set_surface_variation_max(m.training.surface_variation_max);
  t->set_surface_variation_min(m.training.surface_variation_min);
  t->set_sensor(m.training.sensor);
  t->set_image_width(m.training.image_width), t->set_image_height(m.training.image_height);
  t->set_acquired_spacing_min(m.training.acquired_spacing_min);
  t->set_acquired_spacing_max(m.training.acquired_spacing_max);
  t->set_roughness_min(m.training.roughness_min), t->set_roughness_max(m.training.roughness_max);
  if (std::isfinite(m.training.noise_growth_min) && std::isfinite(m.training.noise_growth_max)) {
    t->set_noise_growth_min(m.training.noise_growth_min);
    t->set_noise_growth_max(m.training.noise_growth_max);
  }
  if (std::isfinite(m.training.depth_ties_min) && std::isfinite(m.training.depth_ties_max)) {
    t->set_depth_ties_min(m.training.depth_ties_min);
    t->set_depth_ties_max(m.training.depth_ties_max);
  }
  t->set_class_balance(m.training.class_balance);
  for (double w : m.training.class_weights) t->add_class_weights(w);
  t->set_data_attribution(m.training.data_attribution);

  v1::Evaluation* e = out.mutable_validation();
  e->set_points(m.validation.points), e->set_accuracy(m.validation.accuracy);
  for (const ClassScore& c : m.validation.per_class) {
    v1::ClassScores* s = e->add_per_class();
    s->set_precision(c.precision), s->set_recall(c.recall), s->set_f1(c.f1);
    s->set_support(c.support);
  }
  out.set_created_unix_ms(m.created_unix_ms);
  out.set_created_by(m.created_by);
  return out;
}

// ---- proto -> in-memory ----------------------------------------------------------------------

LabelModel from_proto(const v1::Model& in, const std::string& source) {
  LabelModel m;
  m.name = in.name();
  m.version = in.version();
  switch (in.kind()) {
    case v1::MODEL_KIND_CRF:
      m.kind = ModelKind::kCrf;
      break;
    case v1::MODEL_KIND_NODE_ONLY:
      m.kind = ModelKind::kNodeOnly;
      break;
    case v1::MODEL_KIND_SVM:
      m.kind = ModelKind::kSvm;
      break;
    default:
      fail(source, "unknown model kind " + std::to_string(int(in.kind())));
  }
  std::vector<std::uint32_t> ids;
  for (const auto& c : in.classes()) ids.push_back(c.id());

  const v1::FeatureParameters& f = in.features();
  switch (f.descriptor_kind()) {
    case v1::DESCRIPTOR_FPFH:
      m.features.descriptor = DescriptorKind::kFpfh;
      break;
    case v1::DESCRIPTOR_PFH:
      m.features.descriptor = DescriptorKind::kPfh;
      break;
    default:
      fail(source, "unknown descriptor kind " + std::to_string(int(f.descriptor_kind())));
  }
  m.features.fpfh_variant = f.fpfh_variant() == v1::FPFH_VARIANT_WITH_OWN_SPFH
                                ? FpfhVariant::kWithOwnSpfh
                                : FpfhVariant::kPcl;
  if (f.descriptor_dim() != std::uint32_t(m.features.descriptor_dim()))
    fail(source, "descriptor_dim " + std::to_string(f.descriptor_dim()) + " does not match the " +
                     "descriptor kind (" + std::to_string(m.features.descriptor_dim()) + ")");
  m.features.normals = neighborhood_from(f.normal_radius(), f.normal_k(), f.normal_max_neighbors(),
                                         source, "normal");
  m.features.features =
      neighborhood_from(f.feature_radius(), f.feature_k(), f.max_neighbors(), source, "feature");
  m.features.voxel_size = f.voxel_size();
  m.features.feature_sample_size = f.feature_sample_size();
  if (!(m.features.feature_sample_size >= 0.0f) || !std::isfinite(m.features.feature_sample_size))
    fail(source, "feature_sample_size must be finite and >= 0");
  m.features.radii_overridable = f.radii_overridable();
  m.features.extra_feature_radii.assign(f.extra_feature_radii().begin(),
                                        f.extra_feature_radii().end());
  m.features.surface_variation_features = f.surface_variation_features();
  m.features.shape_evidence = f.shape_evidence();
  if (m.features.extra_feature_radii.size() > kMaxExtraFeatureRadii)
    fail(source, "more than " + std::to_string(kMaxExtraFeatureRadii) + " extra feature radii");
  for (float r : m.features.extra_feature_radii)
    if (!(r > 0.0f) || !std::isfinite(r)) fail(source, "an extra feature radius is not > 0");
  if (m.features.multi_scale() && m.features.descriptor != DescriptorKind::kFpfh)
    fail(source, "multi-scale features need the FPFH descriptor");

  const v1::GraphParameters& g = in.graph();
  m.graph.neighborhood = neighborhood_from(g.radius(), g.k(), g.max_neighbors(), source, "graph");

  if (m.kind == ModelKind::kSvm) {
    if (!in.has_svm()) fail(source, "an SVM model without SVM weights");
    m.svm_model = in.svm().libsvm_model();
    m.svm_class_ids = ids;
    m.weights.feature_scale = in.svm().feature_scale();
    m.weights.class_ids = ids;
    m.weights.descriptor_dim = m.features.model_input_dim();
  } else {
    if (!in.has_crf()) fail(source, "a CRF model without weights");
    m.weights.class_ids = ids;
    m.weights.descriptor_dim = m.features.model_input_dim();
    m.weights.feature_scale = in.crf().feature_scale();
    m.weights.node_knots.assign(in.crf().node_knots().begin(), in.crf().node_knots().end());
    m.weights.node_weights = from_proto(in.crf().node_weights(), source, "node weights");
    m.weights.edge_weights =
        m.kind == ModelKind::kCrf
            ? from_proto(in.crf().edge_weights(), source, "edge weights")
            : Eigen::MatrixXf::Zero(m.weights.node_weights.rows(), m.weights.edge_feature_dim());
  }

  const v1::InferenceParameters& inf = in.inference();
  m.inference.method = inf.method() == v1::InferenceParameters::METHOD_MEAN_FIELD
                           ? crf::InferenceMethod::kMeanField
                           : crf::InferenceMethod::kLoopyBp;
  if (inf.max_iterations() > 0) m.inference.max_iterations = int(inf.max_iterations());
  m.inference.damping = inf.damping();
  if (inf.tolerance() > 0) m.inference.tolerance = inf.tolerance();
  m.inference.max_product = inf.max_product();

  const v1::TrainingSummary& t = in.training();
  m.training.sources.assign(t.sources().begin(), t.sources().end());
  m.training.scenes = t.scenes(), m.training.points = t.points();
  m.training.class_points.assign(t.class_points().begin(), t.class_points().end());
  m.training.objective = t.objective(), m.training.l2 = t.l2();
  m.training.iterations = t.iterations(), m.training.seconds = t.seconds();
  m.training.point_spacing_min = t.point_spacing_min();
  m.training.point_spacing_max = t.point_spacing_max();
  m.training.surface_variation_max = t.surface_variation_max();
  m.training.surface_variation_min = t.surface_variation_min();
  m.training.sensor = t.sensor();
  m.training.image_width = t.image_width(), m.training.image_height = t.image_height();
  m.training.acquired_spacing_min = t.acquired_spacing_min();
  m.training.acquired_spacing_max = t.acquired_spacing_max();
  m.training.roughness_min = t.roughness_min(), m.training.roughness_max = t.roughness_max();
  if (t.has_noise_growth_min() && t.has_noise_growth_max()) {
    m.training.noise_growth_min = t.noise_growth_min();
    m.training.noise_growth_max = t.noise_growth_max();
  }
  if (t.has_depth_ties_min() && t.has_depth_ties_max()) {
    m.training.depth_ties_min = t.depth_ties_min();
    m.training.depth_ties_max = t.depth_ties_max();
  }
  m.training.class_balance = t.class_balance();
  m.training.class_weights.assign(t.class_weights().begin(), t.class_weights().end());
  m.training.data_attribution = t.data_attribution();

  const v1::Evaluation& e = in.validation();
  m.validation.points = e.points(), m.validation.accuracy = e.accuracy();
  for (const auto& s : e.per_class())
    m.validation.per_class.push_back({s.precision(), s.recall(), s.f1(), s.support()});
  m.created_unix_ms = in.created_unix_ms();
  m.created_by = in.created_by();
  m.validate(source);
  return m;
}

}  // namespace

void LabelModel::validate(const std::string& source) const {
  const auto& ids = class_ids();
  if (ids.empty()) fail(source, "the model has no classes");
  for (std::uint32_t id : ids)
    if (!class_from_id(id))
      fail(source, "class id " + std::to_string(id) + " is not in the taxonomy");
  if (kind == ModelKind::kSvm) {
    if (svm_model.empty()) fail(source, "the SVM model is empty");
    try {
      svm::SvmClassifier::from_libsvm_text(svm_model, svm_class_ids, features.model_input_dim(),
                                           weights.feature_scale);
    } catch (const std::invalid_argument& e) {
      fail(source, std::string("SVM model: ") + e.what());
    }
    return;
  }
  if (weights.descriptor_dim != features.model_input_dim())
    fail(source, "weights are for " + std::to_string(weights.descriptor_dim) +
                     "-value descriptors but the features give " +
                     std::to_string(features.model_input_dim()));
  try {
    weights.validate();
  } catch (const std::invalid_argument& e) {
    fail(source, e.what());
  }
}

std::string serialize_model(const LabelModel& model) {
  model.validate("serialize_model");
  v1::ModelEnvelope envelope;
  envelope.set_format_version(kModelFormatVersion);
  envelope.set_model(to_proto(model).SerializeAsString());
  envelope.set_model_crc32(crc32_of(envelope.model()));
  return std::string(kMagic, kMagicSize) + envelope.SerializeAsString();
}

LabelModel parse_model(const std::string& bytes, const std::string& source) {
  if (bytes.size() < kMagicSize || bytes.compare(0, kMagicSize, kMagic) != 0)
    fail(source, "not a primlabel model file (no PRIMLABEL-MODEL header)");
  v1::ModelEnvelope envelope;
  if (!envelope.ParseFromArray(bytes.data() + kMagicSize, int(bytes.size() - kMagicSize)))
    fail(source, "corrupt or truncated model file (the envelope does not parse)");
  if (envelope.format_version() == 0) fail(source, "model file without a format version");
  if (envelope.format_version() > kModelFormatVersion)
    fail(source, "model format version " + std::to_string(envelope.format_version()) +
                     " is newer than this build reads (" + std::to_string(kModelFormatVersion) +
                     ")");
  if (crc32_of(envelope.model()) != envelope.model_crc32())
    fail(source, "checksum mismatch: the model file is corrupt");
  v1::Model model;
  if (!model.ParseFromString(envelope.model())) fail(source, "corrupt model payload");
  return from_proto(model, source);
}

void save_model(const std::string& path, const LabelModel& model) {
  const std::string bytes = serialize_model(model);
  try {
    atomic_write_file(path, bytes);
  } catch (const AtomicWriteError& e) {
    throw ModelError(std::string("cannot write the model file: ") + e.what());
  }
}

LabelModel load_model(const std::string& path) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) fail(path, "no such model file");
  const auto size = std::filesystem::file_size(path, ec);
  if (ec) fail(path, "cannot read (" + ec.message() + ")");
  if (size > (std::uintmax_t(1) << 30)) fail(path, "larger than 1 GiB: not a model file");
  std::ifstream in(path, std::ios::binary);
  if (!in) fail(path, "cannot open (" + std::string(std::strerror(errno)) + ")");
  std::string bytes(static_cast<std::size_t>(size), '\0');
  in.read(bytes.data(), std::streamsize(size));
  if (!in) fail(path, "read failed");
  return parse_model(bytes, path);
}

}  // namespace primlabel
