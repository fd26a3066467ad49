// The fitted truth's own error on synthetic Kinect scenes, and scoring against it.

#include "primlabel/research/truth_check.hpp"

#include <cstdio>

#include "primlabel/geometry/taxonomy.hpp"

namespace primlabel::research {
namespace {

std::string format(const char* fmt, auto... args) {
  char buffer[512];
  std::snprintf(buffer, sizeof buffer, fmt, args...);
  return buffer;
}

std::string class_name(std::uint32_t id) {
  const auto c = class_from_id(id);
  return c ? std::string(name(*c)) : std::to_string(id);
}

std::string confusion_text(const crf::ConfusionMatrix& m) {
  std::string out = format("  %-16s %9s %9s %9s\n", "class", "points", "recall", "precision");
  for (int k = 0; k < m.num_classes(); ++k) {
    const crf::ClassScores s = m.scores(k);
    if (!s.support && !(s.precision >= 0)) continue;
    out += format("  %-16s %9llu %8.1f%% %8.1f%%\n", class_name(m.class_ids()[k]).c_str(),
                  static_cast<unsigned long long>(s.support), 100 * s.recall, 100 * s.precision);
  }
  out += format("  %-16s %9llu %8.1f%%\n", "all", static_cast<unsigned long long>(m.total()),
                100 * m.accuracy());
  return out;
}

}  // namespace

std::vector<std::uint32_t> scored_class_ids() {
  std::vector<std::uint32_t> ids;
  for (PrimitiveClass c : all_classes())
    if (c != PrimitiveClass::kUnknown) ids.push_back(class_id(c));
  return ids;
}

void add_object_points(crf::ConfusionMatrix& confusion, const std::vector<int>& segments,
                       const std::vector<std::uint32_t>& truth,
                       const std::vector<std::uint32_t>& predicted) {
  for (std::size_t i = 0; i < segments.size(); ++i)
    if (segments[i] > 0 && truth[i] != class_id(PrimitiveClass::kUnknown))
      confusion.add(truth[i], predicted[i]);
}

TruthCheck check_truth_on_synthetic(const TruthCheckOptions& options, const RunContext& context) {
  TruthCheck check;
  for (int i = 0; i < options.scenes; ++i) {
    synth::GenerateOptions generate;
    generate.sensor = synth::SensorKind::kKinect;
    generate.seed = synth::set_seed(synth::SceneSet::kTest, options.first + i);
    generate.label_radius = options.truth.label_radius;
    const synth::Generated scene = synth::generate(generate);
    const std::vector<int> segments = synthetic_segments(scene.cloud);
    const ObjectTruth truth = fit_object_truth(scene.cloud, segments, options.truth, context);
    std::vector<bool> box_or_can(scene.scene.objects.size(), false);
    for (std::size_t k = 1; k < scene.scene.objects.size(); ++k) {
      const std::string_view kind = scene.scene.objects[k].shape->kind();
      box_or_can[k] = kind == "box" || kind == "can";
    }
    for (const FittedObject& o : truth.objects)
      ++check.kinds[std::string(scene.scene.objects[o.segment].shape->kind())]
                   [std::string(fitted_kind_name(o.kind))];
    // The fitted truth in the "predicted" place: rows say what the points really are.
    for (std::size_t p = 0; p < segments.size(); ++p) {
      if (segments[p] <= 0) continue;
      const bool regular = box_or_can[segments[p]];
      ++check.all_points;
      check.box_can_points += regular;
      if (truth.labels[p] == class_id(PrimitiveClass::kUnknown)) continue;
      check.all.add(scene.cloud.labels[p], truth.labels[p]);
      if (regular) check.box_can.add(scene.cloud.labels[p], truth.labels[p]);
    }
  }
  return check;
}

std::string truth_check_text(const TruthCheck& check) {
  std::string out = "fitted truth against the synthetic labels (rows: true class)\n";
  out += format("box and can objects: %llu of %llu points labeled\n",
                static_cast<unsigned long long>(check.box_can.total()),
                static_cast<unsigned long long>(check.box_can_points));
  out += confusion_text(check.box_can);
  std::vector<std::string> names;
  for (std::uint32_t id : check.box_can.class_ids()) names.push_back(class_name(id));
  out += "  confusion (rows true, columns fitted):\n" + check.box_can.to_text(names);
  out += format("all objects: %llu of %llu points labeled\n",
                static_cast<unsigned long long>(check.all.total()),
                static_cast<unsigned long long>(check.all_points));
  out += confusion_text(check.all);
  out += "objects (true kind: fitted as)\n";
  for (const auto& [kind, fitted] : check.kinds) {
    out += format("  %-10s", kind.c_str());
    for (const auto& [as, n] : fitted) out += format(" %s %d", as.c_str(), n);
    out += "\n";
  }
  return out;
}

json::Json confusion_classes_json(const crf::ConfusionMatrix& m) {
  json::Json classes = json::Json::object();
  for (int k = 0; k < m.num_classes(); ++k) {
    const crf::ClassScores s = m.scores(k);
    if (!s.support && !(s.precision >= 0)) continue;
    classes[class_name(m.class_ids()[k])] = {{"recall", json::rounded(s.recall, "%.6f")},
                                             {"precision", json::rounded(s.precision, "%.6f")},
                                             {"support", s.support}};
  }
  // The matrix itself (rows truth, columns predicted, then "other": a prediction outside the
  // classes), so reports over several files can be summed exactly and errors traced.
  json::Json names = json::Json::array(), rows = json::Json::array();
  for (int t = 0; t < m.num_classes(); ++t) {
    names.push_back(class_name(m.class_ids()[t]));
    json::Json row = json::Json::array();
    for (int p = 0; p <= m.num_classes(); ++p) row.push_back(m.count(t, p));
    rows.push_back(std::move(row));
  }
  names.push_back("other");
  return {{"points", m.total()},
          {"accuracy", json::rounded(m.accuracy(), "%.6f")},
          {"classes", std::move(classes)},
          {"confusion", {{"columns", std::move(names)}, {"rows", std::move(rows)}}}};
}

std::string truth_check_json(const TruthCheck& check) {
  json::Json kinds = json::Json::object();
  for (const auto& [kind, fitted] : check.kinds) {
    json::Json row = json::Json::object();
    for (const auto& [as, n] : fitted) row[as] = n;
    kinds[kind] = std::move(row);
  }
  const json::Json out = {{"box_can", confusion_classes_json(check.box_can)},
                          {"box_can_points", check.box_can_points},
                          {"all", confusion_classes_json(check.all)},
                          {"all_points", check.all_points},
                          {"objects", std::move(kinds)}};
  return json::dump(out) + "\n";
}

}  // namespace primlabel::research
