#include "primlabel/pipeline/model_choice.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace primlabel::pipeline {
namespace {

std::string size_text(std::uint32_t width, std::uint32_t height) {
  return std::to_string(width) + "x" + std::to_string(height);
}

std::string decimal(double value) {
  char text[32];
  std::snprintf(text, sizeof text, "%.2f", value);
  return text;
}

std::string millimetres(float metres) { return decimal(double(metres) * 1e3); }

// Whether `value` lies within kSignatureTolerance of [low, high].
bool within(float value, float low, float high) {
  return value >= low / kSignatureTolerance && value <= high * kSignatureTolerance;
}

std::string joined(const std::vector<std::string>& parts, const char* separator) {
  std::string out;
  for (const std::string& part : parts) out += (out.empty() ? "" : separator) + part;
  return out;
}

// Which parts of the signature a model recorded (0 or NaN: a file from before they were).
bool spacing_recorded(const TrainingSummary& t) { return t.acquired_spacing_min > 0.0f; }
bool roughness_recorded(const TrainingSummary& t) { return t.roughness_min > 0.0f; }
bool growth_recorded(const TrainingSummary& t) {
  return std::isfinite(t.noise_growth_min) && std::isfinite(t.noise_growth_max);
}
bool records_signature(const ModelCandidate& candidate) {
  const TrainingSummary& t = *candidate.training;
  return spacing_recorded(t) || roughness_recorded(t) || growth_recorded(t);
}

}  // namespace

DomainVerdict judge_shape(const TrainingSummary& training, const CloudShape& shape) {
  if (!shape.organized()) return {DomainFit::kUnknown, "the cloud is not organised"};
  if (training.sensor.empty()) return {DomainFit::kUnknown, "its training shape is not recorded"};
  if (training.image_height <= 1)
    return {DomainFit::kOutside, "trained on unorganised " + training.sensor + " scans"};
  const std::string trained = "trained on " +
                              size_text(training.image_width, training.image_height) + " " +
                              training.sensor + " frames";
  // Frames of another size are likely the same kind of sensor: the signature decides.
  if (training.image_width != shape.width || training.image_height != shape.height)
    return {DomainFit::kUnknown, trained};
  return {DomainFit::kFits, trained};
}

DomainVerdict judge_signature(const TrainingSummary& training, const CloudSignature& signature) {
  if (!records_signature({"", &training}))
    return {DomainFit::kUnknown, "its training scans' signature is not recorded"};
  const bool spacing_known = spacing_recorded(training) && std::isfinite(signature.point_spacing) &&
                             signature.point_spacing > 0.0f;
  const bool roughness_known = roughness_recorded(training) && std::isfinite(signature.roughness);
  const bool growth_known = growth_recorded(training) && std::isfinite(signature.noise_growth);
  if (!spacing_known && !roughness_known && !growth_known)
    return {DomainFit::kUnknown, "the cloud has no measurable spacing, roughness or noise growth"};
  std::vector<std::string> outside, inside;
  const auto check = [&](bool known, bool fits, const std::string& measured,
                         const std::string& trained) {
    if (!known) return;
    (fits ? inside : outside).push_back(measured + " (trained " + trained + ")");
  };
  check(
      spacing_known,
      within(signature.point_spacing, training.acquired_spacing_min, training.acquired_spacing_max),
      "acquired spacing " + millimetres(signature.point_spacing) + " mm",
      millimetres(training.acquired_spacing_min) + "-" +
          millimetres(training.acquired_spacing_max) + " mm");
  check(roughness_known,
        within(signature.roughness, training.roughness_min, training.roughness_max),
        "roughness " + millimetres(signature.roughness) + " mm",
        millimetres(training.roughness_min) + "-" + millimetres(training.roughness_max) + " mm");
  check(growth_known,
        signature.noise_growth >= training.noise_growth_min - kNoiseGrowthTolerance &&
            signature.noise_growth <= training.noise_growth_max + kNoiseGrowthTolerance,
        "noise growth " + decimal(signature.noise_growth),
        decimal(training.noise_growth_min) + " to " + decimal(training.noise_growth_max));
  // Quantised depth marks a depth camera: a model whose training scans showed none is not for
  // such a cloud. The absence of ties says nothing (a frame turned into another frame loses them).
  if (std::isfinite(training.depth_ties_max) && training.depth_ties_max < kQuantisedDepthTies / 2 &&
      signature.depth_ties >= kQuantisedDepthTies)
    outside.push_back("depth ties " + decimal(signature.depth_ties) +
                      " (quantised depth, a depth camera's; trained up to " +
                      decimal(training.depth_ties_max) + ")");
  if (!outside.empty()) return {DomainFit::kOutside, "outside: " + joined(outside, ", ")};
  return {DomainFit::kFits, joined(inside, ", ")};
}

