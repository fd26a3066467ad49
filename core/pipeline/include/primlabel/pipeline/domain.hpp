#pragma once
// Whether a cloud is one a model can label: a model trained on one sensor's point spacing reads
// a much denser or sparser cloud through radii that then hold other shapes (an LMS400 model
// labels little of a Kinect table plane), and nothing else would tell the user.

#include <string>

#include "primlabel/model/label_model.hpp"

namespace primlabel::pipeline {

// A cloud whose median point spacing is within this factor of the training scenes' range passes.
inline constexpr float kSpacingTolerance = 2.0f;

// One line naming the cloud's spacing and the model's range when `point_spacing` (m) is more than
// kSpacingTolerance outside [training.point_spacing_min, training.point_spacing_max]; empty
// otherwise, and for models that did not record their range or clouds without a spacing.
std::string spacing_warning(const TrainingSummary& training, float point_spacing);

// Surface variation grows with the square of the noise: this factor is twice the noise.
inline constexpr float kSurfaceVariationTolerance = 4.0f;

// One line when `surface_variation` is more than kSurfaceVariationTolerance above the noisiest
// training scene's (a noisier sensor than the model knows); empty otherwise or when unrecorded.
// A cleaner cloud passes: less noise does not mislead the model.
std::string noise_warning(const TrainingSummary& training, float surface_variation);

// Both, joined by "; " when both apply.
std::string domain_warning(const TrainingSummary& training, float point_spacing,
                           float surface_variation);

}  // namespace primlabel::pipeline
