// The registry, configuration and start-up against a hostile client or a careless operator, on
// an in-process server on 127.0.0.1: admin RPCs without a token, unload until reload, a model
// directory moved away and back under load, a second model added under load, symlinks out of
// the repository, zero-length client normals, megabyte names, and health following the
// registry whoever changes it. (Start-up failures of the binary: test_server_process.)

#include <fcntl.h>

#include <fstream>
#include <sstream>
#include <thread>

#include "primlabel/service/model_registry.hpp"
#include "server_test_util.hpp"

namespace primlabel::servertest {
namespace {

using rpc::kLabelerServiceName;
using service::ModelRegistry;
using service::RegistryError;
using testing::random_label_model;
using testing::table_with_box_cloud;

constexpr std::size_t kShortMessage = 1000;  // a status naming a huge string stays this short

void insecure_admin(ops::ServerConfig& config) { config.insecure_admin = true; }

grpc::Status unload(TestServer& server, const std::string& model, const std::string& version = "") {
  v1::UnloadModelRequest request;
  request.set_model(model);
  request.set_version(version);
  v1::UnloadModelResponse response;
  grpc::ClientContext context;
  context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(30));
  return server.admin->UnloadModel(&context, request, &response);
}

grpc::Status reload(TestServer& server, v1::ReloadModelsResponse* out = nullptr) {
  v1::ReloadModelsResponse response;
  grpc::ClientContext context;
  context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(30));
  const grpc::Status status = server.admin->ReloadModels(&context, {}, &response);
  if (out) *out = response;
  return status;
}

grpc::Status load(TestServer& server, const std::string& model) {
  v1::LoadModelRequest request;
  request.set_model(model);
  v1::LoadModelResponse response;
  grpc::ClientContext context;
  context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(30));
  return server.admin->LoadModel(&context, request, &response);
}

grpc::Status metadata(TestServer& server, const std::string& model, v1::ModelMetadata* out) {
  v1::GetModelMetadataRequest request;
  request.set_model(model);
  grpc::ClientContext context;
  context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(30));
  return server.stub->GetModelMetadata(&context, request, out);
}

// Requests that name no model, on `threads` threads, until stopped: every status is kept.
class DefaultModelLoad {
 public:
  DefaultModelLoad(TestServer& server, const PointCloud& cloud) {
    threads_.emplace_back([&server, &cloud, this] {
      const auto requests = scan_requests(cloud, header_for());
      while (!stop_) record(label_stream(*server.stub, requests, std::chrono::seconds(30)).status);
    });
    threads_.emplace_back([&server, this] {
      while (!stop_) {
        v1::ModelMetadata out;
        record(metadata(server, "", &out));
        std::this_thread::sleep_for(std::chrono::milliseconds(2));
      }
    });
  }
  ~DefaultModelLoad() { finish(); }

  void finish() {
    stop_ = true;
    for (std::thread& thread : threads_)
      if (thread.joinable()) thread.join();
  }
  int ok() const { return ok_; }
  int failed() const { return failed_; }
  std::string first_failure() {
    std::lock_guard lock(mutex_);
    return first_failure_;
  }

 private:
  void record(const grpc::Status& status) {
    if (status.ok()) {
      ++ok_;
      return;
    }
    if (failed_++ == 0) {
      std::lock_guard lock(mutex_);
      first_failure_ = std::to_string(status.error_code()) + ": " + status.error_message();
    }
  }

  std::atomic<bool> stop_{false};
  std::atomic<int> ok_{0}, failed_{0};
  std::mutex mutex_;
  std::string first_failure_;
  std::vector<std::thread> threads_;
};

TEST(HostileAdmin, RefusedWithoutATokenUnlessInsecureAdminIsGiven) {
  TestServer server({random_label_model("m", "1")});
  for (const grpc::Status& status : {unload(server, "m"), reload(server), load(server, "m")}) {
    EXPECT_EQ(status.error_code(), grpc::StatusCode::PERMISSION_DENIED) << status.error_message();
    EXPECT_NE(status.error_message().find("--token-file"), std::string::npos);
    EXPECT_NE(status.error_message().find("--insecure-admin"), std::string::npos);
  }
  EXPECT_EQ(server.server->registry().loaded_versions(), 1u);  // nothing was unloaded
  EXPECT_EQ(health_status(server.channel, kLabelerServiceName), "SERVING");

  TestServer open({random_label_model("m", "1")}, insecure_admin);
  EXPECT_TRUE(unload(open, "m").ok());
}

