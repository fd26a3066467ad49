// Administration and security in process: admin RPCs load, unload and rescan models (health
// follows), hot reload by polling, the bearer token on admin RPCs (and optionally on all), and
// TLS / mutual TLS with certificates made by openssl for the test.

#include <cstdlib>
#include <fstream>
#include <sstream>
#include <thread>

#include "server_test_util.hpp"

namespace primlabel::servertest {
namespace {

using testing::random_label_model;
using testing::table_with_box_cloud;

template <typename Request, typename Response, typename Call>
grpc::Status call_with_token(Call call, const Request& request, Response& response,
                             const std::string& token) {
  grpc::ClientContext context;
  context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(30));
  if (!token.empty()) context.AddMetadata("authorization", "Bearer " + token);
  return call(&context, request, &response);
}

TEST(AdminService, LoadUnloadAndReloadFollowHealthAndMetrics) {
  TestServer server({random_label_model("m", "1")},
                    [](ops::ServerConfig& c) { c.insecure_admin = true; });
  auto& admin = *server.admin;
  v1::UnloadModelRequest unload;
  unload.set_model("m");
  v1::UnloadModelResponse unloaded;
  grpc::ClientContext c1;
  ASSERT_TRUE(admin.UnloadModel(&c1, unload, &unloaded).ok());
  EXPECT_EQ(unloaded.unloaded_versions(), 1u);
  EXPECT_EQ(health_status(server.channel, "primlabel.v1.Labeler"), "NOT_SERVING");
  EXPECT_EQ(
      label_cloud(*server.stub, table_with_box_cloud(0.02f), header_for()).status.error_code(),
      grpc::StatusCode::NOT_FOUND);

  write_model(server.repo.path(), random_label_model("m", "2"));
  v1::LoadModelRequest load;
  load.set_model("m");
  v1::LoadModelResponse loaded;
  grpc::ClientContext c2;
  ASSERT_TRUE(admin.LoadModel(&c2, load, &loaded).ok());
  EXPECT_EQ(loaded.model().version(), "2");
  EXPECT_EQ(health_status(server.channel, "primlabel.v1.Labeler"), "SERVING");

  // A new good version and a broken one: the rescan loads one, reports the other.
  write_model(server.repo.path(), random_label_model("m", "3"));
  fs::create_directories(server.repo.path() / "m" / "4");
  std::ofstream(server.repo.path() / "m" / "4" / "model.plm") << "garbage";
  v1::ReloadModelsResponse reloaded;
  grpc::ClientContext c3;
  ASSERT_TRUE(admin.ReloadModels(&c3, {}, &reloaded).ok());
  EXPECT_EQ(reloaded.failed(), 1u);
  ASSERT_EQ(reloaded.errors_size(), 1);
  EXPECT_NE(reloaded.errors(0).find("m/4/model.plm"), std::string::npos) << reloaded.errors(0);
  ASSERT_EQ(reloaded.models_size(), 1);
  EXPECT_EQ(reloaded.models(0).version(), "3");  // 4 failed: 3 is the latest that loaded
  // Loading "m" again lifted the model-wide unload, so the rescan brought version 1 back too.
  EXPECT_EQ(reloaded.models(0).loaded_versions_size(), 3);

  const auto samples = scrape_metrics(server.server->metrics_port());
  EXPECT_EQ(scrape::sum_samples(samples, "primlabel_model_reload_failures_total"), 1.0);
  EXPECT_EQ(scrape::sum_samples(samples, "primlabel_model_info", {{"version", "3"}}), 1.0);
  EXPECT_EQ(scrape::sum_samples(samples, "primlabel_model_info", {{"version", "2"}}), 0.0);

  v1::LoadModelRequest bad;
  bad.set_model("../../etc");
  grpc::ClientContext c4;
  EXPECT_EQ(admin.LoadModel(&c4, bad, &loaded).error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  bad.set_model("m");
  bad.set_version("4");
  grpc::ClientContext c5;
  EXPECT_EQ(admin.LoadModel(&c5, bad, &loaded).error_code(), grpc::StatusCode::FAILED_PRECONDITION);
}

TEST(AdminService, PollingPicksUpNewVersions) {
  TestServer server({random_label_model("m", "1")},
                    [](ops::ServerConfig& c) { c.reload_seconds = 0.05; });
  write_model(server.repo.path(), random_label_model("m", "2"));
  std::string served;
  for (int i = 0; i < 400 && served != "2"; ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(25));
    grpc::ClientContext context;
    v1::ListModelsResponse list;
    if (server.stub->ListModels(&context, {}, &list).ok() && list.models_size() == 1)
      served = list.models(0).version();
  }
  EXPECT_EQ(served, "2");
}

TEST(TokenAuth, AdminNeedsTheTokenLabelingOnlyWhenAskedTo) {
  TestServer server({random_label_model("m", "1")},
                    [](ops::ServerConfig& c) { c.token = "s3cret"; });
  auto reload = [&](grpc::ClientContext* c, const v1::ReloadModelsRequest& r,
                    v1::ReloadModelsResponse* out) {
    return server.admin->ReloadModels(c, r, out);
  };
  v1::ReloadModelsResponse response;
  grpc::Status status = call_with_token(reload, v1::ReloadModelsRequest{}, response, "");
  EXPECT_EQ(status.error_code(), grpc::StatusCode::UNAUTHENTICATED);
  EXPECT_NE(status.error_message().find("Bearer"), std::string::npos);
  EXPECT_EQ(call_with_token(reload, v1::ReloadModelsRequest{}, response, "wrong").error_code(),
            grpc::StatusCode::UNAUTHENTICATED);
  EXPECT_TRUE(call_with_token(reload, v1::ReloadModelsRequest{}, response, "s3cret").ok());
  const PointCloud cloud = table_with_box_cloud(0.02f);
  EXPECT_TRUE(label_stream(*server.stub, scan_requests(cloud, header_for())).status.ok());

  TestServer strict({random_label_model("m", "1")}, [](ops::ServerConfig& c) {
    c.token = "s3cret";
    c.token_for_all = true;
  });
  EXPECT_EQ(label_stream(*strict.stub, scan_requests(cloud, header_for())).status.error_code(),
            grpc::StatusCode::UNAUTHENTICATED);
  EXPECT_TRUE(label_stream(*strict.stub, scan_requests(cloud, header_for()),
                           std::chrono::seconds(60), "s3cret")
                  .status.ok());
  EXPECT_EQ(health_status(strict.channel, ""), "SERVING");  // probes need no token
}

// A CA, a server certificate for 127.0.0.1 / localhost and a client certificate, by openssl.
struct Certificates {
  TempDir dir{"certs"};
  bool ok = false;
  std::string path(const std::string& name) const { return (dir.path() / name).string(); }
  static std::string read(const std::string& file) {
    std::ifstream in(file);
    std::stringstream text;
    text << in.rdbuf();
    return text.str();
  }
  Certificates() {
    const std::string d = dir.path().string();
    std::ofstream(d + "/san.ext") << "subjectAltName=DNS:localhost,IP:127.0.0.1\n";
    const std::string key = " -newkey ec -pkeyopt ec_paramgen_curve:prime256v1 -nodes";
    const std::string script =
        "cd " + d + " && openssl req -x509" + key +
        " -keyout ca.key -out ca.pem -days 2 -subj /CN=primlabel-test-ca 2>/dev/null"
        " && openssl req" +
        key +
        " -keyout server.key -out server.csr -subj /CN=localhost"
        " 2>/dev/null && openssl x509 -req -in server.csr -CA ca.pem -CAkey ca.key"
        " -CAcreateserial -out server.pem -days 2 -extfile san.ext 2>/dev/null"
        " && openssl req" +
        key +
        " -keyout client.key -out client.csr -subj /CN=client"
        " 2>/dev/null && openssl x509 -req -in client.csr -CA ca.pem -CAkey ca.key"
        " -CAcreateserial -out client.pem -days 2 2>/dev/null";
    ok = std::system(script.c_str()) == 0;
  }
};

std::shared_ptr<grpc::Channel> tls_channel(int port, const Certificates& certs, bool client_cert) {
  grpc::SslCredentialsOptions options;
  options.pem_root_certs = Certificates::read(certs.path("ca.pem"));
  if (client_cert) {
    options.pem_private_key = Certificates::read(certs.path("client.key"));
    options.pem_cert_chain = Certificates::read(certs.path("client.pem"));
  }
  grpc::ChannelArguments args;
  args.SetSslTargetNameOverride("localhost");
  return grpc::CreateCustomChannel("127.0.0.1:" + std::to_string(port),
                                   grpc::SslCredentials(options), args);
}

TEST(Tls, ServerTlsAndMutualTls) {
  Certificates certs;
  if (!certs.ok) GTEST_SKIP() << "openssl could not make test certificates";
  const PointCloud cloud = table_with_box_cloud(0.02f);
  auto labels_over = [&](const std::shared_ptr<grpc::Channel>& channel) {
    auto stub = v1::Labeler::NewStub(channel);
    return label_stream(*stub, scan_requests(cloud, header_for()), std::chrono::seconds(20)).status;
  };
  {
    TestServer server({random_label_model()}, [&](ops::ServerConfig& c) {
      c.tls_cert = certs.path("server.pem");
      c.tls_key = certs.path("server.key");
    });
    const grpc::Status secure = labels_over(tls_channel(server.server->port(), certs, false));
    EXPECT_TRUE(secure.ok()) << secure.error_message();
    EXPECT_EQ(labels_over(server.channel).error_code(), grpc::StatusCode::UNAVAILABLE);
  }
  TestServer mutual({random_label_model()}, [&](ops::ServerConfig& c) {
    c.tls_cert = certs.path("server.pem");
    c.tls_key = certs.path("server.key");
    c.tls_client_ca = certs.path("ca.pem");
  });
  const grpc::Status with_cert = labels_over(tls_channel(mutual.server->port(), certs, true));
  EXPECT_TRUE(with_cert.ok()) << with_cert.error_message();
  EXPECT_FALSE(labels_over(tls_channel(mutual.server->port(), certs, false)).ok());
}

}  // namespace
}  // namespace primlabel::servertest
