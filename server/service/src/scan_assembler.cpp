#include "primlabel/service/scan_assembler.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

#include "primlabel/wire/packing.hpp"

namespace primlabel::service {

namespace {

ServiceError invalid(const std::string& message) { return {ErrorCode::kInvalidArgument, message}; }

std::string describe_point(const Vec3f& p) {
  std::ostringstream text;
  text << "(" << p.x() << ", " << p.y() << ", " << p.z() << ")";
  return text.str();
}

constexpr std::uint64_t kMaxReservedPoints = 1u << 18;  // 3 MiB of xyz

// Shorter than this (or non-finite), a client's normal gives no direction: used as given, a
// zero normal makes every pair angle degenerate and the whole scan look like one plane.
constexpr float kMinNormalLength = 1e-3f;

bool usable_normal(const Vec3f& n) {
  return is_finite(n) && n.squaredNorm() >= kMinNormalLength * kMinNormalLength;
}

}  // namespace

std::optional<ServiceError> check_header(const v1::ScanHeader& header, const ScanLimits& limits) {
  if (header.expected_points() > limits.max_points)
    return invalid("the scan announces " + std::to_string(header.expected_points()) +
                   " points; this server takes at most " + std::to_string(limits.max_points));
  const v1::LabelOptions& options = header.options();
  const v1::Vec3& viewpoint = header.viewpoint();
  if (!std::isfinite(viewpoint.x()) || !std::isfinite(viewpoint.y()) ||
      !std::isfinite(viewpoint.z()))
    return invalid("the viewpoint must be finite");
  if (options.non_finite() != v1::NON_FINITE_DROP && options.non_finite() != v1::NON_FINITE_REJECT)
    return invalid("unknown options.non_finite policy " + std::to_string(options.non_finite()));
  const v1::PointLayout& layout = header.layout();
  if (layout.height() > 1 || layout.width() > 0) {
    const std::uint64_t pixels = std::uint64_t(layout.width()) * layout.height();
    const std::string frame = "layout.width x layout.height (" + std::to_string(layout.width()) +
                              "x" + std::to_string(layout.height()) + ")";
    if (layout.width() == 0 || layout.height() == 0)
      return invalid(frame +
                     ": an organised frame needs both; leave both 0 for an unorganised "
                     "cloud");
    if (pixels > limits.max_points)
      return invalid(frame + " is " + std::to_string(pixels) +
                     " points; this server takes at most " + std::to_string(limits.max_points));
    if (header.expected_points() > 0 && header.expected_points() != pixels)
      return invalid(frame + " is " + std::to_string(pixels) + " points but expected_points is " +
                     std::to_string(header.expected_points()));
  }
  return std::nullopt;
}

ScanAssembler::ScanAssembler(const v1::ScanHeader& header, const ScanLimits& limits)
    : normals_(header.layout().normals()),
      intensity_(header.layout().intensity()),
      reject_non_finite_(header.options().non_finite() == v1::NON_FINITE_REJECT),
      expected_points_(header.expected_points()),
      frame_points_(std::uint64_t(header.layout().width()) * header.layout().height()),
      limits_(limits) {
  cloud_.viewpoint.origin =
      Vec3f(header.viewpoint().x(), header.viewpoint().y(), header.viewpoint().z());
  // A header alone must not buy memory: announced points are reserved only up to a modest
  // count, the rest grows as points really arrive.
  const std::uint64_t reserved = std::min<std::uint64_t>(expected_points_, kMaxReservedPoints);
  if (reserved > 0) {
    cloud_.xyz.reserve(reserved);
    if (normals_) cloud_.normals.reserve(reserved);
  }
}

std::optional<ServiceError> ScanAssembler::add(const v1::PointChunk& chunk) {
  ++chunks_;
  const std::string where = "chunk " + std::to_string(chunks_);
  const std::string& xyz = chunk.xyz();
  if (xyz.size() % wire::kXyzBytesPerPoint != 0)
    return invalid(where + ": xyz has " + std::to_string(xyz.size()) +
                   " bytes, not a multiple of 12 (float32 x, y, z per point)");
  const std::uint64_t n = xyz.size() / wire::kXyzBytesPerPoint;
  if (normals_ && chunk.normals().size() != n * wire::kNormalBytesPerPoint)
    return invalid(where + ": normals has " + std::to_string(chunk.normals().size()) + " bytes; " +
                   std::to_string(n) + " points need " +
                   std::to_string(n * wire::kNormalBytesPerPoint));
  if (!normals_ && !chunk.normals().empty())
    return invalid(where + " carries normals but the header's layout does not declare them");
  if (intensity_ && chunk.intensity().size() != n * wire::kIntensityBytesPerPoint)
    return invalid(where + ": intensity has " + std::to_string(chunk.intensity().size()) +
                   " bytes; " + std::to_string(n) + " points need " +
                   std::to_string(n * wire::kIntensityBytesPerPoint));
  if (!intensity_ && !chunk.intensity().empty())
    return invalid(where + " carries intensity but the header's layout does not declare it");

  const std::uint64_t first = cloud_.size();
  if (first + n > limits_.max_points)
    return invalid(where + " brings the scan to " + std::to_string(first + n) +
                   " points; this server takes at most " + std::to_string(limits_.max_points));
  if (expected_points_ > 0 && first + n > expected_points_)
    return invalid(where + " brings the scan to " + std::to_string(first + n) +
                   " points, more than the " + std::to_string(expected_points_) +
                   " the header announced");
  bytes_ += xyz.size() + chunk.normals().size() + chunk.intensity().size();
  if (bytes_ > limits_.max_bytes)
    return invalid(where + " brings the scan to " + std::to_string(bytes_) +
                   " bytes; this server takes at most " + std::to_string(limits_.max_bytes));

  // Eigen::Vector3f is three packed floats, so the packed array unpacks straight into place.
  if (n == 0) return std::nullopt;
  cloud_.xyz.resize(first + n);
  wire::unpack_le<float>(xyz, cloud_.xyz[first].data());
  if (normals_) {
    cloud_.normals.resize(first + n);
    wire::unpack_le<float>(chunk.normals(), cloud_.normals[first].data());
  }
  for (std::uint64_t i = first; i < first + n; ++i) {
    const bool finite_xyz = is_finite(cloud_.xyz[i]);
    if (!finite_xyz && reject_non_finite_)
      return invalid("point " + std::to_string(i) + " (" + where +
                     ") has a non-finite coordinate " + describe_point(cloud_.xyz[i]) +
                     " and options.non_finite is NON_FINITE_REJECT");
    bool dropped = !finite_xyz;
    if (normals_ && !usable_normal(cloud_.normals[i])) {
      if (reject_non_finite_)
        return invalid("point " + std::to_string(i) + " (" + where + ") has the normal " +
                       describe_point(cloud_.normals[i]) +
                       ", zero-length or non-finite, and options.non_finite is "
                       "NON_FINITE_REJECT");
      // As a PCL normal of NaNs means: this point has no normal (no descriptor, label 0).
      cloud_.normals[i] = Vec3f::Constant(std::numeric_limits<float>::quiet_NaN());
      dropped = true;
    }
    non_finite_ += dropped;
  }
  cloud_.width = static_cast<std::uint32_t>(cloud_.size());
  cloud_.height = 1;
  return std::nullopt;
}

std::optional<ServiceError> ScanAssembler::finish() const {
  if (cloud_.empty()) return invalid("the scan has no points");
  if (expected_points_ > 0 && cloud_.size() != expected_points_)
    return invalid("the scan has " + std::to_string(cloud_.size()) + " points but the header " +
                   "announced " + std::to_string(expected_points_));
  if (frame_points_ > 0 && cloud_.size() != frame_points_)
    return invalid("the scan has " + std::to_string(cloud_.size()) +
                   " points but layout.width x layout.height is " + std::to_string(frame_points_));
  return std::nullopt;
}

}  // namespace primlabel::service
