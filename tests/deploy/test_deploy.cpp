// The static invariants of deploy/ (Dockerfile, Compose, Kubernetes, nginx, Prometheus), checked
// by check_deploy.py; each check also runs on a broken copy to show that it can fail.

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "test_util.hpp"

namespace primlabel::test {
namespace {

namespace fs = std::filesystem;

constexpr int kSkipped = 77;  // check_deploy.py could not run the check here

std::string source_path(const std::string& relative) {
  return std::string(PRIMLABEL_SOURCE_DIR) + "/" + relative;
}

// Debian's python3 first: deploy/setup.sh installs PyYAML for it (python3-yaml).
std::string python() {
  return access("/usr/bin/python3", X_OK) == 0 ? "/usr/bin/python3" : "python3";
}

CommandResult run_check(const std::string& arguments) {
  return run_command(python() + " " + PRIMLABEL_DEPLOY_CHECK + " " + arguments);
}

#define EXPECT_CHECK_PASSES(arguments)                                      \
  do {                                                                      \
    const CommandResult result = run_check(arguments);                      \
    if (result.exit_code == kSkipped) GTEST_SKIP() << result.output;        \
    EXPECT_EQ(result.exit_code, 0) << (arguments) << "\n" << result.output; \
  } while (0)

// Expects the check to fail with a message containing `expected`.
#define EXPECT_CHECK_FAILS_WITH(arguments, expected)                             \
  do {                                                                           \
    const CommandResult result = run_check(arguments);                           \
    if (result.exit_code == kSkipped) GTEST_SKIP() << result.output;             \
    EXPECT_EQ(result.exit_code, 1) << (arguments) << "\n" << result.output;      \
    EXPECT_NE(result.output.find(expected), std::string::npos) << result.output; \
  } while (0)

// A copy of deploy/ in a temporary directory, to break on purpose.
class BrokenCopy : public ::testing::Test {
 protected:
  void SetUp() override {
    fs::copy(source_path("deploy"), root_ + "/deploy", fs::copy_options::recursive);
  }
  std::string path(const std::string& relative) const { return root_ + "/" + relative; }
  // Replaces the first `from` in the file (which must contain it) by `to`.
  void edit(const std::string& relative, const std::string& from, const std::string& to) {
    std::ifstream in(path(relative));
    std::stringstream text;
    text << in.rdbuf();
    std::string content = text.str();
    const auto at = content.find(from);
    ASSERT_NE(at, std::string::npos) << relative << " has no '" << from << "'";
    content.replace(at, from.size(), to);
    std::ofstream(path(relative)) << content;
  }

