#pragma once
// Helpers shared by the test executables: fixture paths and files, CSV fixtures, synthetic clouds.

#include <gtest/gtest.h>
#include <sys/wait.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "primlabel/geometry/point_cloud.hpp"

namespace primlabel::test {

inline std::string test_data(const std::string& name) {
  return std::string(PRIMLABEL_TEST_DATA) + "/" + name;
}
inline std::string shared_data(const std::string& name) {
  return std::string(PRIMLABEL_SHARED_DATA) + "/" + name;
}
inline std::string binary(const std::string& name) {
  return std::string(PRIMLABEL_BIN_DIR) + "/" + name;
}

// A CSV of floats, one row per point ("nan" allowed). Lines starting with '#' and header lines
// (any cell that is not a number) are skipped.
inline std::vector<std::vector<float>> read_csv(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error("cannot open fixture " + path);
  std::vector<std::vector<float>> rows;
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    std::vector<float> row;
    std::stringstream s(line);
    std::string cell;
    bool numeric = true;
    while (std::getline(s, cell, ',')) {
      char* end = nullptr;
      row.push_back(std::strtof(cell.c_str(), &end));
      numeric = numeric && end != cell.c_str() && *end == '\0';
    }
    if (numeric) rows.push_back(std::move(row));
  }
  return rows;
}

// What a command printed (stdout and stderr together) and how it exited (-1: killed or not run).
struct CommandResult {
  int exit_code;
  std::string output;
};

// Runs `command` through the shell, as a user would type it.
inline CommandResult run_command(const std::string& command) {
  CommandResult result{-1, {}};
  FILE* pipe = popen((command + " 2>&1").c_str(), "r");
  if (!pipe) return result;
  char buffer[4096];
  while (std::fgets(buffer, sizeof buffer, pipe)) result.output += buffer;
  const int status = pclose(pipe);
  result.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return result;
}

// Writes `bytes` to `path` as they are (a fixture file, possibly malformed on purpose).
inline void write_bytes(const std::string& path, const std::string& bytes) {
  std::ofstream out(path, std::ios::binary);
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  ASSERT_TRUE(out.good()) << path;
}

inline int count_lines(const std::string& text) {
  return static_cast<int>(std::count(text.begin(), text.end(), '\n'));
}

// A fresh temporary directory, removed when the object dies.
class TempDir {
 public:
  TempDir() {
    std::random_device rd;
    path_ = std::filesystem::temp_directory_path() /
            ("primlabel-test-" + std::to_string(rd()) + std::to_string(rd()));
    std::filesystem::create_directories(path_);
  }
  ~TempDir() {
    std::error_code ec;
    std::filesystem::remove_all(path_, ec);
  }
  std::string file(const std::string& name) const { return (path_ / name).string(); }

 private:
  std::filesystem::path path_;
};

// `n` points none of which has finite coordinates (a depth frame with its lens covered).
inline PointCloud nan_cloud(std::size_t n) {
  PointCloud cloud;
  cloud.resize_unorganized(n);
  for (Vec3f& p : cloud.xyz) p = Vec3f::Constant(std::numeric_limits<float>::quiet_NaN());
  return cloud;
}

// Points on z = a x + b y over [-extent, extent]^2 at the given spacing.
inline PointCloud plane_grid(float a, float b, float extent, float spacing) {
  PointCloud cloud;
  for (float x = -extent; x <= extent + 1e-6f; x += spacing)
    for (float y = -extent; y <= extent + 1e-6f; y += spacing)
      cloud.xyz.emplace_back(x, y, a * x + b * y);
  cloud.width = static_cast<std::uint32_t>(cloud.xyz.size());
  return cloud;
}

// `n` points spread evenly over a sphere (Fibonacci lattice), optionally jittered.
inline PointCloud sphere(const Vec3f& center, float radius, int n, float jitter = 0.0f,
                         unsigned seed = 1) {
  PointCloud cloud;
  std::mt19937 rng(seed);
  std::normal_distribution<float> noise(0.0f, jitter > 0 ? jitter : 1.0f);
  const float golden = static_cast<float>(M_PI) * (3.0f - std::sqrt(5.0f));
  for (int i = 0; i < n; ++i) {
    const float z = 1.0f - 2.0f * (i + 0.5f) / n;
    const float r = std::sqrt(1.0f - z * z);
    Vec3f p = center + radius * Vec3f(r * std::cos(golden * i), r * std::sin(golden * i), z);
    if (jitter > 0) p += Vec3f(noise(rng), noise(rng), noise(rng)) * 1.0f;
    cloud.xyz.push_back(p);
  }
  cloud.width = static_cast<std::uint32_t>(cloud.xyz.size());
  return cloud;
}

// Uniform random points in a box.
inline PointCloud random_box(int n, float extent, unsigned seed) {
  PointCloud cloud;
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(-extent, extent);
  for (int i = 0; i < n; ++i) cloud.xyz.emplace_back(u(rng), u(rng), u(rng));
  cloud.width = static_cast<std::uint32_t>(n);
  return cloud;
}

}  // namespace primlabel::test
