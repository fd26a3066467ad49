// The synthetic ground-truth rule applied to fitted surfaces: the very functions the scanners
// label their returns with (synth::ground_truth, then the observed-crease pass), so the fitted
// truth and the synthetic truth cannot drift apart.

#include "../synth/scan_common.hpp"
#include "shape_fit.hpp"

namespace primlabel::synth::fit {

std::vector<std::uint32_t> label_by_rule(const synth::Scene& scene,
                                         const std::vector<RulePoint>& points, double radius) {
  std::vector<synth::detail::Return> returns(points.size());
  for (std::size_t i = 0; i < points.size(); ++i) {
    const RulePoint& p = points[i];
    const synth::SceneObject& owner = scene.objects[p.object];
    synth::detail::Return& r = returns[i];
    r.label = class_id(synth::ground_truth(scene, p.object, p.part, p.surface, radius));
    r.surface_xyz = p.surface.cast<float>();
    r.part = p.part;
    r.object = static_cast<float>(p.object);
    r.surface_label =
        class_id(owner.shape->surface_class(p.part, owner.local_from_world * p.surface));
  }
  synth::detail::label_unseen_creases_as_surface(returns, radius);
  std::vector<std::uint32_t> labels(points.size());
  for (std::size_t i = 0; i < points.size(); ++i) labels[i] = returns[i].label;
  return labels;
}

}  // namespace primlabel::synth::fit
