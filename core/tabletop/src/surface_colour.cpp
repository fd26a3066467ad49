#include "surface_colour.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>

namespace primlabel::tabletop::colour {

std::optional<Eigen::Vector2d> chromaticity(std::uint32_t rgba) {
  const double r = (rgba >> 16) & 0xFF, g = (rgba >> 8) & 0xFF, b = rgba & 0xFF;
  if (r + g + b < 60.0) return std::nullopt;
  return Eigen::Vector2d(r, g) / (r + g + b);
}

Material material_of(const std::vector<Eigen::Vector2d>& colours, std::size_t least) {
  Material m;
  if (colours.empty() || colours.size() < least) return m;
  double squares = 0;
  for (const auto& x : colours) {
    m.mean += x;
    squares += x.squaredNorm();
  }
  m.count = colours.size();
  m.mean /= double(m.count);
  m.variance = std::max(0.0, squares / double(m.count) - m.mean.squaredNorm());
  return m;
}

bool different(const Material& a, const Material& b, const TwoColourRule& rule) {
  if (a.count == 0 || b.count == 0) return false;
  const double step = (a.mean - b.mean).norm();
  return step >= rule.step && step >= rule.separation * std::sqrt(a.variance + b.variance);
}

bool same(const Material& a, const Material& b, const TwoColourRule& rule) {
  return a.count > 0 && b.count > 0 && (a.mean - b.mean).norm() < 0.5 * rule.step &&
         std::sqrt(a.variance + b.variance) < 0.5 * rule.step;
}

std::optional<double> height_step(std::vector<std::pair<double, Eigen::Vector2d>> samples,
                                  double min_rise, const TwoColourRule& rule) {
  const std::size_t n = samples.size(), least = std::max<std::size_t>(rule.least, 1);
  if (n < 2 * least) return std::nullopt;
  std::sort(samples.begin(), samples.end(),
            [](const auto& a, const auto& b) { return a.first < b.first; });
  std::vector<Eigen::Vector2d> sum(n + 1, Eigen::Vector2d::Zero());
  std::vector<double> squares(n + 1, 0.0);
  for (std::size_t k = 0; k < n; ++k) {
    sum[k + 1] = sum[k] + samples[k].second;
    squares[k + 1] = squares[k] + samples[k].second.squaredNorm();
  }
  const auto scatter = [&](std::size_t from, std::size_t to) {  // [from, to)
    const Eigen::Vector2d s = sum[to] - sum[from];
    return squares[to] - squares[from] - s.squaredNorm() / double(to - from);
  };
  const double total = scatter(0, n);
  if (!(total > 0.0)) return std::nullopt;
  std::size_t best = 0;
  double best_scatter = total;
  for (std::size_t m = least; m + least <= n; ++m) {
    if (samples[m].first <= samples[m - 1].first) continue;  // cut between distinct heights
    if (samples[m - 1].first - samples[0].first < min_rise ||
        samples[n - 1].first - samples[m].first < min_rise)
      continue;
    const double within = scatter(0, m) + scatter(m, n);
    if (within < best_scatter) {
      best_scatter = within;
      best = m;
    }
  }
  if (best == 0 || 1.0 - best_scatter / total < rule.explained) return std::nullopt;
  const Eigen::Vector2d below = sum[best] / double(best);
  const Eigen::Vector2d above = (sum[n] - sum[best]) / double(n - best);
  if ((below - above).norm() < rule.step) return std::nullopt;
  return 0.5 * (samples[best - 1].first + samples[best].first);
}

std::optional<std::vector<std::uint8_t>> two_materials(const std::vector<Eigen::Vector2d>& colours,
                                                       const TwoColourRule& rule) {
  const std::size_t least = std::max<std::size_t>(rule.least, 1);
  if (colours.size() < 2 * least) return std::nullopt;
  Eigen::Vector2d mean = Eigen::Vector2d::Zero();
  for (const auto& x : colours) mean += x;
  mean /= double(colours.size());
  Eigen::Matrix2d scatter = Eigen::Matrix2d::Zero();
  for (const auto& x : colours) scatter += (x - mean) * (x - mean).transpose();
  const double total = scatter.trace();
  if (!(total > 0.0)) return std::nullopt;
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> solver(scatter);
  const Eigen::Vector2d axis = solver.eigenvectors().col(1);
  const auto [lo, hi] =
      std::minmax_element(colours.begin(), colours.end(),
                          [&](const auto& a, const auto& b) { return a.dot(axis) < b.dot(axis); });
  Eigen::Vector2d centre[2] = {*lo, *hi};
  std::vector<std::uint8_t> group(colours.size(), 0);
  for (int iteration = 0; iteration < 10; ++iteration) {
    Eigen::Vector2d sum[2] = {Eigen::Vector2d::Zero(), Eigen::Vector2d::Zero()};
    std::size_t count[2] = {0, 0};
    for (std::size_t k = 0; k < colours.size(); ++k) {
      group[k] = (colours[k] - centre[1]).squaredNorm() < (colours[k] - centre[0]).squaredNorm();
      sum[group[k]] += colours[k];
      ++count[group[k]];
    }
    if (count[0] == 0 || count[1] == 0) return std::nullopt;
    centre[0] = sum[0] / double(count[0]);
    centre[1] = sum[1] / double(count[1]);
  }
  double within[2] = {0, 0};
  std::size_t count[2] = {0, 0};
  for (std::size_t k = 0; k < colours.size(); ++k) {
    within[group[k]] += (colours[k] - centre[group[k]]).squaredNorm();
    ++count[group[k]];
  }
  if (count[0] < least || count[1] < least) return std::nullopt;
  if (1.0 - (within[0] + within[1]) / total < rule.explained) return std::nullopt;
  const Material a{centre[0], within[0] / double(count[0]), count[0]};
  const Material b{centre[1], within[1] / double(count[1]), count[1]};
  if (!different(a, b, rule)) return std::nullopt;
  return group;
}

}  // namespace primlabel::tabletop::colour