TEST(HostileAdmin, AnUnloadLastsUntilTheNextReload) {
  TestServer server({random_label_model("m", "1")}, insecure_admin);
  const PointCloud cloud = table_with_box_cloud(0.02f);
  ASSERT_TRUE(unload(server, "m").ok());
  EXPECT_EQ(health_status(server.channel, kLabelerServiceName), "NOT_SERVING");
  // The periodic scan does not undo an explicit unload ...
  server.server->registry().rescan();
  EXPECT_EQ(label_cloud(*server.stub, cloud, header_for()).status.error_code(),
            grpc::StatusCode::NOT_FOUND);
  // ... ReloadModels does.
  v1::ReloadModelsResponse reloaded;
  ASSERT_TRUE(reload(server, &reloaded).ok());
  ASSERT_EQ(reloaded.models_size(), 1);
  EXPECT_EQ(reloaded.models(0).name(), "m");
  EXPECT_EQ(health_status(server.channel, kLabelerServiceName), "SERVING");
  const LabelAnswer answer = label_cloud(*server.stub, cloud, header_for());
  EXPECT_TRUE(answer.status.ok()) << answer.status.error_message();
}

TEST(HostileRegistry, AModelDirectoryMovedAwayAndBackUnderLoadKeepsServing) {
  // Polls every 50 ms; a version must be missing at 40 scans in a row (2 s) to go.
  TestServer server({random_label_model("m", "1")}, [](ops::ServerConfig& c) {
    c.reload_seconds = 0.05;
    c.unload_after_missing_polls = 40;
  });
  const PointCloud cloud = table_with_box_cloud(0.02f);
  const fs::path away =
      server.repo.path().parent_path() / (server.repo.path().filename().string() + "_away");
  DefaultModelLoad clients(server, cloud);
  std::this_thread::sleep_for(std::chrono::milliseconds(200));
  fs::rename(server.repo.path() / "m", away);
  std::this_thread::sleep_for(std::chrono::milliseconds(600));  // about 12 polls see it missing
  EXPECT_EQ(server.server->registry().loaded_versions(), 1u);
  fs::rename(away, server.repo.path() / "m");
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  clients.finish();
  EXPECT_EQ(clients.failed(), 0) << clients.first_failure();
  EXPECT_GT(clients.ok(), 10);
  EXPECT_EQ(health_status(server.channel, kLabelerServiceName), "SERVING");
}

TEST(HostileRegistry, AVersionGoesOnlyAfterMissingAtSeveralScans) {
  TempDir repo("hostile");
  write_model(repo.path(), random_label_model("m", "1"));
  ModelRegistry registry({repo.path(), "", {}, 3});
  registry.rescan();
  const fs::path away = repo.path() / ".away";
  fs::rename(repo.path() / "m", away);
  for (int scan = 1; scan <= 2; ++scan) {
    const service::ReloadReport report = registry.rescan();
    EXPECT_EQ(report.missing, 1u) << scan;
    EXPECT_EQ(report.removed, 0u) << scan;
    EXPECT_EQ(registry.resolve("", "")->version, "1");
  }
  fs::rename(away, repo.path() / "m");  // back before the third scan: the count starts over
  EXPECT_EQ(registry.rescan().missing, 0u);
  fs::rename(repo.path() / "m", away);
  EXPECT_EQ(registry.rescan().removed, 0u);
  EXPECT_EQ(registry.rescan().removed, 0u);
  EXPECT_EQ(registry.rescan().removed, 1u);
  EXPECT_THROW(registry.resolve("m", ""), RegistryError);
}

TEST(HostileRegistry, ASecondModelAddedUnderLoadLeavesTheDefaultInPlace) {
  TestServer server({random_label_model("a", "1")}, insecure_admin);
  const PointCloud cloud = table_with_box_cloud(0.02f);
  DefaultModelLoad clients(server, cloud);
  std::this_thread::sleep_for(std::chrono::milliseconds(200));
  write_model(server.repo.path(), random_label_model("b", "1"));
  ASSERT_TRUE(reload(server).ok());
  std::this_thread::sleep_for(std::chrono::milliseconds(400));
  clients.finish();
  EXPECT_EQ(clients.failed(), 0) << clients.first_failure();
  EXPECT_GT(clients.ok(), 10);
  v1::ModelMetadata served;
  ASSERT_TRUE(metadata(server, "", &served).ok());
  EXPECT_EQ(served.name(), "a");
  grpc::ClientContext context;
  v1::ListModelsResponse list;
  ASSERT_TRUE(server.stub->ListModels(&context, {}, &list).ok());
  ASSERT_EQ(list.models_size(), 2);
  EXPECT_TRUE(list.models(0).is_default());  // a
  EXPECT_FALSE(list.models(1).is_default());
}

