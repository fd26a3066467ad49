#pragma once
// The point cloud every stage of primlabel reads and writes.
//
// Structure of arrays: xyz is always present; every other attribute is either empty (absent) or
// holds exactly one entry per point. Organised clouds (height > 1, e.g. a 640x480 depth frame)
// keep invalid pixels as points whose coordinates are NaN, so indices stay pixel indices.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace primlabel {

using Vec3f = Eigen::Vector3f;

// Sensor acquisition pose, as in the PCD VIEWPOINT header (translation + orientation quaternion).
struct Viewpoint {
  Vec3f origin = Vec3f::Zero();
  Eigen::Quaternionf orientation = Eigen::Quaternionf::Identity();
};

// A per-point float attribute with `count` values per point (e.g. "fpfh" with count 33, or an
// "intensity" field read from a file). Values are stored point-major: point i owns
// values[i*count .. i*count+count).
struct FloatField {
  std::string name;
  int count = 1;
  std::vector<float> values;

  const float* row(std::size_t point) const { return values.data() + point * count; }
  float* row(std::size_t point) { return values.data() + point * count; }
};

struct PointCloud {
  std::vector<Vec3f> xyz;
  std::vector<Vec3f> normals;         // NaN where a normal could not be estimated
  std::vector<float> curvature;       // surface variation lambda0 / (lambda0 + lambda1 + lambda2)
  std::vector<std::uint32_t> labels;  // integer class / segment labels
  std::vector<std::uint32_t> rgba;    // packed 0xAARRGGBB as PCL stores rgb/rgba
  std::vector<FloatField> fields;     // descriptors and any other float attributes

  std::uint32_t width = 0;   // points per row; equals size() when height == 1
  std::uint32_t height = 1;  // rows; > 1 means organised
  Viewpoint viewpoint;

  std::size_t size() const { return xyz.size(); }
  bool empty() const { return xyz.empty(); }
  bool organized() const { return height > 1; }
  bool has_normals() const { return !normals.empty(); }
  bool has_curvature() const { return !curvature.empty(); }
  bool has_labels() const { return !labels.empty(); }
  bool has_rgba() const { return !rgba.empty(); }

  // Resizes xyz to n points, as one unorganised row; clears every optional attribute.
  void resize_unorganized(std::size_t n) {
    *this = PointCloud{};
    xyz.resize(n);
    width = static_cast<std::uint32_t>(n);
    height = 1;
  }

  const FloatField* find_field(const std::string& name) const {
    for (const auto& f : fields)
      if (f.name == name) return &f;
    return nullptr;
  }
  FloatField* find_field(const std::string& name) {
    for (auto& f : fields)
      if (f.name == name) return &f;
    return nullptr;
  }
  // Returns the field `name`, creating (or reshaping) it with `count` values per point.
  FloatField& set_field(const std::string& name, int count) {
    FloatField* f = find_field(name);
    if (!f) {
      fields.push_back(FloatField{name, count, {}});
      f = &fields.back();
    }
    f->count = count;
    f->values.assign(size() * static_cast<std::size_t>(count), 0.0f);
    return *f;
  }
};

inline bool is_finite(const Vec3f& p) {
  return std::isfinite(p.x()) && std::isfinite(p.y()) && std::isfinite(p.z());
}

// Number of points with finite coordinates.
inline std::size_t count_finite(const PointCloud& cloud) {
  std::size_t n = 0;
  for (const auto& p : cloud.xyz) n += is_finite(p) ? 1 : 0;
  return n;
}

}  // namespace primlabel
