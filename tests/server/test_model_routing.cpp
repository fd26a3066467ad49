// A request that names no model goes to the model whose recorded domain fits its cloud (the
// sensor and image size first, then the cloud's spacing and roughness), else to the
// repository's default, else it is refused naming the candidates; the summary, the log and the
// metrics say how the model was chosen. A named model used outside its domain warns.

#include <gtest/gtest.h>

#include <cfloat>
#include <cmath>
#include <fstream>
#include <random>

#include "primlabel/geometry/cloud_signature.hpp"
#include "server_test_util.hpp"

namespace primlabel::servertest {
namespace {

using testing::random_label_model;
using testing::table_with_box_cloud;

// `name`, trained (as its record says) on `width` x `height` frames (0 x 0: unorganised
// scans), with signature ranges around `around` (factor `spread` each way) or far from it.
LabelModel model_with_domain(const std::string& name, std::uint32_t width, std::uint32_t height,
                             const CloudSignature& around, bool fits, float spread = 1.2f) {
  LabelModel model = random_label_model(name, "1");
  TrainingSummary& t = model.training;
  t.sensor = height > 1 ? "camera" : "scanner";
  t.image_width = width, t.image_height = height;
  const float away = fits ? 1.0f : 10.0f;  // ten times coarser and rougher: outside the 2x
  t.acquired_spacing_min = around.point_spacing * away / spread;
  t.acquired_spacing_max = around.point_spacing * away * spread;
  // A noise-free synthetic cloud has no roughness to speak of: only its spacing is recorded.
  t.roughness_min = around.roughness * away / spread;
  t.roughness_max = around.roughness * away * spread;
  return model;
}

// The cloud as a frame of two rows (points even).
v1::ScanHeader frame_header(const PointCloud& cloud, const std::string& model = "") {
  v1::ScanHeader header = header_for(model);
  header.mutable_layout()->set_width(std::uint32_t(cloud.size() / 2));
  header.mutable_layout()->set_height(2);
  return header;
}

PointCloud even_cloud() {
  PointCloud cloud = table_with_box_cloud(0.01f);
  if (cloud.size() % 2) cloud.xyz.pop_back(), cloud.width = std::uint32_t(cloud.size());
  return cloud;
}

void declare_default(const TestServer& server, const std::string& model) {
  std::ofstream(server.repo.path() / "default_model") << model << "\n";
  server.server->registry().reload();
}

TEST(ModelRouting, AFrameNamingNoModelGoesToTheModelTrainedOnFramesOfItsSize) {
  const PointCloud cloud = even_cloud();
  const auto signature = measure_signature(cloud.xyz, cloud.viewpoint.origin);
  const std::uint32_t width = std::uint32_t(cloud.size() / 2);
  // The scanner model fits the cloud's signature too: the frame's shape decides before it.
  const LabelModel camera = model_with_domain("cam", width, 2, signature, false);
  const LabelModel scanner = model_with_domain("laser", 0, 0, signature, true);
  TestServer server({camera, scanner}, [](ops::ServerConfig& c) { c.default_model = "laser"; });
  for (bool streamed : {true, false}) {
    const LabelAnswer answer =
        streamed ? label_stream(*server.stub, scan_requests(cloud, frame_header(cloud)))
                 : label_cloud(*server.stub, cloud, frame_header(cloud));
    ASSERT_TRUE(answer.status.ok()) << answer.status.error_message();
    EXPECT_EQ(answer.summary->model(), "cam");
    EXPECT_EQ(answer.summary->model_choice(), v1::MODEL_CHOICE_DOMAIN);
    EXPECT_NE(answer.summary->model_choice_reason().find(std::to_string(width) + "x2"),
              std::string::npos)
        << answer.summary->model_choice_reason();
    EXPECT_EQ(answer.labels, reference_labels(camera, cloud));
  }
  // Unorganised, the same points go by their signature: the scanner's.
  const LabelAnswer scan = label_cloud(*server.stub, cloud, header_for(""));
  ASSERT_TRUE(scan.status.ok()) << scan.status.error_message();
  EXPECT_EQ(scan.summary->model(), "laser");
  EXPECT_EQ(scan.summary->model_choice(), v1::MODEL_CHOICE_DOMAIN);
  EXPECT_EQ(scan.labels, reference_labels(scanner, cloud));

  const auto samples = scrape_metrics(server.server->metrics_port());
  EXPECT_EQ(scrape::sum_samples(samples, "primlabel_model_choices_total",
                                {{"model", "cam"}, {"reason", "domain"}}),
            2.0);
  EXPECT_EQ(scrape::sum_samples(samples, "primlabel_model_choices_total",
                                {{"model", "laser"}, {"reason", "domain"}}),
            1.0);
}

TEST(ModelRouting, AnUnorganisedCloudGoesToTheOnlyModelItsSignatureFits) {
  const PointCloud cloud = even_cloud();
  const auto signature = measure_signature(cloud.xyz, cloud.viewpoint.origin);
  const LabelModel near = model_with_domain("near", 640, 480, signature, true);
  const LabelModel far = model_with_domain("far", 0, 0, signature, false);
  TestServer server({far, near}, [](ops::ServerConfig& c) { c.default_model = "far"; });
  const LabelAnswer answer = label_stream(*server.stub, scan_requests(cloud, header_for("")));
  ASSERT_TRUE(answer.status.ok()) << answer.status.error_message();
  EXPECT_EQ(answer.summary->model(), "near");
  EXPECT_EQ(answer.summary->model_choice(), v1::MODEL_CHOICE_DOMAIN);
  EXPECT_NE(answer.summary->model_choice_reason().find("spacing"), std::string::npos);
}

TEST(ModelRouting, WhenSeveralOrNoneFitTheRepositorysDefaultFileDecides) {
  const PointCloud cloud = even_cloud();
  const auto signature = measure_signature(cloud.xyz, cloud.viewpoint.origin);
  TestServer server({model_with_domain("a", 0, 0, signature, true),
                     model_with_domain("b", 0, 0, signature, true)});
  // No default: refused, naming both.
  const LabelAnswer refused = label_cloud(*server.stub, cloud, header_for(""));
  EXPECT_EQ(refused.status.error_code(), grpc::StatusCode::NOT_FOUND);
  EXPECT_NE(refused.status.error_message().find(": a, b)"), std::string::npos)
      << refused.status.error_message();
  EXPECT_NE(refused.status.error_message().find("several models fit"), std::string::npos)
      << refused.status.error_message();

  declare_default(server, "b");
  EXPECT_EQ(server.server->registry().default_model(), "b");
  EXPECT_EQ(server.server->registry().default_source(), "repository");
  const LabelAnswer answer = label_cloud(*server.stub, cloud, header_for(""));
  ASSERT_TRUE(answer.status.ok()) << answer.status.error_message();
  EXPECT_EQ(answer.summary->model(), "b");
  EXPECT_EQ(answer.summary->model_choice(), v1::MODEL_CHOICE_DEFAULT);

  // The file follows the repository: a new default is read at the next scan, a bad one ignored.
  declare_default(server, "a");
  EXPECT_EQ(server.server->registry().default_model(), "a");
  declare_default(server, "../etc/passwd");
  EXPECT_EQ(server.server->registry().default_model(), "");
  declare_default(server, std::string(100000, 'a'));  // read no further than its bound
  EXPECT_EQ(server.server->registry().default_model(), "");
  std::filesystem::remove(server.repo.path() / "default_model");
  server.server->registry().reload();
  EXPECT_EQ(server.server->registry().default_model(), "");  // two models: no safe guess
}

TEST(ModelRouting, TheDefaultFlagOverridesTheRepositorysFile) {
  const PointCloud cloud = even_cloud();
  const auto signature = measure_signature(cloud.xyz, cloud.viewpoint.origin);
  TestServer server({model_with_domain("a", 0, 0, signature, true),
                     model_with_domain("b", 0, 0, signature, true)},
                    [](ops::ServerConfig& c) { c.default_model = "a"; });
  declare_default(server, "b");
  EXPECT_EQ(server.server->registry().default_model(), "a");
  EXPECT_EQ(server.server->registry().default_source(), "flag");
}

TEST(ModelRouting, ANamedModelKeepsItsNameAndWarnsOutsideItsDomain) {
  const PointCloud cloud = even_cloud();
  const auto signature = measure_signature(cloud.xyz, cloud.viewpoint.origin);
  TestServer server({model_with_domain("laser", 0, 0, signature, true)});
  const LabelAnswer named = label_cloud(*server.stub, cloud, frame_header(cloud, "laser"));
  ASSERT_TRUE(named.status.ok()) << named.status.error_message();
  EXPECT_EQ(named.summary->model_choice(), v1::MODEL_CHOICE_NAMED);
  EXPECT_NE(named.summary->domain_warning().find("organised"), std::string::npos)
      << named.summary->domain_warning();
  const LabelAnswer unorganised = label_cloud(*server.stub, cloud, header_for("laser"));
  ASSERT_TRUE(unorganised.status.ok());
  EXPECT_EQ(unorganised.summary->domain_warning().find("organised"), std::string::npos);
}

TEST(ModelRouting, AFrameLayoutMustMatchThePoints) {
  const PointCloud cloud = even_cloud();
  TestServer server({random_label_model("m", "1")});
  v1::ScanHeader header = header_for("m");
  header.mutable_layout()->set_width(3);
  header.mutable_layout()->set_height(2);  // 6 pixels, not the cloud's points
  for (bool streamed : {true, false}) {
    const LabelAnswer answer = streamed ? label_stream(*server.stub, scan_requests(cloud, header))
                                        : label_cloud(*server.stub, cloud, header);
    EXPECT_EQ(answer.status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
    EXPECT_NE(answer.status.error_message().find("layout.width x layout.height"), std::string::npos)
        << answer.status.error_message();
  }
  header.mutable_layout()->set_height(0);  // a width alone
  EXPECT_EQ(label_cloud(*server.stub, cloud, header).status.error_code(),
            grpc::StatusCode::INVALID_ARGUMENT);
  header.mutable_layout()->set_width(0xFFFFFFFFu);  // 2^64 pixels would overflow 32 bits
  header.mutable_layout()->set_height(0xFFFFFFFFu);
  const LabelAnswer huge = label_cloud(*server.stub, cloud, header);
  EXPECT_EQ(huge.status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_NE(huge.status.error_message().find("at most"), std::string::npos)
      << huge.status.error_message();
  EXPECT_TRUE(label_cloud(*server.stub, cloud, header_for("m")).status.ok());  // still serving
}

// Clouds an attacker or a broken sensor sends, naming no model, to a server whose models need
// the signature to choose: each gets an answer in bounded time and the server keeps serving.
TEST(ModelRouting, HostileCloudsNamingNoModelAreChosenForInBoundedTime) {
  const PointCloud table = even_cloud();
  const auto signature = measure_signature(table.xyz, table.viewpoint.origin);
  TestServer server({model_with_domain("a", 0, 0, signature, true),
                     model_with_domain("b", 0, 0, signature, false)},
                    [](ops::ServerConfig& c) { c.default_model = "b"; });
  const float nan = std::nanf("");
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> mm(0.0f, 0.001f);
  std::vector<Vec3f> cube(20000);
  for (Vec3f& p : cube) p = Vec3f(mm(rng), mm(rng), 0.5f + mm(rng));
  std::vector<Vec3f> far = table.xyz;
  far.insert(far.end(), {{1e30f, 0, 0}, {FLT_MAX, FLT_MAX, -FLT_MAX}, {0.1f, -1e18f, 3}});
  const std::vector<std::pair<const char*, std::vector<Vec3f>>> clouds = {
      {"coincident", std::vector<Vec3f>(100000, Vec3f(0.1f, 0.2f, 0.3f))},
      {"millimetre cube", cube},
      {"far points", far},
      {"all NaN but one",
       [&] {
         std::vector<Vec3f> points(5000, Vec3f(nan, nan, nan));
         points[17] = Vec3f(0, 0, 1);
         return points;
       }()},
  };
  for (const auto& [what, points] : clouds) {
    SCOPED_TRACE(what);
    PointCloud cloud;
    cloud.resize_unorganized(points.size());
    cloud.xyz = points;
    const auto start = std::chrono::steady_clock::now();
    const LabelAnswer answer =
        label_stream(*server.stub, scan_requests(cloud, header_for("")), std::chrono::seconds(60));
    const double seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    ASSERT_TRUE(answer.status.ok()) << answer.status.error_message();
    EXPECT_EQ(answer.labels.size(), points.size());
    EXPECT_NE(answer.summary->model_choice(), v1::MODEL_CHOICE_UNSPECIFIED);
    EXPECT_LT(seconds, 30.0);
  }
  const LabelAnswer legit = label_cloud(*server.stub, table, header_for(""));
  ASSERT_TRUE(legit.status.ok()) << legit.status.error_message();
  EXPECT_EQ(legit.summary->model(), "a");  // still chosen by its domain
}

}  // namespace
}  // namespace primlabel::servertest
