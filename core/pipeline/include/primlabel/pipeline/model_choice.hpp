#pragma once
// Which model labels a cloud whose request names none: the one whose recorded domain fits it.
//
// A model's domain is what its training scans were (TrainingSummary): the sensor, whether they
// were organised frames and of which size, and the ranges of their signatures as acquired
// (cloud_signature.hpp: point spacing and roughness). The choice goes in two steps, the second
// only when the first leaves it open, because it costs a neighbour index over the cloud:
//   1. the shape the request announces: an organised frame fits the models trained on frames of
//      its size, leaves open those trained on frames of another size, and fits no model trained
//      on unorganised scans; an unorganised cloud says nothing;
//   2. the cloud's signature (spacing, roughness, noise growth with range) against each
//      remaining model's ranges, widened by kSignatureTolerance and kNoiseGrowthTolerance.
// One model left fitting: it labels the cloud (by domain). Several or none: the repository's
// default model, when there is one. Otherwise the request is refused, naming the candidates.
// No transport here: the server maps the refusal to its status.

#include <optional>
#include <string>
#include <vector>

#include "primlabel/geometry/cloud_signature.hpp"
#include "primlabel/model/label_model.hpp"

namespace primlabel::pipeline {

// A spacing and roughness within this factor of a model's training range fit it: about the
// spread of one sensor's spacing over a table's depth, and twice its noise.
inline constexpr float kSignatureTolerance = 2.0f;
// A noise growth exponent within this much of a model's training range fits it: a quarter of
// the way between a laser scanner's (0) and a depth camera's (2).
inline constexpr float kNoiseGrowthTolerance = 0.5f;
// A cloud with at least this fraction of depth ties (geometry/cloud_signature.hpp) has quantised
// depth; a model whose training scans never reached half of it does not fit such a cloud.
inline constexpr float kQuantisedDepthTies = 0.1f;

// The organisation a request announces (0 x 0: unorganised or not said).
struct CloudShape {
  std::uint32_t width = 0, height = 0;
  bool organized() const { return height > 1 && width > 0; }
};

enum class DomainFit {
  kFits,     // the recorded domain covers the cloud
  kUnknown,  // the model records nothing that tells (an older file) or the cloud shows nothing
  kOutside,  // the recorded domain excludes the cloud
};

struct DomainVerdict {
  DomainFit fit = DomainFit::kUnknown;
  std::string why;  // one phrase, e.g. "trained on 640x480 frames"
};

DomainVerdict judge_shape(const TrainingSummary& training, const CloudShape& shape);
DomainVerdict judge_signature(const TrainingSummary& training, const CloudSignature& signature);

// How the model of a request was chosen.
enum class ChoiceReason { kNamed, kDomain, kDefault };
const char* choice_reason_name(ChoiceReason reason);  // "named", "domain", "default"

struct ModelCandidate {
  std::string name;
  const TrainingSummary* training = nullptr;  // must outlive the chooser
};

struct ModelChoice {
  std::string model;  // empty: refused (see `why`)
  ChoiceReason reason = ChoiceReason::kDomain;
  std::string why;  // one line: what decided, or why nothing could
};

class ModelChooser {
 public:
  // `candidates`: the models served, in a fixed order (by name); `default_model` empty when the
  // repository declares none.
  ModelChooser(std::vector<ModelCandidate> candidates, std::string default_model,
               const CloudShape& shape);

  // Decided from the shape alone (no signature needed); else needs_signature().
  bool decided() const { return choice_.has_value(); }
  bool needs_signature() const { return !choice_.has_value(); }
  // The models still in the running after the shape (all of them when it said nothing).
  const std::vector<ModelCandidate>& remaining() const { return remaining_; }
  // Step 2; call only when needs_signature().
  void consider(const CloudSignature& signature);
  // After decided() or consider().
  const ModelChoice& choice() const { return *choice_; }

 private:
  ModelChoice fall_back(const std::string& what, const std::vector<std::string>& notes) const;

  std::vector<ModelCandidate> all_;
  std::string default_model_;
  std::vector<ModelCandidate> remaining_;
  std::vector<std::string> shape_notes_;  // "model: why" for those the shape ruled out
  std::optional<ModelChoice> choice_;
};

}  // namespace primlabel::pipeline
