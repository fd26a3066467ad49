#pragma once
// Whether a cloud is one a model can label: a model trained on one sensor's point spacing reads
// a much denser or sparser cloud through radii that then hold other shapes (an LMS400 model
// labels little of a Kinect table plane), and nothing else would tell the user.

#include <string>

#include "primlabel/geometry/point_cloud.hpp"
#include "primlabel/geometry/run_context.hpp"
#include "primlabel/model/label_model.hpp"

namespace primlabel::pipeline {

// A cloud whose median point spacing is within this factor of the training scenes' range passes.
inline constexpr float kSpacingTolerance = 2.0f;

// One line naming the cloud's spacing and the model's range when `point_spacing` (m) is more than
// kSpacingTolerance outside [training.point_spacing_min, training.point_spacing_max]; empty
// otherwise, and for models that did not record their range or clouds without a spacing.
std::string spacing_warning(const TrainingSummary& training, float point_spacing);

// Whether `point_spacing` (m) is more than kSpacingTolerance sparser than the model's training
// scenes (the case of a cloud in millimetres read as metres); false without a recorded range.
bool sparser_than_trained(const TrainingSummary& training, float point_spacing);

// Surface variation grows with the square of the noise: this factor is twice the noise.
inline constexpr float kSurfaceVariationTolerance = 4.0f;

// One line when `surface_variation` is more than kSurfaceVariationTolerance above the noisiest
// training scene's (a noisier sensor than the model knows); empty otherwise or when unrecorded.
// A cleaner cloud passes: less noise does not mislead the model.
std::string noise_warning(const TrainingSummary& training, float surface_variation);

// Both, joined by "; " when both apply.
std::string domain_warning(const TrainingSummary& training, float point_spacing,
                           float surface_variation);

// A cloud written in millimetres or centimetres looks metres-sized to the model: its points seem
// a thousand times apart, nothing lies within the radii, and every point comes back unknown.
// When the cloud's acquired spacing, scaled by 0.001 (or 0.01), fits the model's training scans
// and its median range from the viewpoint then lies within [kTableTopRangeMin, kTableTopRangeMax]
// m, one line saying so and how to fix it ("... pass --units mm"); empty otherwise, and when the
// model did not record its acquired spacing. Builds a neighbour index to measure the spacing:
// call it only for a cloud already found sparser than the model's domain.
inline constexpr float kTableTopRangeMin = 0.1f, kTableTopRangeMax = 10.0f;
inline constexpr std::size_t kUnitsSamples = 1024;
std::string units_hint(const TrainingSummary& training, const PointCloud& cloud,
                       const RunContext& context = {});

}  // namespace primlabel::pipeline
