// primlabel-pcl-reference: dumps what PCL 1.13 computes for one cloud (normals, FPFH, PFH, k-NN
// lists) as CSV so primlabel's tests can check bit-level compatibility without linking PCL.
//
// Descriptors are computed from the normals STORED in the input file (not re-estimated) so that a
// descriptor fixture isolates the descriptor arithmetic from normal estimation. Everything runs
// single-threaded (the non-OMP PCL classes) with a sorted pcl::search::KdTree, so the neighbour
// order and therefore the floating-point summation order are deterministic.

#include <pcl/features/fpfh.h>
#include <pcl/features/normal_3d.h>
#include <pcl/features/pfh.h>
#include <pcl/io/pcd_io.h>
#include <pcl/point_types.h>
#include <pcl/search/kdtree.h>

#include <CLI/CLI.hpp>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <iostream>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "primlabel/build_version.hpp"

namespace {

using CloudXYZ = pcl::PointCloud<pcl::PointXYZ>;
using CloudNormal = pcl::PointCloud<pcl::Normal>;

// The neighbourhood definition of one fixture: exactly one of k / radius is non-zero.
struct SearchSpec {
  int k = 0;
  double radius = 0.0;

  // File-name suffix: "k10" or "r0.01".
  std::string tag() const {
    if (k > 0) return "k" + std::to_string(k);
    char buffer[32];
    std::snprintf(buffer, sizeof(buffer), "r%g", radius);
    return buffer;
  }
};

std::string format_value(float value) {
  // "%g" would print "-nan" for some NaN payloads; readers want one spelling.
  if (std::isnan(value)) return "nan";
  char buffer[32];
  std::snprintf(buffer, sizeof(buffer), "%.9g", value);
  return buffer;
}

// Writes a header line then `rows` lines of `columns` values produced by `value_at(row, column)`.
void write_csv(const std::filesystem::path& path, const std::vector<std::string>& header,
               std::size_t rows,
               const std::function<std::string(std::size_t, std::size_t)>& value_at) {
  std::FILE* file = std::fopen(path.c_str(), "w");
  if (!file) throw std::runtime_error("cannot write " + path.string());
  for (std::size_t c = 0; c < header.size(); ++c)
    std::fprintf(file, "%s%s", c ? "," : "", header[c].c_str());
  std::fputc('\n', file);
  for (std::size_t r = 0; r < rows; ++r) {
    for (std::size_t c = 0; c < header.size(); ++c)
      std::fprintf(file, "%s%s", c ? "," : "", value_at(r, c).c_str());
    std::fputc('\n', file);
  }
  if (std::fclose(file) != 0) throw std::runtime_error("error writing " + path.string());
  std::cerr << "wrote " << path.string() << " (" << rows << " rows)\n";
}

std::vector<std::string> numbered_columns(const std::string& prefix, int count) {
  std::vector<std::string> names;
  for (int i = 0; i < count; ++i) names.push_back(prefix + std::to_string(i));
  return names;
}

pcl::search::KdTree<pcl::PointXYZ>::Ptr sorted_kdtree() {
  // sorted = true: results in ascending distance, like primlabel's NeighborSearch. (PCL's Feature
  // default when no tree is given is an UNsorted KdTree.)
  return std::make_shared<pcl::search::KdTree<pcl::PointXYZ>>(true);
}

template <typename Estimator>
void apply_search(Estimator& estimator, const SearchSpec& spec) {
  estimator.setSearchMethod(sorted_kdtree());
  if (spec.k > 0)
    estimator.setKSearch(spec.k);
  else
    estimator.setRadiusSearch(spec.radius);
}

void write_normals(const CloudXYZ::ConstPtr& cloud, const SearchSpec& spec,
                   const std::filesystem::path& path) {
  pcl::NormalEstimation<pcl::PointXYZ, pcl::Normal> estimator;
  estimator.setInputCloud(cloud);
  apply_search(estimator, spec);
  estimator.setViewPoint(0.0f, 0.0f, 0.0f);
  CloudNormal normals;
  estimator.compute(normals);
  write_csv(path, {"nx", "ny", "nz", "curvature"}, normals.size(),
            [&](std::size_t r, std::size_t c) {
              const pcl::Normal& n = normals[r];
              return format_value(c < 3 ? n.normal[c] : n.curvature);
            });
}

template <typename Estimator, typename Signature, int kBins>
void write_descriptor(const CloudXYZ::ConstPtr& cloud, const CloudNormal::ConstPtr& normals,
                      const SearchSpec& spec, const std::filesystem::path& path) {
  Estimator estimator;
  estimator.setInputCloud(cloud);
  estimator.setInputNormals(normals);
  apply_search(estimator, spec);
  pcl::PointCloud<Signature> descriptors;
  estimator.compute(descriptors);
  write_csv(
      path, numbered_columns("f", kBins), descriptors.size(),
      [&](std::size_t r, std::size_t c) { return format_value(descriptors[r].histogram[c]); });
}

// The k nearest neighbours of every point (itself included) and their squared distances, exactly
// as KdTreeFLANN returns them, for debugging neighbour-order differences.
void write_knn(const CloudXYZ::ConstPtr& cloud, int k, const std::filesystem::path& path) {
  auto tree = sorted_kdtree();
  tree->setInputCloud(cloud);
  std::vector<pcl::Indices> indices(cloud->size());
  std::vector<std::vector<float>> sq_dists(cloud->size());
  for (std::size_t i = 0; i < cloud->size(); ++i)
    tree->nearestKSearch(static_cast<pcl::index_t>(i), k, indices[i], sq_dists[i]);
  std::vector<std::string> header = numbered_columns("i", k);
  for (const auto& name : numbered_columns("sqd", k)) header.push_back(name);
  const auto kk = static_cast<std::size_t>(k);
  write_csv(path, header, cloud->size(), [&](std::size_t r, std::size_t c) -> std::string {
    if (c < kk) return c < indices[r].size() ? std::to_string(indices[r][c]) : "-1";
    return c - kk < sq_dists[r].size() ? format_value(sq_dists[r][c - kk]) : "nan";
  });
}

bool has_field(const pcl::PCLPointCloud2& blob, const std::string& name) {
  for (const auto& field : blob.fields)
    if (field.name == name) return true;
  return false;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Writes PCL 1.13 reference normals/FPFH/PFH for a PCD as CSV fixtures"};
  app.set_version_flag("--version", primlabel::version_line("primlabel-pcl-reference"));
  std::string input;
  std::string output_dir = ".";
  std::string name;
  int k = 10;
  std::vector<double> radii = {0.01, 0.02};
  app.add_option("--input", input, "PCD with x y z (and normal_x normal_y normal_z curvature)")
      ->required()
      ->check(CLI::ExistingFile);
  app.add_option("--output-dir", output_dir, "where the CSV files go")->capture_default_str();
  app.add_option("--name", name, "file-name prefix (default: input stem)");
  app.add_option("--k", k, "k for the k-NN fixtures")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  app.add_option("--radius", radii, "radii for the radius-search FPFH fixtures")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  CLI11_PARSE(app, argc, argv);

  try {
    if (name.empty()) name = std::filesystem::path(input).stem().string();
    const std::filesystem::path dir(output_dir);
    std::filesystem::create_directories(dir);
    const auto out = [&](const std::string& what) { return dir / (name + "_" + what + ".csv"); };

    pcl::PCLPointCloud2 blob;
    if (pcl::io::loadPCDFile(input, blob) != 0) throw std::runtime_error("cannot read " + input);
    auto cloud = std::make_shared<CloudXYZ>();
    pcl::fromPCLPointCloud2(blob, *cloud);
    std::cerr << input << ": " << cloud->size() << " points\n";

    const SearchSpec knn{k, 0.0};
    write_normals(cloud, knn, out("normals_" + knn.tag()));
    write_knn(cloud, k, out("knn" + std::to_string(k)));

    if (!has_field(blob, "normal_x")) {
      std::cerr << "no stored normals in " << input << ": descriptor fixtures skipped\n";
      return 0;
    }
    auto normals = std::make_shared<CloudNormal>();
    pcl::fromPCLPointCloud2(blob, *normals);

    using Fpfh = pcl::FPFHEstimation<pcl::PointXYZ, pcl::Normal, pcl::FPFHSignature33>;
    using Pfh = pcl::PFHEstimation<pcl::PointXYZ, pcl::Normal, pcl::PFHSignature125>;
    write_descriptor<Fpfh, pcl::FPFHSignature33, 33>(cloud, normals, knn, out("fpfh_" + knn.tag()));
    for (double radius : radii) {
      const SearchSpec by_radius{0, radius};
      write_descriptor<Fpfh, pcl::FPFHSignature33, 33>(cloud, normals, by_radius,
                                                       out("fpfh_" + by_radius.tag()));
    }
    write_descriptor<Pfh, pcl::PFHSignature125, 125>(cloud, normals, knn, out("pfh_" + knn.tag()));
  } catch (const std::exception& error) {
    std::cerr << "primlabel-pcl-reference: " << error.what() << "\n";
    return 1;
  }
  return 0;
}
