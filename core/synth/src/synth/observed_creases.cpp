// Ground truth limited to what the scan shows: see label_unseen_creases_as_surface.

#include <cmath>

#include "primlabel/geometry/neighbor_search.hpp"
#include "primlabel/geometry/parallel.hpp"
#include "scan_common.hpp"

namespace primlabel::synth::detail {

void label_unseen_creases_as_surface(std::vector<Return>& returns, double label_radius) {
  std::vector<Vec3f> surface(returns.size());
  for (std::size_t i = 0; i < returns.size(); ++i) surface[i] = returns[i].surface_xyz;
  const NeighborSearch search(surface);
  const Neighborhood hood = Neighborhood::Radius(static_cast<float>(label_radius));
  const double fraction = kObservedCreaseFraction;

  std::vector<std::uint32_t> relabeled(returns.size());
  primlabel::detail::parallel_for(
      static_cast<std::ptrdiff_t>(returns.size()), 0, primlabel::detail::Schedule::Dynamic(256),
      [] { return NeighborList{}; },
      [&](NeighborList& neighbors, std::ptrdiff_t i) {
        const Return& r = returns[i];
        relabeled[i] = r.label;
        if (r.part < 0 || r.label == r.surface_label) return;
        search.find(r.surface_xyz, hood, neighbors, /*sorted=*/false);
        std::size_t across = 0;
        for (std::uint32_t j : neighbors.indices)
          across += returns[j].object != r.object || returns[j].part != r.part;
        if (double(across) < fraction * double(neighbors.size())) relabeled[i] = r.surface_label;
      });
  for (std::size_t i = 0; i < returns.size(); ++i) returns[i].label = relabeled[i];
}

}  // namespace primlabel::synth::detail