TEST(HostileRegistry, TheDefaultStaysStickyAndItsAbsenceIsNamed) {
  TempDir repo("hostile");
  write_model(repo.path(), random_label_model("a", "1"));
  ModelRegistry registry({repo.path(), "", {}, 1});
  registry.rescan();
  write_model(repo.path(), random_label_model("b", "1"));
  write_model(repo.path(), random_label_model("c", "1"));
  registry.rescan();
  EXPECT_EQ(registry.resolve("", "")->name, "a");
  registry.unload("a", "");
  try {
    registry.resolve("", "");
    FAIL() << "the default is not loaded";
  } catch (const RegistryError& e) {
    EXPECT_NE(std::string(e.what()).find("the default model 'a' is not loaded"), std::string::npos)
        << e.what();
  }
  registry.reload();
  EXPECT_EQ(registry.resolve("", "")->name, "a");
  // With two models at start and none named, there is no default (as before).
  ModelRegistry fresh({repo.path(), "", {}, 1});
  fresh.rescan();
  EXPECT_THROW(fresh.resolve("", ""), RegistryError);
  EXPECT_EQ(fresh.default_model(), "");
}

TEST(HostileRegistry, PathsResolvingOutsideTheRepositoryAreRefused) {
  TempDir outside("outside");
  write_model(outside.path(), random_label_model("evil", "1"));
  write_model(outside.path(), random_label_model("m", "7"));
  TestServer server({random_label_model("m", "1")}, insecure_admin);
  const fs::path& repo = server.repo.path();
  fs::create_directory_symlink(outside.path() / "evil", repo / "evil");        // a model directory
  fs::create_directory_symlink(outside.path() / "m" / "7", repo / "m" / "7");  // a version
  fs::create_directories(repo / "m" / "8");
  fs::create_symlink(outside.path() / "m" / "7" / "model.plm", repo / "m" / "8" / "model.plm");
  fs::create_directory_symlink(repo / "m", repo / "alias");  // inside: served

  v1::ReloadModelsResponse reloaded;
  ASSERT_TRUE(reload(server, &reloaded).ok());
  std::string errors;
  for (const std::string& error : reloaded.errors()) errors += error + "\n";
  EXPECT_EQ(reloaded.errors_size(), 5) << errors;  // the alias leads to m/7 and m/8 as well
  for (const char* path : {"evil:", "m/7:", "m/8/model.plm:", "alias/7:", "alias/8/model.plm:"})
    EXPECT_NE(errors.find(path), std::string::npos) << path << "\n" << errors;
  EXPECT_NE(errors.find("outside the model repository"), std::string::npos) << errors;

  v1::ModelMetadata out;
  EXPECT_EQ(metadata(server, "evil", &out).error_code(), grpc::StatusCode::NOT_FOUND);
  auto& registry = server.server->registry();
  EXPECT_THROW(registry.resolve("m", "7"), RegistryError);
  EXPECT_THROW(registry.resolve("m", "8"), RegistryError);
  EXPECT_EQ(registry.resolve("m", "")->version, "1");
  EXPECT_EQ(registry.resolve("alias", "")->version, "1");
  EXPECT_EQ(load(server, "evil").error_code(), grpc::StatusCode::NOT_FOUND);
}