  TempDir temp_;
  std::string root_ = fs::path(temp_.file("x")).parent_path().string();
};

// ---- the real files ----

TEST(Deploy, DockerfileInvariants) {
  EXPECT_CHECK_PASSES("dockerfile " + source_path("deploy/Dockerfile"));
}

TEST(Deploy, DockerfileRuntimePackagesExistInDebian) {
  EXPECT_CHECK_PASSES("dockerfile-packages " + source_path("deploy/Dockerfile"));
}

TEST(Deploy, RuntimePackagesProvideEveryLibraryOfTheServer) {
  const std::string server = binary("primlabel-server");
  const std::string client = binary("primlabel");
  if (!fs::exists(server)) GTEST_SKIP() << server << " not built";
  EXPECT_CHECK_PASSES("dockerfile-ldd " + source_path("deploy/Dockerfile") + " " + server + " " +
                      client);
}

TEST(Deploy, EveryYamlFileParses) { EXPECT_CHECK_PASSES("yaml " + source_path("deploy")); }

TEST(Deploy, KubernetesObjects) { EXPECT_CHECK_PASSES("k8s " + source_path("deploy/k8s")); }

TEST(Deploy, ComposeReferencesExistingFiles) {
  EXPECT_CHECK_PASSES("compose " + source_path("deploy/compose.yaml"));
}

TEST(Deploy, PrometheusAndNginxCoverEveryReplica) {
  EXPECT_CHECK_PASSES("targets " + source_path("deploy/compose.yaml") + " " +
                      source_path("deploy/prometheus/prometheus.yml") + " " +
                      source_path("deploy/nginx/nginx.conf"));
}

TEST(Deploy, AlertsUseTheAgreedMetrics) {
  EXPECT_CHECK_PASSES("alert-metrics " + source_path("deploy/prometheus/alerts.yml"));
}

TEST(Deploy, PromtoolAcceptsConfigRulesAndRuleTests) {
  EXPECT_CHECK_PASSES("promtool " + source_path("deploy/prometheus"));
}

TEST(Deploy, NginxAcceptsItsConfig) {
  EXPECT_CHECK_PASSES("nginx " + source_path("deploy/nginx/nginx.conf"));
}

TEST(Deploy, MakeDefaultModelIsExecutableAndWrapsSetup) {
  const std::string script = source_path("deploy/make-default-model.sh");
  EXPECT_EQ(access(script.c_str(), X_OK), 0);
  std::ifstream in(script);
  std::stringstream text;
  text << in.rdbuf();
  EXPECT_NE(text.str().find("deploy/setup.sh\" default-model"), std::string::npos);
  EXPECT_EQ(run_command(script).exit_code, 2);  // usage
}

TEST(Deploy, DockerignoreKeepsBuildTreesAndGitOutOfTheImage) {
  EXPECT_CHECK_PASSES("dockerignore " + std::string(PRIMLABEL_SOURCE_DIR));
}

TEST(Deploy, ComposeNginxAndPrometheusAreTheLocalProofsDebianVersions) {
  EXPECT_CHECK_PASSES("compose-versions " + source_path("deploy/compose.yaml"));
}

// The image proof itself is opt-in (about 20 min, deploy/README.md); here only its exit codes.
TEST(Deploy, ImageProofRejectsBadUsageAndSkipsWithoutItsTools) {
  const std::string script = source_path("deploy/image-proof.sh");
  EXPECT_EQ(run_command(script + " --no-such-option").exit_code, 2);
  const auto missing = run_command("PODMAN=/nonexistent/podman " + script);
  EXPECT_EQ(missing.exit_code, kSkipped) << missing.output;
  EXPECT_NE(missing.output.find("SKIP"), std::string::npos) << missing.output;
}

TEST(Deploy, ShellScriptsParse) {
  for (const char* script : {"deploy/setup.sh", "deploy/make-default-model.sh",
                             "deploy/local-proof.sh", "deploy/image-proof.sh"}) {
    const auto result = run_command("bash -n " + source_path(script));
    EXPECT_EQ(result.exit_code, 0) << script << "\n" << result.output;
    EXPECT_EQ(access(source_path(script).c_str(), X_OK), 0) << script << " is not executable";
  }
}

// ---- each check fails on a broken copy ----

TEST_F(BrokenCopy, DockerfileRunningAsRootFails) {
  edit("deploy/Dockerfile", "USER 10001:10001", "USER root");
  EXPECT_CHECK_FAILS_WITH("dockerfile " + path("deploy/Dockerfile"), "runs as root");
}

TEST_F(BrokenCopy, DockerfileWithoutUserMetricsPortOrHealthcheckFails) {
  edit("deploy/Dockerfile", "USER 10001:10001", "");
  edit("deploy/Dockerfile", "EXPOSE 50051 9464", "EXPOSE 50051");
  edit("deploy/Dockerfile", "HEALTHCHECK", "# HEALTHCHECK");
  edit("deploy/Dockerfile", "deploy/setup.sh build", "make");
  const auto result = run_check("dockerfile " + path("deploy/Dockerfile"));
  EXPECT_EQ(result.exit_code, 1);
  for (const char* expected : {"no USER", "EXPOSE 9464", "no HEALTHCHECK", "setup.sh build"})
    EXPECT_NE(result.output.find(expected), std::string::npos) << expected << "\n" << result.output;
}

TEST_F(BrokenCopy, BuildStageBuildingTooLittleFails) {
  edit("deploy/Dockerfile", "BUILD_TARGETS=\"primlabel-server primlabel primlabel-train\"",
       "BUILD_TARGETS=\"primlabel-server\"");
  const auto result = run_check("dockerfile " + path("deploy/Dockerfile"));
  EXPECT_EQ(result.exit_code, 1);
  for (const char* expected : {"BUILD_TARGETS lacks primlabel\n", "lacks primlabel-train"})
    EXPECT_NE(result.output.find(expected), std::string::npos) << expected << "\n" << result.output;
}

TEST_F(BrokenCopy, BuildStageBuildingEveryToolFails) {
  edit("deploy/Dockerfile", "BUILD_TARGETS=", "NOT_BUILD_TARGETS=");
  EXPECT_CHECK_FAILS_WITH("dockerfile " + path("deploy/Dockerfile"), "sets no BUILD_TARGETS");
}

TEST_F(BrokenCopy, DockerignoreKeepingBuildOrGitFails) {
  fs::copy_file(source_path(".dockerignore"), path(".dockerignore"));
  edit(".dockerignore", "\n.git\n", "\n");
  edit(".dockerignore", "\nbuild\n", "\n");
  const auto result = run_check("dockerignore " + root_);
  EXPECT_EQ(result.exit_code, 1);
  for (const char* expected : {"keeps .git/HEAD", "keeps build/CMakeCache.txt"})
    EXPECT_NE(result.output.find(expected), std::string::npos) << expected << "\n" << result.output;
}

TEST_F(BrokenCopy, MissingOrOverriddenDockerignoreFails) {
  EXPECT_CHECK_FAILS_WITH("dockerignore " + root_, "no .dockerignore at the repository root");
  fs::copy_file(source_path(".dockerignore"), path(".dockerignore"));
  std::ofstream(path("deploy/Dockerfile.dockerignore")) << ".git\n";
  EXPECT_CHECK_FAILS_WITH("dockerignore " + root_, "deploy/Dockerfile.dockerignore overrides");
}

TEST_F(BrokenCopy, ComposeWithUpstreamNginxOrUnpinnedPrometheusFails) {
  edit("deploy/compose.yaml",
       "image: primlabel-nginx:1.22-bookworm\n    build:\n      context: ./nginx\n"
       "      dockerfile: Dockerfile\n",
       "image: nginx:1.27-bookworm\n");
  edit("deploy/prometheus/Dockerfile", "'prometheus=2.42.*'", "prometheus");
  const auto result = run_check("compose-versions " + path("deploy/compose.yaml"));
  EXPECT_EQ(result.exit_code, 1);
  for (const char* expected :
       {"nginx: not built from Debian's nginx 1.22", "does not install prometheus=2.42.*"})
    EXPECT_NE(result.output.find(expected), std::string::npos) << expected << "\n" << result.output;
}

TEST_F(BrokenCopy, UnknownRuntimePackageFails) {
  edit("deploy/Dockerfile", "liblzf1 ", "liblzf1 libprimlabel-no-such-package ");
  EXPECT_CHECK_FAILS_WITH("dockerfile-packages " + path("deploy/Dockerfile"),
                          "libprimlabel-no-such-package is not in the Debian archive");
}

TEST_F(BrokenCopy, LibraryWithoutRuntimePackageFails) {
  // This test executable needs libstdc++6 like the server does.
  edit("deploy/Dockerfile", "libstdc++6 ", "");
  const std::string self = fs::read_symlink("/proc/self/exe").string();
  EXPECT_CHECK_FAILS_WITH("dockerfile-ldd " + path("deploy/Dockerfile") + " " + self,
                          "comes from libstdc++6");
}

TEST_F(BrokenCopy, ShortGracePeriodFails) {
  edit("deploy/k8s/deployment.yaml", "terminationGracePeriodSeconds: 30",
       "terminationGracePeriodSeconds: 20");
  EXPECT_CHECK_FAILS_WITH("k8s " + path("deploy/k8s"), "< preStop 5 + drain 20");
}

TEST_F(BrokenCopy, HttpProbeAndStraySelectorFail) {
  edit("deploy/k8s/deployment.yaml",
       "readinessProbe:\n            grpc:\n              port: 50051",
       "readinessProbe:\n            tcpSocket:\n              port: 50051");
  edit("deploy/k8s/service-headless.yaml", "component: server", "component: srv");
  const auto result = run_check("k8s " + path("deploy/k8s"));
  EXPECT_EQ(result.exit_code, 1);
  EXPECT_NE(result.output.find("readinessProbe is not a gRPC probe"), std::string::npos)
      << result.output;
  EXPECT_NE(result.output.find("Service primlabel-headless: selector"), std::string::npos)
      << result.output;
}

TEST_F(BrokenCopy, MissingKustomizeResourceFails) {
  fs::remove(path("deploy/k8s/pdb.yaml"));
  EXPECT_CHECK_FAILS_WITH("k8s " + path("deploy/k8s"), "lists pdb.yaml, which does not exist");
}

TEST_F(BrokenCopy, ComposeMountingAMissingFileFails) {
  fs::remove(path("deploy/nginx/nginx.conf"));
  EXPECT_CHECK_FAILS_WITH("compose " + path("deploy/compose.yaml"),
                          "mounts ./nginx/nginx.conf, which does not exist");
}

TEST_F(BrokenCopy, UnscrapedReplicaFails) {
  edit("deploy/prometheus/prometheus.yml", "- primlabel-3:9464", "");
  EXPECT_CHECK_FAILS_WITH("targets " + path("deploy/compose.yaml") + " " +
                              path("deploy/prometheus/prometheus.yml") + " " +
                              path("deploy/nginx/nginx.conf"),
                          "does not scrape primlabel-3:9464");
}

TEST_F(BrokenCopy, InvalidYamlFails) {
  std::ofstream(path("deploy/k8s/broken.yaml")) << "a: [unclosed\n";
  EXPECT_CHECK_FAILS_WITH("yaml " + path("deploy"), "broken.yaml does not parse");
}

TEST_F(BrokenCopy, PromtoolRejectsABrokenRule) {
  edit("deploy/prometheus/alerts.yml", "primlabel_models_loaded == 0",
       "primlabel_models_loaded ==");
  EXPECT_CHECK_FAILS_WITH("promtool " + path("deploy/prometheus"), "check rules");
}

TEST_F(BrokenCopy, NginxRejectsABrokenConfig) {
  edit("deploy/nginx/nginx.conf", "grpc_pass grpc://primlabel;", "grpc_pass grpc://primlabel");
  EXPECT_CHECK_FAILS_WITH("nginx " + path("deploy/nginx/nginx.conf"), "nginx -t failed");
}

}  // namespace
}  // namespace primlabel::test
