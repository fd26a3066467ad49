// Model files: what is saved comes back, and every kind of broken file is refused with a
// message that names the file and the problem.

#include <gtest/gtest.h>
#include <zlib.h>

#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <limits>

#include "primlabel/geometry/taxonomy.hpp"
#include "primlabel/model/label_model.hpp"
#include "primlabel/v1/model.pb.h"
#include "test_util.hpp"

namespace primlabel {
namespace {

using test::write_bytes;

LabelModel sample_crf() {
  LabelModel m;
  m.name = "tabletop";
  m.version = "7";
  m.kind = ModelKind::kCrf;
  m.features.normals = Neighborhood::Radius(0.012f);
  m.features.features = Neighborhood::Hybrid(0.025f, 300);
  m.features.fpfh_variant = FpfhVariant::kWithOwnSpfh;
  m.graph.neighborhood = Neighborhood::Knn(8);
  m.weights =
      crf::CrfModel::zeros({class_id(PrimitiveClass::kPlane), class_id(PrimitiveClass::kEdgeConvex),
                            class_id(PrimitiveClass::kCylinderConvex)},
                           kFpfhSize);
  m.weights.node_weights.setRandom();
  m.weights.edge_weights.setRandom();
  m.inference.max_product = true;
  m.inference.max_iterations = 17;
  m.training.sources = {"synth lms400 train 1000-1019"};
  m.training.scenes = 20;
  m.training.points = 1750000;
  m.training.class_points = {1000000, 500000, 250000};
  m.training.objective = "pseudo-likelihood";
  m.training.class_balance = 0.5;
  m.training.class_weights = {0.25, 0.5, 1.5};
  m.training.data_attribution = "Scans by A. N. Other, CC-BY 4.0";
  m.validation.accuracy = 0.975;
  m.validation.per_class = {{0.99, 0.98, 0.985, 100}, {0.9, 0.8, 0.85, 10}, {0.7, 0.6, 0.65, 5}};
  m.created_unix_ms = 1763776800000;
  m.created_by = "test";
  return m;
}

// An SVM over three classes with three support vectors, in libsvm's text format.
LabelModel sample_svm() {
  LabelModel m = sample_crf();
  m.kind = ModelKind::kSvm;
  m.svm_model =
      "svm_type c_svc\nkernel_type rbf\ngamma 0.5\nnr_class 3\ntotal_sv 3\nrho 0.1 0.2 0.3\n"
      "label 0 1 2\nnr_sv 1 1 1\nSV\n1 0.5 1:0.25 7:1 \n-1 0.5 2:0.5 \n-0.5 -1 33:0.125 \n";
  m.svm_class_ids = m.weights.class_ids;
  m.weights.feature_scale = 0.02f;
  return m;
}

LabelModel load_model_bytes_roundtrip(const test::TempDir& dir, const LabelModel& model) {
  save_model(dir.file("roundtrip.plm"), model);
  return load_model(dir.file("roundtrip.plm"));
}

TEST(LabelModel, CrfRoundTrip) {
  test::TempDir dir;
  const LabelModel saved = sample_crf();
  save_model(dir.file("m.plm"), saved);
  const LabelModel loaded = load_model(dir.file("m.plm"));
  EXPECT_EQ(loaded.name, "tabletop");
  EXPECT_EQ(loaded.version, "7");
  EXPECT_EQ(loaded.kind, ModelKind::kCrf);
  EXPECT_EQ(loaded.class_ids(), saved.class_ids());
  EXPECT_EQ(loaded.features.fpfh_variant, FpfhVariant::kWithOwnSpfh);
  EXPECT_EQ(loaded.features.features.radius, 0.025f);
  EXPECT_EQ(loaded.features.features.max_neighbors, 300);
  EXPECT_EQ(loaded.features.normals.radius, 0.012f);
  EXPECT_EQ(loaded.graph.neighborhood.k, 8);
  EXPECT_TRUE(loaded.weights.node_weights == saved.weights.node_weights);
  EXPECT_TRUE(loaded.weights.edge_weights == saved.weights.edge_weights);
  EXPECT_TRUE(loaded.inference.max_product);
  EXPECT_EQ(loaded.inference.max_iterations, 17);
  EXPECT_EQ(loaded.training.class_points, saved.training.class_points);
  EXPECT_EQ(loaded.training.class_balance, 0.5);
  EXPECT_EQ(loaded.training.class_weights, saved.training.class_weights);
  EXPECT_EQ(loaded.training.data_attribution, saved.training.data_attribution);
  EXPECT_EQ(loaded.validation.per_class.size(), 3u);
  EXPECT_DOUBLE_EQ(loaded.validation.per_class[1].f1, 0.85);
  EXPECT_EQ(loaded.created_unix_ms, saved.created_unix_ms);
}

// Model files go through the one atomic writer: no fixed "<path>.tmp" that two trainers (or a
// stale leftover) share, nothing left beside the file, and a failed save keeps the old model.
TEST(LabelModel, SavesAtomicallyWithoutASharedTemporaryName) {
  test::TempDir dir;
  const std::string path = dir.file("m.plm");
  std::filesystem::create_directories(path + ".tmp/stale");  // blocked the old fixed name
  save_model(path, sample_crf());
  EXPECT_EQ(load_model(path).name, "tabletop");
  std::size_t entries = 0;
  for (const auto& entry : std::filesystem::directory_iterator(dir.file(""))) {
    (void)entry;
    ++entries;
  }
  EXPECT_EQ(entries, 2u);  // m.plm and the stale m.plm.tmp/, no temporary of ours
  std::filesystem::create_directories(dir.file("busy/inside"));
  try {
    save_model(dir.file("busy"), sample_crf());
    FAIL() << "saved over a directory";
  } catch (const ModelError& e) {
    EXPECT_NE(std::string(e.what()).find(dir.file("busy")), std::string::npos) << e.what();
  }
  EXPECT_TRUE(std::filesystem::is_directory(dir.file("busy/inside")));
}

// A file written before the persisted settings were split from the run state (by
// write_fixture at commit a9ed7c5, when LabelModel held InferenceOptions / GraphOptions with
// threads and stop tokens) loads into GraphSettings / InferenceSettings and serialises back to the
// same bytes: the file format did not change.
TEST(LabelModel, AFileWrittenBeforeTheRunContextLoadsUnchanged) {
  const std::string path = test::test_data("models/crf_before_run_context.plm");
  const LabelModel m = load_model(path);
  EXPECT_EQ(m.name, "written-before-run-context");
  EXPECT_EQ(m.graph.neighborhood.radius, 0.03f);
  EXPECT_EQ(m.graph.neighborhood.max_neighbors, 12);
  EXPECT_EQ(m.inference.method, crf::InferenceMethod::kMeanField);
  EXPECT_TRUE(m.inference.max_product);
  EXPECT_EQ(m.inference.max_iterations, 17);
  EXPECT_EQ(m.inference.damping, 0.25f);
  EXPECT_EQ(m.inference.tolerance, 1e-4f);
  EXPECT_EQ(m.weights.node_weights(1, 2), 0.01f * float((37 + 22) % 23) - 0.1f);
  EXPECT_EQ(m.weights.edge_weights(2, 4), 0.002f * float((10 + 12) % 7));
  EXPECT_EQ(m.training.class_balance, 0.0);  // older files: the unweighted objective
  EXPECT_FALSE(m.features.shape_evidence);     // older files: no shape evidence
  EXPECT_TRUE(m.training.class_weights.empty());
  std::ifstream in(path, std::ios::binary);
  const std::string bytes{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
  EXPECT_EQ(serialize_model(m), bytes);
}

TEST(LabelModel, NodeOnlyAndSvmRoundTrip) {
  LabelModel node = sample_crf();
  node.kind = ModelKind::kNodeOnly;
  const LabelModel node_back = parse_model(serialize_model(node), "node");
  EXPECT_EQ(node_back.kind, ModelKind::kNodeOnly);
  EXPECT_TRUE(node_back.weights.edge_weights.isZero());
  EXPECT_TRUE(node_back.weights.node_weights == node.weights.node_weights);

  const LabelModel svm = sample_svm();
  const LabelModel svm_back = parse_model(serialize_model(svm), "svm");
  EXPECT_EQ(svm_back.kind, ModelKind::kSvm);
  EXPECT_EQ(svm_back.svm_model, svm.svm_model);
  EXPECT_EQ(svm_back.class_ids(), svm.class_ids());
  EXPECT_EQ(svm_back.weights.feature_scale, 0.02f);
}

TEST(LabelModel, SvmWithBrokenLibsvmTextIsRefusedOnLoad) {
  // A file from another writer: valid envelope and checksum, but the libsvm text is cut short.
  v1::ModelEnvelope envelope;
  const std::string bytes = serialize_model(sample_svm());
  ASSERT_TRUE(envelope.ParseFromString(bytes.substr(16)));
  v1::Model model;
  ASSERT_TRUE(model.ParseFromString(envelope.model()));
  const std::string text = model.svm().libsvm_model();
  model.mutable_svm()->set_libsvm_model(text.substr(0, text.find("\n-1 ") + 1));
  envelope.set_model(model.SerializeAsString());
  envelope.set_model_crc32(
      static_cast<std::uint32_t>(crc32(0L, reinterpret_cast<const Bytef*>(envelope.model().data()),
                                       static_cast<uInt>(envelope.model().size()))));
  try {
    parse_model(bytes.substr(0, 16) + envelope.SerializeAsString(), "cut.plm");
    FAIL() << "accepted a truncated SVM";
  } catch (const ModelError& e) {
    EXPECT_NE(std::string(e.what()).find("cut.plm: SVM model: libsvm model, line 10: only 1 of 3 "
                                         "support vectors (truncated?)"),
              std::string::npos)
        << e.what();
  }
}

// A file another writer produced: the model message re-encoded under a valid envelope.
std::string rewrap(const std::string& bytes, const std::function<void(v1::Model&)>& change) {
  v1::ModelEnvelope envelope;
  EXPECT_TRUE(envelope.ParseFromString(bytes.substr(16)));
  v1::Model model;
  EXPECT_TRUE(model.ParseFromString(envelope.model()));
  change(model);
  envelope.set_model(model.SerializeAsString());
  envelope.set_model_crc32(
      static_cast<std::uint32_t>(crc32(0L, reinterpret_cast<const Bytef*>(envelope.model().data()),
                                       static_cast<uInt>(envelope.model().size()))));
  return bytes.substr(0, 16) + envelope.SerializeAsString();
}

TEST(LabelModel, TentBasisRoundTripAndMismatchedKnotsAreRefused) {
  LabelModel saved = sample_crf();
  saved.weights =
      crf::CrfModel::zeros(saved.weights.class_ids, kFpfhSize, 0.01f, crf::default_node_knots());
  saved.weights.node_weights.setRandom();
  ASSERT_EQ(saved.weights.node_weights.cols(),
            kFpfhSize * int(crf::default_node_knots().size()) + 1);
  const std::string bytes = serialize_model(saved);
  const LabelModel loaded = parse_model(bytes, "tent.plm");
  EXPECT_EQ(loaded.weights.node_knots, crf::default_node_knots());
  EXPECT_TRUE(loaded.weights.node_weights == saved.weights.node_weights);

  // One knot dropped: the weights no longer fit the basis.
  const std::string dropped =
      rewrap(bytes, [](v1::Model& m) { m.mutable_crf()->mutable_node_knots()->RemoveLast(); });
  try {
    parse_model(dropped, "dropped.plm");
    FAIL() << "accepted weights that do not fit the knots";
  } catch (const ModelError& e) {
    EXPECT_NE(std::string(e.what()).find("dropped.plm"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("node_weights"), std::string::npos) << e.what();
  }
  // Knots out of order.
  const std::string unordered =
      rewrap(bytes, [](v1::Model& m) { m.mutable_crf()->set_node_knots(1, 2.0f); });
  try {
    parse_model(unordered, "unordered.plm");
    FAIL() << "accepted knots that do not increase";
  } catch (const ModelError& e) {
    EXPECT_NE(std::string(e.what()).find("not finite and increasing"), std::string::npos)
        << e.what();
  }
}

std::string load_error(const std::string& path) {
  try {
    load_model(path);
  } catch (const ModelError& e) {
    return e.what();
  }
  return "";
}

// The opt-in sampled FPFH (feature_sample_size) survives a save, and a model that carries a
// negative or non-finite one is refused on load instead of describing nothing.
TEST(LabelModel, FeatureSampleSizeRoundTripsAndBadValuesAreRefused) {
  test::TempDir dir;
  LabelModel saved = sample_crf();
  EXPECT_EQ(load_model_bytes_roundtrip(dir, saved).features.feature_sample_size, 0.0f);
  saved.features.feature_sample_size = 0.004f;
  EXPECT_EQ(load_model_bytes_roundtrip(dir, saved).features.feature_sample_size, 0.004f);
  for (const float bad :
       {-0.004f, std::numeric_limits<float>::quiet_NaN(), std::numeric_limits<float>::infinity()}) {
    saved.features.feature_sample_size = bad;
    save_model(dir.file("bad.plm"), saved);
    EXPECT_NE(load_error(dir.file("bad.plm")).find("feature_sample_size"), std::string::npos)
        << bad;
  }
}

TEST(LabelModel, BrokenFilesAreRefusedWithTheirNameAndReason) {
  test::TempDir dir;
  const std::string good = serialize_model(sample_crf());

  EXPECT_NE(load_error(dir.file("missing.plm")).find("missing.plm: no such model file"),
            std::string::npos);

  write_bytes(dir.file("text.plm"), "hello, I am a PCD file\n");
  EXPECT_NE(load_error(dir.file("text.plm")).find("not a primlabel model file"), std::string::npos);

  for (std::size_t cut : {good.size() / 2, good.size() - 3, std::size_t(20)}) {
    write_bytes(dir.file("cut.plm"), good.substr(0, cut));
    const std::string error = load_error(dir.file("cut.plm"));
    EXPECT_NE(error.find("cut.plm: "), std::string::npos) << cut;
    EXPECT_TRUE(error.find("truncated") != std::string::npos ||
                error.find("checksum") != std::string::npos)
        << error;
  }

  std::string flipped = good;
  flipped[flipped.size() - 40] ^= 0x5A;  // inside the weights
  write_bytes(dir.file("flip.plm"), flipped);
  const std::string flip_error = load_error(dir.file("flip.plm"));
  EXPECT_TRUE(flip_error.find("checksum mismatch") != std::string::npos ||
              flip_error.find("corrupt") != std::string::npos)
      << flip_error;
}

TEST(LabelModel, NewerFormatAndInconsistentModelsAreRefused) {
  // Rewrite the envelope's version field (field 1, varint) to 99.
  std::string bytes = serialize_model(sample_crf());
  ASSERT_EQ(bytes[16], 0x08);
  ASSERT_EQ(bytes[17], static_cast<char>(kModelFormatVersion));
  bytes[17] = 99;
  try {
    parse_model(bytes, "future.plm");
    FAIL() << "accepted a newer format";
  } catch (const ModelError& e) {
    EXPECT_NE(std::string(e.what()).find("format version 99 is newer"), std::string::npos);
  }

  LabelModel bad = sample_crf();
  bad.weights.node_weights.resize(3, 10);  // not 33 + 1 columns
  EXPECT_THROW(serialize_model(bad), ModelError);
  LabelModel unknown_class = sample_crf();
  unknown_class.weights.class_ids[2] = 4242;
  EXPECT_THROW(serialize_model(unknown_class), ModelError);
}

}  // namespace
}  // namespace primlabel
