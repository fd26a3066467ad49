#pragma once
// Builds the cloud of one scan from its PointChunks, checking each as it arrives: byte lengths
// that fit the point layout, the point and byte limits, the announced point count, and
// non-finite coordinates and client normals that are zero-length (shorter than 1e-3) or
// non-finite (counted, the point then has no normal and gets label 0; or refused when the
// request says NON_FINITE_REJECT). Every refusal is an INVALID_ARGUMENT naming the chunk and,
// for a point, the point.

#include <cstdint>
#include <optional>

#include "primlabel/geometry/point_cloud.hpp"
#include "primlabel/service/service_error.hpp"
#include "primlabel/v1/labeling.pb.h"

namespace primlabel::service {

struct ScanLimits {
  std::uint64_t max_points = 0;
  std::uint64_t max_bytes = 0;
};

class ScanAssembler {
 public:
  ScanAssembler(const v1::ScanHeader& header, const ScanLimits& limits);

  // Checks and appends one chunk (chunks are numbered from 1 in messages).
  std::optional<ServiceError> add(const v1::PointChunk& chunk);
  // After the last chunk: at least one point, and as many as the header announced.
  std::optional<ServiceError> finish() const;

  PointCloud& cloud() { return cloud_; }
  std::uint64_t points() const { return cloud_.size(); }
  // Points with a non-finite coordinate or an unusable normal (each counted once).
  std::uint64_t non_finite() const { return non_finite_; }

 private:
  const bool normals_;
  const bool intensity_;
  const bool reject_non_finite_;
  const std::uint64_t expected_points_;
  const std::uint64_t frame_points_;  // layout.width x height; 0: unorganised
  const ScanLimits limits_;
  PointCloud cloud_;
  std::uint64_t bytes_ = 0;
  std::uint64_t chunks_ = 0;
  std::uint64_t non_finite_ = 0;
};

// Checks a header before any point arrives: limits against expected_points and option values.
std::optional<ServiceError> check_header(const v1::ScanHeader& header, const ScanLimits& limits);

}  // namespace primlabel::service
