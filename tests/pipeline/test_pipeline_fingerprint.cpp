// The check clouds: what label_cloud answers on a fixed set of clouds and models, as a digest per
// part (labels, probabilities, descriptors, normals, primitives, objects), compared with the
// digests in tests/data/fingerprints/labeling.txt. A restructuring of the pipeline or the service
// must leave every part bit-identical; a change meant to alter results regenerates the file:
//
//   PRIMLABEL_WRITE_FINGERPRINTS=tests/data/fingerprints/labeling.txt build/bin/test_pipeline_fingerprint
//
// The cases cover every path a cloud takes through labeling: exact duplicates and non-finite
// points, voxel downsampling, the table-top stage with objects, multi-scale model input, a CRF
// with edges, an SVM, the cloud's own normals and overridden radii. Cases on the real Kinect
// scene are skipped when ../shared/data is absent.

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <map>
#include <sstream>
#include <string>
#include <type_traits>
#include <vector>

#include "primlabel/geometry/cloud_io.hpp"
#include "primlabel/pipeline/labeling.hpp"
#include "primlabel/synth/generate.hpp"
#include "random_label_model.hpp"
#include "small_svm_model.hpp"
#include "test_util.hpp"

namespace primlabel::pipeline {
namespace {

// FNV-1a over the bytes of plain values, in order.
class Digest {
 public:
  template <typename T>
  void add(const T& value) {
    static_assert(std::is_trivially_copyable_v<T>);
    unsigned char bytes[sizeof(T)];
    std::memcpy(bytes, &value, sizeof(T));
    for (unsigned char b : bytes) hash_ = (hash_ ^ b) * 1099511628211ull;
  }
  template <typename T>
  void add_all(const std::vector<T>& values) {
    add(values.size());
    for (const T& v : values) add(v);
  }
  void add_vector(const Eigen::Vector3d& v) {
    for (int i = 0; i < 3; ++i) add(v[i]);
  }
  std::string hex() const {
    std::ostringstream out;
    out << std::hex << hash_;
    return out.str();
  }

