// Instance matching of fitted primitives against the true ones (see primitive_matching.hpp).

#include "primitive_matching.hpp"

#include <algorithm>
#include <cmath>
#include <map>

namespace primlabel::bench {
namespace {

using primitives::PrimitiveKind;
using Vec3d = Eigen::Vector3d;

bool scored_kind(PrimitiveKind kind) {
  return kind == PrimitiveKind::kPlane || kind == PrimitiveKind::kCylinder ||
         kind == PrimitiveKind::kSphere || kind == PrimitiveKind::kTorus;
}

// The parameter errors of a detection against the true primitive it lies on (same kind).
MatchedPair errors(const primitives::Model& fitted, const primitives::Model& true_model) {
  MatchedPair pair;
  if (const auto* c = std::get_if<primitives::CylinderModel>(&fitted)) {
    const auto& t = std::get<primitives::CylinderModel>(true_model);
    pair.radius_error = std::abs(c->radius - t.radius);
    pair.axis_error_deg = axis_angle_deg(c->axis, t.axis);
  } else if (const auto* s = std::get_if<primitives::SphereModel>(&fitted)) {
    pair.radius_error = std::abs(s->radius - std::get<primitives::SphereModel>(true_model).radius);
  } else if (const auto* r = std::get_if<primitives::TorusModel>(&fitted)) {
    const auto& t = std::get<primitives::TorusModel>(true_model);
    pair.radius_error = std::abs(r->major_radius - t.major_radius);
    pair.axis_error_deg = axis_angle_deg(r->axis, t.axis);
  } else if (const auto* p = std::get_if<primitives::PlaneModel>(&fitted)) {
    pair.axis_error_deg =
        axis_angle_deg(p->normal, std::get<primitives::PlaneModel>(true_model).normal);
  }
  return pair;
}

}  // namespace

bool visible(const synth::TruePrimitive& truth, const MatchOptions& options) {
  return truth.own_points >= options.min_true_points;
}

double axis_angle_deg(const Vec3d& a, const Vec3d& b) {
  return std::acos(std::min(1.0, std::abs(a.normalized().dot(b.normalized())))) * 180 / M_PI;
}

InstanceMatch match_instances(const primitives::PrimitiveSet& detected,
                              const std::vector<Vec3f>& xyz, std::span<const float> object,
                              const std::vector<synth::TruePrimitive>& truth,
                              const MatchOptions& options) {
  if (detected.point_segment.size() != xyz.size() || object.size() != xyz.size())
    throw std::invalid_argument("match_instances: point_segment, xyz and object sizes differ");
  std::vector<std::vector<std::uint32_t>> members(detected.primitives.size());
  for (std::size_t i = 0; i < xyz.size(); ++i) {
    const std::uint32_t s = detected.point_segment[i];
    if (s != primitives::kNoSegment && s < members.size()) members[s].push_back(std::uint32_t(i));
  }
  // The true primitives of each object, so a point is measured against its own object's only.
  std::map<int, std::vector<std::size_t>> truth_of_object;
  for (std::size_t t = 0; t < truth.size(); ++t) truth_of_object[truth[t].object].push_back(t);

  InstanceMatch out;
  for (const auto& t : truth) {
    if (visible(t, options)) ++out.true_instances;
    if (t.primitive.points >= options.min_true_points) ++out.listed_instances;
  }

  // best[t]: the detection with most points on true primitive t, and that count.
  std::vector<std::pair<std::size_t, std::size_t>> best(truth.size(), {0, 0});
  for (std::size_t d = 0; d < detected.primitives.size(); ++d) {
    const primitives::Primitive& p = detected.primitives[d];
    if (!scored_kind(p.kind()) || members[d].size() < options.min_detection_points) continue;
    ++out.detections;
    std::vector<std::size_t> on(truth.size(), 0);
    for (const std::uint32_t i : members[d]) {
      const auto found = truth_of_object.find(int(object[i]));
      if (found == truth_of_object.end()) continue;
      const Vec3d point = xyz[i].cast<double>();
      for (const std::size_t t : found->second)
        if (truth[t].primitive.kind() == p.kind() &&
            synth::distance_to(truth[t].primitive.model, point) <= options.tolerance)
          ++on[t];
    }
    const auto most = std::max_element(on.begin(), on.end());
    if (most == on.end() || 2 * *most < members[d].size()) continue;  // on no true surface
    const std::size_t t = std::size_t(most - on.begin());
    const MatchedPair e = errors(p.model, truth[t].primitive.model);
    if (e.axis_error_deg > options.max_angle_deg || e.radius_error > options.max_radius_error)
      continue;  // a wrong instance of that surface
    if (*most > best[t].second) best[t] = {d, *most};
  }
  for (std::size_t t = 0; t < truth.size(); ++t) {
    if (best[t].second == 0) continue;
    MatchedPair pair = errors(detected.primitives[best[t].first].model, truth[t].primitive.model);
    pair.truth = t;
    pair.detection = best[t].first;
    out.pairs.push_back(pair);
    ++out.correct;
    if (visible(truth[t], options)) ++out.found;
    if (truth[t].primitive.points >= options.min_true_points) ++out.listed_found;
  }
  return out;
}

}  // namespace primlabel::bench
