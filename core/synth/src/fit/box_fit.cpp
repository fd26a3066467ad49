// The box model of a segment: up to three mutually orthogonal faces, each an MSAC plane refined
// by least squares (tabletop::fit_plane), the box frame from their normals, each face's offset
// the least-squares one along its axis and the unseen sides at the extent of the points.

#include <Eigen/Eigenvalues>
#include <cmath>

#include "primlabel/tabletop/plane_fit.hpp"
#include "shape_fit.hpp"

namespace primlabel::synth::fit {
namespace {

constexpr double kDeg = M_PI / 180.0;
const double kOrthogonal = std::sin(12 * kDeg);  // |cos| below: faces at right angles
const double kLevel = std::cos(12 * kDeg);       // |n.z| above: a horizontal face
const double kNormalAgrees = std::cos(30 * kDeg);

struct Face {
  Vec3d normal;  // toward the sensor, i.e. out of the box
  std::vector<std::uint32_t> points;
};

// Main in-plane direction (largest-eigenvalue eigenvector of the covariance) of points[idx]
// projected onto the plane with normal `normal`.
Vec3d principal_direction(const std::vector<Vec3d>& points, const std::vector<std::uint32_t>& idx,
                          const Vec3d& normal) {
  Vec3d mean = Vec3d::Zero();
  for (auto i : idx) mean += points[i];
  mean /= double(std::max<std::size_t>(idx.size(), 1));
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (auto i : idx) {
    Vec3d d = points[i] - mean;
    d -= d.dot(normal) * normal;
    cov += d * d.transpose();
  }
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(cov);
  Vec3d dir = eig.eigenvectors().col(2);
  dir -= dir.dot(normal) * normal;
  return dir.norm() > 1e-9 ? dir.normalized() : normal.unitOrthogonal();
}

std::vector<Face> find_faces(const SegmentPoints& s, const FitSettings& settings) {
  std::vector<Vec3f> points(s.p.size());
  for (std::size_t i = 0; i < s.p.size(); ++i) points[i] = s.p[i].cast<float>();
  std::vector<std::uint32_t> remaining(s.p.size());
  for (std::uint32_t i = 0; i < remaining.size(); ++i) remaining[i] = i;
  const std::size_t min_face = std::max<std::size_t>(20, s.p.size() / 30);

  tabletop::PlaneFitOptions options;
  options.distance_threshold = static_cast<float>(quantile(s.bound, 0.5));
  options.min_inliers = min_face;
  options.max_iterations = 500;
  std::vector<Face> faces;
  for (int attempt = 0; attempt < 6 && faces.size() < 3 && remaining.size() >= min_face;
       ++attempt) {
    options.seed = settings.seed + static_cast<std::uint64_t>(attempt);
    const tabletop::PlaneFit fit = tabletop::fit_plane(points, remaining, options);
    if (fit.status != tabletop::PlaneFitStatus::kOk) break;
    Face face;
    face.normal = fit.plane.head<3>().cast<double>().normalized();
    Vec3d centroid = Vec3d::Zero();
    for (auto i : fit.inliers) centroid += s.p[i];
    centroid /= double(fit.inliers.size());
    if (face.normal.dot(s.viewpoint - centroid) < 0) face.normal = -face.normal;
    // A plane through one face also cuts a strip of the others: keep the points facing its way.
    for (auto i : fit.inliers)
      if (std::isfinite(s.n[i].x()) && std::abs(s.n[i].dot(face.normal)) > kNormalAgrees)
        face.points.push_back(i);
    // Its points leave the pool either way, so the next hypothesis sees the rest.
    std::vector<std::uint32_t> rest;
    std::set_difference(remaining.begin(), remaining.end(), fit.inliers.begin(), fit.inliers.end(),
                        std::back_inserter(rest));
    remaining.swap(rest);
    if (face.points.size() < min_face) continue;
    bool orthogonal = true;
    for (const Face& other : faces)
      orthogonal = orthogonal && std::abs(other.normal.dot(face.normal)) < kOrthogonal;
    if (orthogonal) faces.push_back(std::move(face));
  }
  return faces;
}

}  // namespace

std::optional<FittedObject> fit_box(const SegmentPoints& s, const FitSettings& settings) {
  const std::vector<Face> faces = find_faces(s, settings);
  if (faces.empty()) return std::nullopt;

  const Vec3d up = Vec3d::UnitZ();
  bool level = true;  // every face horizontal or vertical
  for (const Face& f : faces)
    level = level && (std::abs(f.normal.z()) > kLevel || std::abs(f.normal.z()) < kOrthogonal);
  std::vector<double> heights(s.p.size());
  for (std::size_t i = 0; i < s.p.size(); ++i) heights[i] = s.p[i].z();
  const bool on_table = level && quantile(heights, 0.01) < settings.contact_tolerance;

  Eigen::Matrix3d axes;
  if (level) {  // z up; x along a side face's normal, else along the top's main direction
    Vec3d x = Vec3d::Zero();
    for (const Face& f : faces)
      if (std::abs(f.normal.z()) < kOrthogonal) {
        x = Vec3d(f.normal.x(), f.normal.y(), 0).normalized();
        break;
      }
    if (x.isZero()) x = principal_direction(s.p, faces.front().points, up);
    axes << x, up.cross(x), up;
  } else {  // a tilted box: its axes from the faces, the one nearest up as z
    Vec3d a = faces[0].normal;
    Vec3d b = faces.size() > 1 ? faces[1].normal : principal_direction(s.p, faces[0].points, a);
    b = (b - b.dot(a) * a).normalized();
    Eigen::Matrix3d m;
    m << a, b, a.cross(b);
    int z = 0;
    for (int k = 1; k < 3; ++k)
      if (std::abs(m.col(k).z()) > std::abs(m.col(z).z())) z = k;
    const Vec3d zc = m.col(z).z() < 0 ? Vec3d(-m.col(z)) : Vec3d(m.col(z));
    const Vec3d xc = m.col((z + 1) % 3);
    axes << xc, zc.cross(xc), zc;
  }

  // Extent along each axis: a seen face fixes its side (least-squares offset of its points),
  // the points' extent the unseen one.
  Vec3d lo, hi;
  for (int k = 0; k < 3; ++k) {
    std::vector<double> proj(s.p.size());
    for (std::size_t i = 0; i < s.p.size(); ++i) proj[i] = axes.col(k).dot(s.p[i]);
    lo[k] = quantile(proj, 0.005);
    hi[k] = quantile(proj, 0.995);
    for (const Face& f : faces) {
      const double c = f.normal.dot(axes.col(k));
      if (std::abs(c) < kLevel) continue;
      double offset = 0;
      for (auto i : f.points) offset += axes.col(k).dot(s.p[i]);
      offset /= double(f.points.size());
      (c > 0 ? hi[k] : lo[k]) = offset;
    }
  }
  if (on_table) lo.z() = 0;  // the bottom on the table plane
  FittedObject box;
  box.kind = FittedKind::kBox;
  box.on_table = on_table;
  box.faces = static_cast<int>(faces.size());
  box.size = (hi - lo).cwiseMax(0.005);
  const Vec3d origin_local(0.5 * (lo.x() + hi.x()), 0.5 * (lo.y() + hi.y()), lo.z());
  box.table_from_local = Eigen::Isometry3d::Identity();
  box.table_from_local.linear() = axes;
  box.table_from_local.translation() = axes * origin_local;
  return box;
}

}  // namespace primlabel::synth::fit