 private:
  std::uint64_t hash_ = 14695981039346656037ull;
};

void add_model(Digest& d, const primitives::Model& model) {
  d.add(std::uint32_t(model.index()));
  std::visit(
      [&](const auto& m) {
        using M = std::decay_t<decltype(m)>;
        if constexpr (std::is_same_v<M, primitives::PlaneModel>) {
          d.add_vector(m.normal), d.add(m.offset), d.add_vector(m.center);
          d.add_vector(m.axis_u), d.add_vector(m.axis_v), d.add(m.extent_u), d.add(m.extent_v);
        } else if constexpr (std::is_same_v<M, primitives::CylinderModel>) {
          d.add_vector(m.center), d.add_vector(m.axis), d.add(m.radius), d.add(m.height);
        } else if constexpr (std::is_same_v<M, primitives::SphereModel>) {
          d.add_vector(m.center), d.add(m.radius);
        } else if constexpr (std::is_same_v<M, primitives::TorusModel>) {
          d.add_vector(m.center), d.add_vector(m.axis), d.add(m.major_radius);
          d.add(m.minor_radius);
        } else if constexpr (std::is_same_v<M, primitives::LineModel>) {
          d.add_vector(m.center), d.add_vector(m.direction), d.add(m.length);
        }
      },
      model);
}

using Parts = std::map<std::string, std::string>;

Parts fingerprint(const LabelingResult& result, const PointCloud& cloud) {
  Parts parts;
  Digest labels;
  labels.add_all(result.labels);
  labels.add_all(result.class_ids);
  labels.add(result.labeled_points), labels.add(result.described_points);
  parts["labels"] = labels.hex();
  if (result.probabilities.size() > 0) {
    Digest p;
    p.add(result.probabilities.rows()), p.add(result.probabilities.cols());
    for (Eigen::Index i = 0; i < result.probabilities.size(); ++i) p.add(result.probabilities(i));
    parts["probabilities"] = p.hex();
  }
  if (result.descriptors.size() > 0) {
    Digest p;
    p.add(result.descriptors.dim);
    p.add_all(result.descriptors.values);
    parts["descriptors"] = p.hex();
  }
  Digest normals;
  for (const Vec3f& n : cloud.normals) normals.add(n.x()), normals.add(n.y()), normals.add(n.z());
  parts["normals"] = normals.hex();
  if (result.primitives) {
    Digest p;
    p.add_all(result.primitives->point_segment);
    for (const primitives::Primitive& s : result.primitives->primitives) {
      p.add(s.class_id), p.add(s.points), p.add(s.first_point), p.add(s.inliers), p.add(s.rms);
      p.add(s.confidence), p.add_vector(s.centroid), p.add_vector(s.bounds_min);
      p.add_vector(s.bounds_max);
      add_model(p, s.model);
    }
    parts["primitives"] = p.hex();
  }
  if (result.objects) {
    Digest p;
    const tabletop::TabletopObjects& objects = *result.objects;
    p.add_all(objects.point_object);
    p.add(bool(objects.table));
    if (objects.table) {
      for (int i = 0; i < 4; ++i) p.add(objects.table->plane[i]);
      for (const Vec3f& v : objects.table->hull) p.add(v.x()), p.add(v.y()), p.add(v.z());
      p.add(objects.table->points);
      p.add_all(objects.table->primitive_ids);
    }
    for (const tabletop::TabletopObject& o : objects.objects) {
      p.add(o.id), p.add(o.points), p.add_vector(o.centroid), p.add_vector(o.bounds_min);
      p.add_vector(o.bounds_max), p.add(o.height);
      p.add_all(o.primitive_ids);
    }
    parts["objects"] = p.hex();
  }
  return parts;
}

// The box on a table with every 7th point repeated and a few non-finite points among them.
PointCloud box_with_duplicates_and_holes() {
  PointCloud cloud = testing::table_with_box_cloud(0.006f);
  const std::size_t n = cloud.size();
  for (std::size_t i = 0; i < n; i += 7) cloud.xyz.push_back(cloud.xyz[i]);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  for (std::size_t i = 0; i < cloud.xyz.size(); i += 101) cloud.xyz[i] = Vec3f(nan, 0, nan);
  cloud.width = std::uint32_t(cloud.xyz.size());
  cloud.height = 1;
  cloud.labels.clear();
  return cloud;
}

PointCloud lms400_scene() {
  return synth::synthetic_scene(synth::SceneSet::kTest, 1, synth::SensorKind::kLms400);
}

PointCloud kinect_scene() {
  return synth::synthetic_scene(synth::SceneSet::kTest, 2, synth::SensorKind::kKinect);
}

LabelModel multi_scale_model() {
  LabelModel model = testing::random_label_model("multi", "1", 11, 0.4f);
  model.features.extra_feature_radii = {0.015f, 0.045f};
  model.features.surface_variation_features = true;
  model.weights = crf::CrfModel::zeros({1, 2, 4, 5, 6}, model.features.model_input_dim());
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> uniform(-1.0f, 1.0f);
  for (Eigen::Index i = 0; i < model.weights.node_weights.size(); ++i)
    model.weights.node_weights(i) = uniform(rng);
  model.weights.edge_weights.col(model.weights.edge_feature_dim() - 1).setConstant(0.4f);
  return model;
}

struct Case {
  std::string name;
  std::function<LabelModel()> model;
  std::function<PointCloud()> cloud;
  LabelingOptions options;
  bool needs_shared_data = false;
};

std::vector<Case> check_cases() {
  std::vector<Case> cases;
  LabelingOptions everything;
  everything.want_probabilities = true;
  everything.want_descriptors = true;
  everything.want_primitives = true;
  everything.primitives.segments.radius = 0.012f;

  cases.push_back({"duplicates_nan_crf", [] { return testing::random_label_model("r", "1", 5, 0.5f); },
                   box_with_duplicates_and_holes, everything});
  LabelingOptions voxels = everything;
  voxels.voxel_size = 0.01f;
  cases.push_back({"duplicates_nan_voxels", [] { return testing::random_label_model("r", "1", 5, 0.5f); },
                   box_with_duplicates_and_holes, voxels});
  cases.push_back({"lms400_node_only", [] { return testing::random_label_model("r", "1", 9); },
                   lms400_scene, everything});
  LabelingOptions radii = everything;
  radii.want_primitives = false;
  radii.normal_radius = 0.012f;
  radii.feature_radius = 0.02f;
  radii.share_neighbor_lists = false;
  cases.push_back({"lms400_radii_unshared",
                   [] {
                     LabelModel m = testing::random_label_model("r", "1", 9);
                     m.features.radii_overridable = true;
                     return m;
                   },
                   lms400_scene, radii});
  cases.push_back({"lms400_svm", [] { return testing::train_small_svm_model(); }, lms400_scene,
                   everything});
  LabelingOptions tabletop = everything;
  tabletop.tabletop_only = true;
  tabletop.want_objects = true;
  cases.push_back({"kinect_tabletop_objects_multi_scale", multi_scale_model, kinect_scene, tabletop});
  LabelingOptions tabletop_voxels = tabletop;
  tabletop_voxels.voxel_size = 0.008f;
  cases.push_back({"kinect_tabletop_voxels_multi_scale", multi_scale_model, kinect_scene,
                   tabletop_voxels});
  LabelingOptions own_normals;
  own_normals.use_cloud_normals = true;
  own_normals.want_probabilities = true;
  cases.push_back({"kinect_own_normals",
                   [] { return testing::random_label_model("r", "1", 3, 0.3f); },
                   [] {
                     PointCloud cloud = kinect_scene();
                     PointCloud with_normals = cloud;
                     describe_cloud(with_normals, testing::random_label_model().features,
                                    RunContext{1});
                     cloud.normals = with_normals.normals;
                     return cloud;
                   },
                   own_normals});
  LabelingOptions real = tabletop;
  real.voxel_size = 0.006f;
  cases.push_back({"mosd_learn3_tabletop_voxels", multi_scale_model,
                   [] { return read_pcd(test::shared_data("mosd/learn3.pcd")); }, real, true});
  return cases;
}

std::map<std::string, Parts> read_expected(const std::string& path) {
  std::map<std::string, Parts> expected;
  std::ifstream in(path);
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream fields(line);
    std::string name, part, digest;
    fields >> name >> part >> digest;
    expected[name][part] = digest;
  }
  return expected;
}

TEST(PipelineFingerprint, EveryPartOfEveryCheckCloudIsBitIdentical) {
  const std::map<std::string, Parts> expected =
      read_expected(test::test_data("fingerprints/labeling.txt"));
  const char* write_path = std::getenv("PRIMLABEL_WRITE_FINGERPRINTS");
  std::ostringstream written;
  written << "# label_cloud's answer on the check clouds, a FNV-1a digest per part\n"
          << "# (tests/pipeline/test_pipeline_fingerprint.cpp says how to regenerate it).\n";
  for (const Case& c : check_cases()) {
    SCOPED_TRACE(c.name);
    if (c.needs_shared_data &&
        !std::filesystem::exists(test::shared_data("mosd/learn3.pcd"))) {
      // Keep the stored digests of a case this machine cannot run.
      for (const auto& [part, digest] : expected.count(c.name) ? expected.at(c.name) : Parts{})
        written << c.name << ' ' << part << ' ' << digest << '\n';
      continue;
    }
    const LabelModel model = c.model();
    PointCloud cloud = c.cloud();
    // Two threads: the results must not depend on the count, so one digest serves every machine.
    const LabelingResult result = label_cloud(model, cloud, c.options, RunContext{2});
    const Parts parts = fingerprint(result, cloud);
    for (const auto& [part, digest] : parts) written << c.name << ' ' << part << ' ' << digest << '\n';
    if (write_path) continue;
    ASSERT_TRUE(expected.count(c.name)) << "no stored digests for this case";
    EXPECT_EQ(parts, expected.at(c.name));
  }
  if (write_path) {
    std::ofstream(write_path) << written.str();
    GTEST_SKIP() << "wrote " << write_path;
  }
}

}  // namespace
}  // namespace primlabel::pipeline
