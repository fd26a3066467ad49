// Fig. 4: class-mean signatures over synthetic scenes, their HIK distances, CSV and PNG.

#include "primlabel/research/fig4.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <stdexcept>

#include "primlabel/geometry/atomic_file.hpp"
#include "primlabel/geometry/taxonomy.hpp"
#include "primlabel/pipeline/labeling.hpp"
#include "primlabel/pipeline/training.hpp"
#include "primlabel/render/heatmap.hpp"

namespace primlabel::research {

namespace {

std::string class_name(std::uint32_t id) {
  const auto c = class_from_id(id);
  return c ? std::string(name(*c)) : std::to_string(id);
}

std::string format(const char* fmt, double v) {
  char buffer[64];
  std::snprintf(buffer, sizeof buffer, fmt, v);
  return buffer;
}

void write_text(const std::string& path, const std::string& text) {
  try {
    atomic_write_file(path, text);
  } catch (const AtomicWriteError& e) {
    throw std::runtime_error(std::string("cannot be written: ") + e.what());
  }
}

std::string signatures_csv(const ClassSignatures& s) {
  std::string out = "class";
  for (Eigen::Index b = 0; b < s.mean.cols(); ++b) out += ",bin" + std::to_string(b);
  out += '\n';
  for (std::size_t k = 0; k < s.class_ids.size(); ++k) {
    out += class_name(s.class_ids[k]);
    for (Eigen::Index b = 0; b < s.mean.cols(); ++b)
      out += "," + format("%.6g", s.mean(Eigen::Index(k), b));
    out += '\n';
  }
  return out;
}

std::string hik_csv(const Fig4& f) {
  std::string out = "class";
  for (std::uint32_t id : f.signatures.class_ids) out += "," + class_name(id);
  out += '\n';
  for (Eigen::Index r = 0; r < f.hik.rows(); ++r) {
    out += class_name(f.signatures.class_ids[std::size_t(r)]);
    for (Eigen::Index c = 0; c < f.hik.cols(); ++c) out += "," + format("%.6f", f.hik(r, c));
    out += '\n';
  }
  return out;
}

// One panel per class, stacked, on a common vertical scale so the shapes compare; dashed lines
// split FPFH's three sub-histograms (alpha, phi, theta).
void write_signatures_png(const ClassSignatures& s, const std::string& path) {
  const int scale = 2, margin = 16, bin_w = 16, panel_h = 70, gap = 10;
  const int bins = int(s.mean.cols()), classes = int(s.class_ids.size());
  int label_w = 0;
  for (std::uint32_t id : s.class_ids)
    label_w = std::max(label_w, Raster::text_width(class_name(id), scale));
  label_w += margin;
  const int title_h = Raster::text_height(scale) + gap;
  const int plot_x = margin + label_w, plot_w = bins * bin_w;
  const int plot_y = margin + title_h;
  const int footer_h = Raster::text_height(scale) + gap;
  Raster raster(plot_x + plot_w + margin,
                plot_y + std::max(classes, 1) * (panel_h + gap) + footer_h + margin);
  const std::uint32_t ink = 0x202020;
  const double top = std::max(1e-9, s.mean.size() ? s.mean.maxCoeff() : 1.0);
  raster.text(margin, margin,
              "class-mean FPFH signatures (common scale, max " + format("%.0f", top) + ")", ink,
              scale);
  for (int k = 0; k < classes; ++k) {
    const int y0 = plot_y + k * (panel_h + gap);
    const std::uint32_t id = s.class_ids[std::size_t(k)];
    const auto cls = class_from_id(id);
    const std::uint32_t rgb = cls ? color(*cls) : 0x404040;
    raster.text(margin, y0 + (panel_h - Raster::text_height(scale)) / 2, class_name(id), ink,
                scale);
    raster.fill(plot_x, y0, plot_w, panel_h, 0xF6F6F6);
    raster.frame(plot_x, y0, plot_w + 1, panel_h + 1, 0xC0C0C0);
    if (bins == 33)
      for (int split : {11, 22})
        for (int y = y0; y < y0 + panel_h; y += 4) raster.set(plot_x + split * bin_w, y, 0x909090);
    auto x_of = [&](int b) { return plot_x + b * bin_w + bin_w / 2.0; };
    auto y_of = [&](double v) { return y0 + panel_h - 2 - (panel_h - 6) * v / top; };
    for (int b = 0; b < bins; ++b) {
      const double v = s.mean(k, b);
      if (b > 0) raster.line(x_of(b - 1), y_of(s.mean(k, b - 1)), x_of(b), y_of(v), rgb, 2);
      raster.fill(int(x_of(b)) - 2, int(y_of(v)) - 2, 5, 5, rgb);
    }
  }
  if (bins == 33) {
    const int y = plot_y + classes * (panel_h + gap);
    const char* names[] = {"f1 alpha", "f2 phi", "f3 theta"};
    for (int h = 0; h < 3; ++h)
      raster.text(plot_x + h * 11 * bin_w + (11 * bin_w - Raster::text_width(names[h], scale)) / 2,
                  y, names[h], ink, scale);
  }
  raster.write_png(path);
}

void write_hik_png(const Fig4& f, const std::string& path) {
  Heatmap heatmap;
  for (std::uint32_t id : f.signatures.class_ids) heatmap.row_names.push_back(class_name(id));
  heatmap.column_names = heatmap.row_names;
  for (Eigen::Index r = 0; r < f.hik.rows(); ++r)
    for (Eigen::Index c = 0; c < f.hik.cols(); ++c) {
      heatmap.shades.push_back(f.hik(r, c));
      heatmap.cell_text.push_back(format("%.2f", f.hik(r, c)));
    }
  heatmap.title = "HIK distance between class-mean signatures";
  draw_heatmap(heatmap).write_png(path);
}

}  // namespace

SignatureAccumulator::SignatureAccumulator(int descriptor_dim)
    : dim_(descriptor_dim),
      sums_(Eigen::MatrixXd::Zero(kPrimitiveClassCount, descriptor_dim)),
      counts_(kPrimitiveClassCount, 0) {
  if (descriptor_dim <= 0) throw std::invalid_argument("signatures: no descriptor bins");
}

void SignatureAccumulator::add(std::span<const std::uint32_t> labels,
                               const Descriptors& descriptors) {
  if (descriptors.dim != dim_ || descriptors.size() != labels.size())
    throw std::invalid_argument(
        "signatures: one descriptor row of the dimension per label expected");
  for (std::size_t i = 0; i < labels.size(); ++i) {
    const std::uint32_t id = labels[i];
    if (id == class_id(PrimitiveClass::kUnknown) || id >= kPrimitiveClassCount) continue;
    const std::span<const float> row = descriptors.row(i);
    if (!std::all_of(row.begin(), row.end(), [](float v) { return std::isfinite(v); })) continue;
    for (int b = 0; b < dim_; ++b) sums_(id, b) += row[b];
    ++counts_[id];
  }
}

ClassSignatures SignatureAccumulator::result() const {
  ClassSignatures out;
  for (std::uint32_t id = 0; id < kPrimitiveClassCount; ++id)
    if (counts_[id]) out.class_ids.push_back(id), out.points.push_back(counts_[id]);
  out.mean.resize(Eigen::Index(out.class_ids.size()), dim_);
  for (std::size_t k = 0; k < out.class_ids.size(); ++k)
    out.mean.row(Eigen::Index(k)) = sums_.row(out.class_ids[k]) / double(out.points[k]);
  return out;
}

double hik_distance(std::span<const double> a, std::span<const double> b) {
  if (a.size() != b.size()) throw std::invalid_argument("hik_distance: histogram sizes differ");
  double common = 0, sum_a = 0, sum_b = 0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    common += std::min(a[i], b[i]);
    sum_a += a[i];
    sum_b += b[i];
  }
  const double smaller = std::min(sum_a, sum_b);
  if (smaller <= 0) return sum_a == sum_b ? 0.0 : 1.0;
  return std::clamp(1.0 - common / smaller, 0.0, 1.0);
}