const char* choice_reason_name(ChoiceReason reason) {
  switch (reason) {
    case ChoiceReason::kNamed:
      return "named";
    case ChoiceReason::kDomain:
      return "domain";
    case ChoiceReason::kDefault:
      return "default";
  }
  return "unknown";
}

ModelChooser::ModelChooser(std::vector<ModelCandidate> candidates, std::string default_model,
                           const CloudShape& shape)
    : all_(std::move(candidates)), default_model_(std::move(default_model)) {
  std::vector<ModelCandidate> fitting;
  std::string fits_why;
  for (const ModelCandidate& candidate : all_) {
    const DomainVerdict verdict = judge_shape(*candidate.training, shape);
    if (verdict.fit == DomainFit::kOutside) {
      shape_notes_.push_back(candidate.name + ": " + verdict.why);
      continue;
    }
    remaining_.push_back(candidate);
    if (verdict.fit == DomainFit::kFits) {
      fitting.push_back(candidate);
      fits_why = verdict.why;
    }
  }
  if (all_.size() == 1 && remaining_.size() == 1 && all_.front().name == default_model_) {
    // One model served: it labels the cloud whatever its signature, which is not worth an index.
    choice_ = ModelChoice{all_.front().name, ChoiceReason::kDefault, "the only model served"};
    return;
  }
  if (!shape.organized()) {  // the shape says nothing: the signature decides, if any is recorded
    if (std::none_of(remaining_.begin(), remaining_.end(), records_signature))
      choice_ = fall_back("no model records the signature of its training scans", shape_notes_);
    return;
  }
  const std::string frame = "an organised " + size_text(shape.width, shape.height) + " frame";
  if (fitting.size() == 1) {
    choice_ = ModelChoice{fitting.front().name, ChoiceReason::kDomain,
                          frame + ": the only model " + fits_why};
    return;
  }
  if (remaining_.empty()) {
    choice_ = fall_back("no model fits " + frame, shape_notes_);
    return;
  }
  if (!fitting.empty()) remaining_ = fitting;  // several models of this size: signatures decide
  if (std::none_of(remaining_.begin(), remaining_.end(), records_signature))
    choice_ = fall_back(frame +
                            " that no model's shape decides, and none records its "
                            "training scans' signature",
                        shape_notes_);
}

void ModelChooser::consider(const CloudSignature& signature) {
  std::vector<std::string> fitting, notes = shape_notes_;
  std::string fits_why;
  for (const ModelCandidate& candidate : remaining_) {
    const DomainVerdict verdict = judge_signature(*candidate.training, signature);
    if (verdict.fit == DomainFit::kFits) {
      fitting.push_back(candidate.name);
      fits_why = verdict.why;
    } else {
      notes.push_back(candidate.name + ": " + verdict.why);
    }
  }
  if (fitting.size() == 1) {
    choice_ = ModelChoice{fitting.front(), ChoiceReason::kDomain,
                          "the only model that fits: " + fits_why};
    return;
  }
  const std::string measured = "acquired spacing " + millimetres(signature.point_spacing) +
                               " mm, roughness " + millimetres(signature.roughness) +
                               " mm, noise growth " + decimal(signature.noise_growth);
  const std::string what = fitting.empty() ? "no model fits the cloud (" + measured + ")"
                                           : "several models fit the cloud (" + measured + ": " +
                                                 joined(fitting, ", ") + ")";
  choice_ = fall_back(what, notes);
}

ModelChoice ModelChooser::fall_back(const std::string& what,
                                    const std::vector<std::string>& notes) const {
  const std::string details = notes.empty() ? "" : " [" + joined(notes, "; ") + "]";
  for (const ModelCandidate& candidate : all_)
    if (candidate.name == default_model_)
      return {candidate.name, ChoiceReason::kDefault,
              what + ": the repository's default model" + details};
  std::vector<std::string> names;
  for (const ModelCandidate& candidate : all_) names.push_back(candidate.name);
  return {"", ChoiceReason::kDefault,
          what + " and the server has no default model; name one of: " +
              (names.empty() ? std::string("(none loaded)") : joined(names, ", ")) + details};
}

}  // namespace primlabel::pipeline