TEST(HostileInput, ZeroLengthAndNonFiniteClientNormals) {
  const LabelModel model = random_label_model("m", "1");
  TestServer server({model});
  const PointCloud cloud = table_with_box_cloud(0.02f);
  v1::ScanHeader header = header_for();
  header.mutable_layout()->set_normals(true);

  // Default policy: such a point has no normal: label 0, counted as dropped.
  PointCloud zero = cloud;
  zero.normals.assign(cloud.size(), Vec3f::Zero());
  const LabelAnswer dropped = label_stream(*server.stub, scan_requests(zero, header, 500));
  ASSERT_TRUE(dropped.status.ok()) << dropped.status.error_message();
  ASSERT_EQ(dropped.labels.size(), cloud.size());
  EXPECT_EQ(std::count(dropped.labels.begin(), dropped.labels.end(), 0u),
            std::ptrdiff_t(cloud.size()));
  EXPECT_EQ(dropped.summary->points_dropped_non_finite(), cloud.size());

  // NON_FINITE_REJECT: refused, naming the point and its chunk.
  PointCloud one_bad = cloud;
  one_bad.normals.assign(cloud.size(), Vec3f(0, 0, 1));
  one_bad.normals[700] = Vec3f(std::numeric_limits<float>::quiet_NaN(), 0, 1);
  header.mutable_options()->set_non_finite(v1::NON_FINITE_REJECT);
  const grpc::Status refused =
      label_stream(*server.stub, scan_requests(one_bad, header, 500)).status;
  EXPECT_EQ(refused.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_NE(refused.error_message().find("point 700 (chunk 2)"), std::string::npos)
      << refused.error_message();
  EXPECT_NE(refused.error_message().find("normal"), std::string::npos) << refused.error_message();
  one_bad.normals[700] = Vec3f::Zero();
  EXPECT_EQ(label_stream(*server.stub, scan_requests(one_bad, header, 500)).status.error_code(),
            grpc::StatusCode::INVALID_ARGUMENT);
  one_bad.normals[700] = Vec3f(0, 0, 1);
  EXPECT_TRUE(label_stream(*server.stub, scan_requests(one_bad, header, 500)).status.ok());
}

// Everything the process writes to stderr while it lives.
class StderrCapture {
 public:
  StderrCapture() : dir_("stderr"), file_(dir_.path() / "stderr.log") {
    std::fflush(stderr);
    saved_ = dup(2);
    const int fd = open(file_.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    dup2(fd, 2);
    close(fd);
  }
  ~StderrCapture() { restore(); }
  std::string text() {
    restore();
    std::ifstream in(file_);
    std::stringstream out;
    out << in.rdbuf();
    return out.str();
  }

 private:
  void restore() {
    if (saved_ < 0) return;
    std::fflush(stderr);
    dup2(saved_, 2);
    close(saved_);
    saved_ = -1;
  }
  TempDir dir_;
  fs::path file_;
  int saved_ = -1;
};

TEST(HostileInput, MegabyteNamesAndScanIdsGiveShortStatusesLogsAndNoMetricSeries) {
  TestServer server({random_label_model("m", "1")}, insecure_admin);
  const PointCloud cloud = table_with_box_cloud(0.02f);
  const std::string huge_model(1 << 20, 'x');
  const std::string huge_scan_id(4 << 20, 's');
  std::string log;
  std::vector<grpc::Status> statuses;
  {
    StderrCapture capture;
    statuses.push_back(
        label_stream(*server.stub, scan_requests(cloud, header_for(huge_model))).status);
    v1::ModelMetadata out;
    statuses.push_back(metadata(server, huge_model, &out));
    statuses.push_back(unload(server, huge_model));
    statuses.push_back(unload(server, "m", huge_model));
    statuses.push_back(load(server, huge_model));
    const LabelAnswer labeled =
        label_stream(*server.stub, scan_requests(cloud, header_for("", huge_scan_id)));
    EXPECT_TRUE(labeled.status.ok()) << labeled.status.error_message();
    log = capture.text();
  }
  for (const grpc::Status& status : statuses) {
    EXPECT_FALSE(status.ok());
    EXPECT_LT(status.error_message().size(), kShortMessage) << status.error_message().size();
    EXPECT_NE(status.error_message().find("bytes)"), std::string::npos)
        << status.error_message().substr(0, kShortMessage);
  }
  std::istringstream lines(log);
  int request_lines = 0;
  for (std::string line; std::getline(lines, line);) {
    EXPECT_LT(line.size(), 5000u) << line.substr(0, 300);
    request_lines += line.find("event=request") != std::string::npos;
  }
  EXPECT_GE(request_lines, 6) << log.substr(0, 2000);
  const std::string metrics = scrape::fetch_text(
      "http://127.0.0.1:" + std::to_string(server.server->metrics_port()) + "/metrics");
  EXPECT_LT(metrics.size(), 200000u);
  EXPECT_EQ(metrics.find("xxxxxxxxxx"), std::string::npos);  // no series for made-up models
}

TEST(HostileRegistry, HealthAndGaugesFollowTheRegistryWhoeverChangesIt) {
  TestServer server({random_label_model("m", "1")},
                    [](ops::ServerConfig& c) { c.unload_after_missing_polls = 1; });
  auto& registry = server.server->registry();
  auto gauge = [&] {
    return scrape::sum_samples(scrape_metrics(server.server->metrics_port()),
                               "primlabel_models_loaded");
  };
  EXPECT_EQ(gauge(), 1.0);
  // Neither the poller nor an admin RPC: a scan called directly still reaches health.
  fs::remove_all(server.repo.path() / "m");
  EXPECT_EQ(registry.rescan().removed, 1u);
  EXPECT_EQ(health_status(server.channel, kLabelerServiceName), "NOT_SERVING");
  EXPECT_EQ(gauge(), 0.0);
  write_model(server.repo.path(), random_label_model("m", "2"));
  registry.load("m", "");
  EXPECT_EQ(health_status(server.channel, kLabelerServiceName), "SERVING");
  EXPECT_EQ(gauge(), 1.0);

  TempDir repo("hostile");
  write_model(repo.path(), random_label_model("m", "1"));
  ModelRegistry counted({repo.path(), "", {}, 1});
  int changes = 0;
  counted.set_observer([&] { ++changes; });
  counted.rescan();
  EXPECT_EQ(changes, 1);
  counted.rescan();  // nothing changed: no call
  EXPECT_EQ(changes, 1);
  counted.unload("m", "");
  EXPECT_EQ(changes, 2);
  counted.load("m", "1");
  EXPECT_EQ(changes, 3);
}

}  // namespace
}  // namespace primlabel::servertest
