#include "primlabel/geometry/normals.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <atomic>
#include <limits>
#include <span>
#include <stdexcept>

#include "primlabel/geometry/cancellation.hpp"
#include "primlabel/geometry/parallel.hpp"
#include "primlabel/geometry/point_moments.hpp"

namespace primlabel {

namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

// Plane normal and surface variation of one neighbourhood.
bool fit_normal(const std::vector<Vec3f>& xyz, const Vec3f& query,
                std::span<const std::uint32_t> neighbors, Vec3f& normal, float& curvature) {
  if (neighbors.size() < 3) return false;
  PointMoments moments;
  for (std::uint32_t index : neighbors) moments.add(xyz[index], query);
  const Eigen::Matrix3d cov = moments.covariance();

  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver;
  solver.computeDirect(cov);
  const Eigen::Vector3d lambda = solver.eigenvalues();  // ascending
  const double trace = cov.trace();
  if (!(trace > 0.0)) return false;  // all neighbours coincide: no plane
  normal = solver.eigenvectors().col(0).cast<float>();
  curvature = static_cast<float>(std::max(lambda(0), 0.0) / trace);
  return is_finite(normal);
}

}  // namespace

NormalStats estimate_normals(PointCloud& cloud, const NormalOptions& options,
                             const RunContext& context, const NeighborSearch* search,
                             const NeighborLists* lists) {
  const std::stop_token& stop = context.stop;
  if (!options.neighborhood.valid())
    throw std::invalid_argument("normal estimation: invalid neighbourhood " +
                                options.neighborhood.describe());
  std::unique_ptr<NeighborSearch> own_search;
  if (!search) {
    own_search = std::make_unique<NeighborSearch>(cloud.xyz, stop);
    search = own_search.get();
  }
  const bool use_lists = lists && options.neighborhood.radius > 0.0f &&
                         options.neighborhood.radius <= lists->neighborhood().radius;
  const Vec3f viewpoint = options.viewpoint.value_or(cloud.viewpoint.origin);
  const std::size_t n = cloud.size();
  if (!options.wanted.empty() && options.wanted.size() != n)
    throw std::invalid_argument("normal estimation: one `wanted` flag per point is needed");
  detail::assign_checked(cloud.normals, n, Vec3f(Vec3f::Constant(kNaN)), stop, "normal estimation");
  detail::assign_checked(cloud.curvature, n, kNaN, stop, "normal estimation");

  std::atomic<std::size_t> estimated{0}, too_few{0}, invalid_input{0};
  detail::ProgressCounter progress(context.progress, n);
  const int threads = detail::resolve_threads(context.threads);
  constexpr std::size_t kBlock = 256;
  const auto blocks = static_cast<std::ptrdiff_t>((n + kBlock - 1) / kBlock);
  const auto make_scratch = [] { return NeighborList(); };
  detail::for_each_block(
      blocks, context.with_threads(threads), make_scratch,
      [&](NeighborList& neighbors, std::ptrdiff_t block) {
        std::size_t block_estimated = 0, block_too_few = 0, block_invalid = 0;
        const std::size_t first = std::size_t(block) * kBlock, last = std::min(n, first + kBlock);
        for (std::size_t i = first; i < last; ++i) {
          // Checked per point: a stop is then honoured within one (capped) neighbourhood's time.
          if (stop.stop_requested()) return;
          if (!options.wanted.empty() && !options.wanted[i]) continue;
          const Vec3f& p = cloud.xyz[i];
          if (!is_finite(p)) {
            ++block_invalid;
            continue;
          }
          // From the shared lists without a copy where they answer as they are.
          std::span<const std::uint32_t> found;
          if (use_lists) {
            found = lists->view(i, options.neighborhood, neighbors);
          } else {
            search->find(p, options.neighborhood, neighbors, /*sorted=*/false);
            found = neighbors.indices;
          }
          Vec3f normal;
          float curvature;
          if (fit_normal(cloud.xyz, p, found, normal, curvature)) {
            // Face the sensor, as PCL's flipNormalTowardsViewpoint does.
            if ((viewpoint - p).dot(normal) < 0.0f) normal = -normal;
            cloud.normals[i] = normal;
            cloud.curvature[i] = curvature;
            ++block_estimated;
          } else {
            ++block_too_few;
          }
        }
        estimated += block_estimated, too_few += block_too_few, invalid_input += block_invalid;
        progress.add(last - first);
      });
  throw_if_stopped(stop, "normal estimation");
  progress.finish();
  return NormalStats{estimated.load(), too_few.load(), invalid_input.load()};
}

}  // namespace primlabel
