#pragma once
// The sums of a neighbourhood's coordinates taken around a point, and the covariance they give:
// normal estimation and the multi-scale surface variations both fit planes this way. The sums
// are in double around the point, which keeps them small and the covariance accurate.

#include <Eigen/Core>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <limits>

#include "primlabel/geometry/point_cloud.hpp"

namespace primlabel {

struct PointMoments {
  double count = 0;
  double sx = 0, sy = 0, sz = 0, sxx = 0, sxy = 0, sxz = 0, syy = 0, syz = 0, szz = 0;

  void add(const Vec3f& p, const Vec3f& origin) {
    const double x = double(p.x()) - origin.x(), y = double(p.y()) - origin.y(),
                 z = double(p.z()) - origin.z();
    count += 1;
    sx += x, sy += y, sz += z;
    sxx += x * x, sxy += x * y, sxz += x * z, syy += y * y, syz += y * z, szz += z * z;
  }

  // The covariance of the points added (at least one).
  Eigen::Matrix3d covariance() const {
    const double inv_n = 1.0 / count;
    const double mx = sx * inv_n, my = sy * inv_n, mz = sz * inv_n;
    Eigen::Matrix3d cov;
    cov(0, 0) = sxx * inv_n - mx * mx;
    cov(0, 1) = sxy * inv_n - mx * my;
    cov(0, 2) = sxz * inv_n - mx * mz;
    cov(1, 1) = syy * inv_n - my * my;
    cov(1, 2) = syz * inv_n - my * mz;
    cov(2, 2) = szz * inv_n - mz * mz;
    cov(1, 0) = cov(0, 1);
    cov(2, 0) = cov(0, 2);
    cov(2, 1) = cov(1, 2);
    return cov;
  }

  // The surface variation (Pauly et al.): the covariance's smallest eigenvalue over their sum,
  // from 0 on a plane to 1/3 for isotropic scatter. NaN for fewer than 3 points or no spread.
  double surface_variation() const {
    if (count < 3) return std::numeric_limits<double>::quiet_NaN();
    const Eigen::Matrix3d cov = covariance();
    const double trace = cov.trace();
    if (!(trace > 0.0)) return std::numeric_limits<double>::quiet_NaN();
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver;
    solver.computeDirect(cov, Eigen::EigenvaluesOnly);
    return std::max(solver.eigenvalues()(0), 0.0) / trace;
  }
};

}  // namespace primlabel
