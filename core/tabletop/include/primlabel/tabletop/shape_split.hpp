#pragma once
// Splits a cluster where a can ends and a touching neighbour starts (a can against a box of its
// height and colour, a can standing on a box, two cans side by side), which the crease split
// misses: at a tangent contact the two surfaces run on parallel, so no sharp fold is seen.
//
// The cluster is over-segmented into fitted instances: planes, cylinders and balls taken one
// after the other by MSAC (primitives::fit_model; each round keeps the plane, cylinder or ball
// whose connected piece is largest, a cylinder only as one unbroken arc of at least 90 degrees
// around its axis, as a can's side is seen; a rounded edge bends less, a cylinder through strips
// of two faces leaves a gap), each instance the image-connected piece of its inliers, with
// per-point normals from the pixel grid. A ball is tried where the round's cylinder took a band no
// wider along its axis than a ball's (where the ball's normals stay within normal_angle_deg of the
// cylinder's): the sphere of the cylinder's radius around the band's middle, grown over the free
// points, refitted to the cap it grew (primitives::fit_sphere) and grown again. It is a ball only
// as a cap reaching 45 degrees from its middle in 7 of 8 directions around it (a sphere through a
// can's side, a rounded edge or a plane's bulge reaches at most normal_angle_deg across it, a
// rounded corner 35), of object size (min_radius to max_radius), seen from outside (the inside
// of a bowl bounds no solid). A plane through a can's lid and the top of a box of the can's height
// is cut by the can's solid into the lid and the rest. Points no instance took join the instance
// they touch in the image.
//
// Two objects of one footprint stacked (a box on a box, a can on a can of its radius) share their
// side faces' fitted planes or cylinder. Where the cloud has colour, such an upright instance is
// cut at a colour seam: a height at which its material (mean chromaticity) changes from one
// colour below to another above, explaining most of its colour variation (a printed face changes
// colour in many places and directions, so no one horizontal line explains it). Every upright
// instance showing the seam at that height is cut, and no piece below it joins one above. A
// surface of two even colours (a box's top in one plane with the book leaning on it) is cut in
// two, and surfaces of even, clearly different colours never join.
//
// A can's or a ball's surface bounds its solid all round, so what lies outside it is another
// object: a fitted instance (plane, can or ball) is kept apart from an object-sized can or ball
// when most of it lies beyond the surface by more than the band, it reaches farther from the
// axis or centre than the solid's diameter (a handle or spout stays closer) and, where it touches
// the solid, its surface does not run on from the solid's (the wider top of a tapered cup).
// Instances join by contact, longest first, never bringing a can or ball and an instance kept apart
// from it together. A plane bounds only a half-space, which a neighbour's visible part may lie in
// (a can beside a box is below the box's top), so two planes never cut here: their concave creases
// are the crease split's. The inside of a mug faces its axis and bounds no solid. Pieces smaller
// than min_object_points, then pieces with no fitted surface of half that size (a handle), join the
// piece they touch most.
//
// The depth noise sets the bands: the inlier band and "outside" are noise_sigmas Kinect sigmas at
// the cluster's mean range (depth_noise_per_m2 * z^2), never narrower than min_band.
// Clusters are split in parallel on context.threads; the result does not depend on them:
// instances are fitted from fixed seeds, joins ordered by contact then index.
//
// Two balls in contact usually arrive in two clusters (the crease split cuts at their contact),
// which the occlusion merge would join again (one height and colour, no table seen between
// them); so may a can and a neighbour of its colour. So every object-sized ball and can fitted
// in a cluster of at least min_object_points (one too small to cut is fitted for this alone)
// goes to `kept_apart` (KeptApart::solids), and the merge never joins a cluster to one lying
// outside the solid. A box's rounded edge can fit a can (mOSD learn18's box, seen left and right
// of a nearer one, would be kept in two halves): a can whose arc runs on at either end into a
// flat face tangent to it (its plane at the radius with the axis behind it, its normal across
// the axis) that then leaves the cylinder is a box edge and is not handed on. A can's arc ends
// at its silhouette, its lid or another object, and its rim stays on its cylinder.

#include <cstddef>
#include <cstdint>
#include <vector>

#include "primlabel/geometry/point_cloud.hpp"
#include "primlabel/geometry/run_context.hpp"
#include "primlabel/tabletop/kept_apart.hpp"

namespace primlabel::tabletop {

struct ShapeSplitOptions {
  bool enabled = true;
  int normal_step = 2;                  // pixels either side for a point's grid normal
  float depth_noise_per_m2 = 2.82e-3f;  // the sensor's depth sigma / range^2 (Kinect, measured)
  float noise_sigmas = 3.0f;            // inlier band and "in front of" margin, in sigmas
  float min_band = 0.003f;              // (m) never narrower (quantisation, near objects)
  float normal_angle_deg = 30.0f;       // an inlier's normal within this of the surface's
  float min_radius = 0.015f, max_radius = 0.25f;  // object-sized cylinders and balls (m)
  std::size_t min_instance_points = 120;          // smaller pieces are not fitted instances
  int max_instances = 24;                         // per cluster
  float max_neighbour_gap = 0.015f;               // pixels farther apart in 3D do not touch (m)
  float outside_share = 0.5f;  // of an instance's inliers outside a touching can: another object
  std::size_t min_object_points = 400;  // both sides of a cut (and a can) hold this many points
  // Colour evidence (seams, two-colour surfaces, joins) where the cloud has colour; off for
  // scans whose colour is not registered to their depth.
  bool use_colour = true;
  // Colour seams: the step's share of an upright instance's chromaticity variance, the least
  // step between the mean chromaticities, and the least height of either part (m).
  float seam_explained = 0.8f;
  float seam_chromaticity_step = 0.05f;
  float seam_min_rise = 0.02f;
  // Two fitted surfaces of even colours this many spreads apart (and a seam step) never join.
  float material_separation = 4.0f;
  // Upright: a plane's normal within this of level, a cylinder's axis within this of up.
  float upright_deg = 20.0f;
  std::uint64_t seed = 1;

  void validate() const;  // throws std::invalid_argument naming the bad option
};

// Organised clouds only (grid normals face the sensor); others are returned as they are.
// `height` holds every clustered point's signed distance above the table, whose normal is `up`.
// Returns the clusters with each cut where a can meets what lies outside it: input indices
// ascending within each piece, pieces ordered by size (largest first, ties by first index).
// `kept_apart`, when given, is set to the pieces of every cut cluster and the balls fitted.
std::vector<std::vector<std::uint32_t>> split_by_shape(
    const PointCloud& cloud, const std::vector<float>& height, const Vec3f& up,
    std::vector<std::vector<std::uint32_t>> clusters, const ShapeSplitOptions& options,
    KeptApart* kept_apart = nullptr, const RunContext& context = {});

}  // namespace primlabel::tabletop