Eigen::MatrixXd hik_distance_matrix(const ClassSignatures& s) {
  const Eigen::Index k = Eigen::Index(s.class_ids.size());
  // Rows of a column-major matrix are strided: copy each to a contiguous vector.
  std::vector<std::vector<double>> rows(static_cast<std::size_t>(k));
  for (Eigen::Index r = 0; r < k; ++r)
    for (Eigen::Index b = 0; b < s.mean.cols(); ++b) rows[std::size_t(r)].push_back(s.mean(r, b));
  Eigen::MatrixXd d = Eigen::MatrixXd::Zero(k, k);
  for (Eigen::Index r = 0; r < k; ++r)
    for (Eigen::Index c = r + 1; c < k; ++c)
      d(r, c) = d(c, r) = hik_distance(rows[std::size_t(r)], rows[std::size_t(c)]);
  return d;
}

Fig4 run_fig4(const Fig4Options& options) {
  SignatureAccumulator accumulator(options.features.descriptor_dim());
  for (int i = 0; i < options.scenes; ++i) {
    PointCloud cloud = synth::synthetic_scene(synth::SceneSet::kTrain, i, options.sensor);
    const pipeline::DescribedCloud described =
        pipeline::describe_cloud(cloud, options.features, RunContext{options.threads});
    accumulator.add(cloud.labels, described.descriptors);
    if (options.progress)
      options.progress("fig4: " + std::string(synth::set_name(synth::SceneSet::kTrain)) + " seed " +
                       std::to_string(synth::set_seed(synth::SceneSet::kTrain, i)) + ", " +
                       std::to_string(cloud.size()) + " points described");
  }
  Fig4 out;
  out.signatures = accumulator.result();
  out.hik = hik_distance_matrix(out.signatures);
  return out;
}

void write_fig4(const Fig4& fig4, const std::string& directory) {
  std::error_code ec;
  std::filesystem::create_directories(directory, ec);
  if (ec) throw std::runtime_error(directory + ": cannot be created (" + ec.message() + ")");
  const std::filesystem::path dir(directory);
  write_text((dir / "fig4_signatures.csv").string(), signatures_csv(fig4.signatures));
  write_text((dir / "fig4_hik.csv").string(), hik_csv(fig4));
  write_signatures_png(fig4.signatures, (dir / "fig4_signatures.png").string());
  write_hik_png(fig4, (dir / "fig4_hik.png").string());
}

std::string hik_text(const Fig4& f) {
  // Columns by taxonomy id (names are too long for the columns), rows by "id name".
  char cell[48];
  std::snprintf(cell, sizeof cell, "%-22s", "HIK distance");
  std::string out = cell;
  for (std::uint32_t id : f.signatures.class_ids) {
    std::snprintf(cell, sizeof cell, " %6u", id);
    out += cell;
  }
  out += '\n';
  for (Eigen::Index r = 0; r < f.hik.rows(); ++r) {
    const std::uint32_t id = f.signatures.class_ids[std::size_t(r)];
    std::snprintf(cell, sizeof cell, "%2u %-19s", id, class_name(id).c_str());
    out += cell;
    for (Eigen::Index c = 0; c < f.hik.cols(); ++c) {
      std::snprintf(cell, sizeof cell, " %6.3f", f.hik(r, c));
      out += cell;
    }
    out += '\n';
  }
  return out;
}

}  // namespace primlabel::research
