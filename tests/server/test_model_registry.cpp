// The model registry on a temporary repository: version order, latest / pinned / default,
// reload of changed files, failed loads keep the old version, removed directories, admin
// load/unload, and names that would escape the repository.

#include <gtest/gtest.h>

#include <fstream>
#include <thread>

#include "model_repository_util.hpp"
#include "primlabel/service/model_registry.hpp"
#include "random_label_model.hpp"

namespace primlabel::servertest {
namespace {

using service::ModelRegistry;
using service::RegistryError;
using service::version_less;
using testing::random_label_model;

ModelRegistry registry_over(const fs::path& root, const std::string& default_model = "",
                            std::map<std::string, std::string> pins = {}) {
  return ModelRegistry({root, default_model, std::move(pins)});
}

void corrupt(const fs::path& file) {
  std::ofstream out(file, std::ios::binary | std::ios::trunc);
  out << "PRIMLABEL-MODEL\nnot a model at all";
}

TEST(ModelRegistry, VersionsCompareDigitRunsByValue) {
  EXPECT_TRUE(version_less("2", "10"));
  EXPECT_FALSE(version_less("10", "2"));
  EXPECT_TRUE(version_less("2026-01-02.1", "2026-01-02.10"));
  EXPECT_TRUE(version_less("1.9", "1.10"));
  EXPECT_TRUE(version_less("v1", "v2"));
  EXPECT_TRUE(version_less("1", "1a"));
  EXPECT_FALSE(version_less("a", "a"));
  EXPECT_TRUE(version_less("1", "01") != version_less("01", "1"));  // strict, total
}

TEST(ModelRegistry, ServesTheLatestUnlessPinnedAndKnowsTheDefault) {
  TempDir repo("registry");
  write_model(repo.path(), random_label_model("m", "2"));
  write_model(repo.path(), random_label_model("m", "10"));
  auto registry = registry_over(repo.path());
  const auto report = registry.rescan();
  EXPECT_EQ(report.loaded, 2u);
  EXPECT_EQ(report.failed, 0u);
  EXPECT_EQ(registry.resolve("m", "")->version, "10");
  EXPECT_EQ(registry.resolve("", "")->version, "10");  // the only model is the default
  EXPECT_EQ(registry.resolve("m", "2")->version, "2");
  EXPECT_EQ(registry.list().front().versions, (std::vector<std::string>{"2", "10"}));

  auto pinned = registry_over(repo.path(), "", {{"m", "2"}});
  pinned.rescan();
  EXPECT_EQ(pinned.resolve("m", "")->version, "2");

  write_model(repo.path(), random_label_model("other", "1"));
  registry.rescan();
  EXPECT_EQ(registry.resolve("", "")->name, "m");  // the only model stays the default
  auto fresh = registry_over(repo.path());
  fresh.rescan();
  EXPECT_THROW(fresh.resolve("", ""), RegistryError);  // two models from the start, none named
  auto with_default = registry_over(repo.path(), "other");
  with_default.rescan();
  EXPECT_EQ(with_default.resolve("", "")->name, "other");
}

TEST(ModelRegistry, ChangedFilesReloadAndFailedLoadsKeepTheOldVersion) {
  TempDir repo("registry");
  const fs::path file = write_model(repo.path(), random_label_model("m", "1", 1));
  auto registry = registry_over(repo.path());
  registry.rescan();
  const auto first = registry.resolve("m", "1");

  EXPECT_EQ(registry.rescan().loaded, 0u);  // unchanged: nothing to do
  EXPECT_EQ(registry.resolve("m", "1"), first);

  write_model(repo.path(), random_label_model("m", "1", 2));
  EXPECT_EQ(registry.rescan().loaded, 1u);
  const auto second = registry.resolve("m", "1");
  EXPECT_NE(second, first);
  EXPECT_NE(second->model->weights.node_weights, first->model->weights.node_weights);
  // A request that took the first entry still has it, intact.
  EXPECT_EQ(first->model->weights.node_weights,
            random_label_model("m", "1", 1).weights.node_weights);

  corrupt(file);
  const auto report = registry.rescan();
  EXPECT_EQ(report.failed, 1u);
  ASSERT_EQ(report.errors.size(), 1u);
  EXPECT_NE(report.errors[0].find("m/1/model.plm"), std::string::npos) << report.errors[0];
  EXPECT_EQ(registry.resolve("m", "1"), second);  // still serving the good one
  EXPECT_EQ(registry.rescan().failed, 0u);        // not retried until the file changes
}

TEST(ModelRegistry, RemovedDirectoriesStopServingAndOthersAreIgnored) {
  TempDir repo("registry");
  write_model(repo.path(), random_label_model("m", "1"));
  write_model(repo.path(), random_label_model("m", "2"));
  fs::create_directories(repo.path() / "m" / "3");  // no model file yet
  fs::create_directories(repo.path() / ".hidden" / "1");
  std::ofstream(repo.path() / "README") << "not a model";
  auto registry = registry_over(repo.path());
  registry.rescan();
  EXPECT_EQ(registry.loaded_versions(), 2u);
  fs::remove_all(repo.path() / "m" / "2");
  for (int scan = 1; scan < 3; ++scan) {  // last known good: served until missing at 3 scans
    EXPECT_EQ(registry.rescan().removed, 0u);
    EXPECT_EQ(registry.resolve("m", "")->version, "2");
  }
  EXPECT_EQ(registry.rescan().removed, 1u);
  EXPECT_EQ(registry.resolve("m", "")->version, "1");
}

TEST(ModelRegistry, LoadAndUnloadByName) {
  TempDir repo("registry");
  write_model(repo.path(), random_label_model("m", "1"));
  write_model(repo.path(), random_label_model("m", "2"));
  auto registry = registry_over(repo.path());
  EXPECT_EQ(registry.load("m", "")->version, "2");  // latest on disk
  EXPECT_EQ(registry.loaded_versions(), 1u);
  EXPECT_EQ(registry.load("m", "1")->version, "1");
  EXPECT_EQ(registry.unload("m", "2"), 1u);
  EXPECT_EQ(registry.resolve("m", "")->version, "1");
  registry.rescan();  // an unloaded version stays unloaded
  EXPECT_THROW(registry.resolve("m", "2"), RegistryError);
  EXPECT_EQ(registry.unload("m", ""), 1u);
  EXPECT_EQ(registry.loaded_versions(), 0u);
  registry.rescan();
  EXPECT_EQ(registry.loaded_versions(), 0u);
  registry.load("m", "2");
  registry.rescan();
  EXPECT_EQ(registry.loaded_versions(), 2u);

  try {
    registry.load("../etc", "");
    FAIL();
  } catch (const RegistryError& e) {
    EXPECT_EQ(e.kind(), RegistryError::Kind::kInvalidArgument);
  }
  try {
    registry.load("m", "9");
    FAIL();
  } catch (const RegistryError& e) {
    EXPECT_EQ(e.kind(), RegistryError::Kind::kNotFound);
  }
  try {
    registry.unload("absent", "");
    FAIL();
  } catch (const RegistryError& e) {
    EXPECT_EQ(e.kind(), RegistryError::Kind::kNotFound);
  }
}

TEST(ModelRegistry, ConcurrentResolveWhileReloading) {
  TempDir repo("registry");
  write_model(repo.path(), random_label_model("m", "1", 1));
  auto registry = registry_over(repo.path());
  registry.rescan();
  std::atomic<bool> done{false};
  std::thread writer([&] {
    for (int i = 0; i < 30; ++i) {
      write_model(repo.path(), random_label_model("m", "1", 1 + i % 2));
      registry.rescan();
    }
    done = true;
  });
  const auto a = random_label_model("m", "1", 1).weights.node_weights;
  const auto b = random_label_model("m", "1", 2).weights.node_weights;
  int checks = 0;
  while (!done) {
    const auto entry = registry.resolve("m", "");
    const auto& w = entry->model->weights.node_weights;
    ASSERT_TRUE(w == a || w == b);
    ++checks;
  }
  writer.join();
  EXPECT_GT(checks, 0);
}

TEST(ModelRegistry, MissingRepositoryIsAnError) {
  auto registry = registry_over("/nonexistent/primlabel/models");
  EXPECT_THROW(registry.rescan(), RegistryError);
}

}  // namespace
}  // namespace primlabel::servertest
