// primlabel._cloud_files: core/geometry's PCD and PLY reader and writer for the Python package, so
// Python reads and writes clouds with the same code as the service and its tools. Clouds cross as
// plain values (numpy arrays, a list of (name, array) fields, width, height, viewpoint); the
// Python modules primlabel.pcd and primlabel.ply build their PointCloud from them.

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <cstdint>
#include <cstring>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "primlabel/geometry/cloud_io.hpp"
#include "primlabel/geometry/labeled_cloud.hpp"
#include "primlabel/geometry/point_cloud.hpp"

namespace py = pybind11;

namespace {

using primlabel::IoError;
using primlabel::PointCloud;

// forcecast: callers pass any numeric dtype, as the Python writer accepted before.
using FloatArray = py::array_t<float, py::array::c_style | py::array::forcecast>;
using UintArray = py::array_t<std::uint32_t, py::array::c_style | py::array::forcecast>;

template <typename T>
py::array_t<T> to_array(const T* data, std::size_t rows, std::size_t columns, bool matrix) {
  std::vector<py::ssize_t> shape{static_cast<py::ssize_t>(rows)};
  if (matrix) shape.push_back(static_cast<py::ssize_t>(columns));
  py::array_t<T> out(shape);
  if (rows * columns > 0) std::memcpy(out.mutable_data(), data, rows * columns * sizeof(T));
  return out;
}

py::array_t<float> points_array(const std::vector<primlabel::Vec3f>& points) {
  static_assert(sizeof(primlabel::Vec3f) == 3 * sizeof(float));
  return to_array(points.empty() ? nullptr : points.front().data(), points.size(), 3, true);
}

py::dict cloud_to_python(const PointCloud& cloud) {
  py::dict out;
  const std::size_t n = cloud.size();
  out["xyz"] = points_array(cloud.xyz);
  out["normals"] = cloud.has_normals() ? py::object(points_array(cloud.normals)) : py::none();
  out["curvature"] = cloud.has_curvature()
                         ? py::object(to_array(cloud.curvature.data(), n, 1, false))
                         : py::none();
  out["labels"] =
      cloud.has_labels() ? py::object(to_array(cloud.labels.data(), n, 1, false)) : py::none();
  out["rgba"] =
      cloud.has_rgba() ? py::object(to_array(cloud.rgba.data(), n, 1, false)) : py::none();
  py::list fields;
  for (const auto& field : cloud.fields)
    fields.append(py::make_tuple(field.name,
                                 to_array(field.values.data(), n, field.count, field.count != 1)));
  out["fields"] = fields;
  out["width"] = cloud.width;
  out["height"] = cloud.height;
  const auto& v = cloud.viewpoint;
  out["viewpoint"] = py::make_tuple(v.origin.x(), v.origin.y(), v.origin.z(), v.orientation.w(),
                                    v.orientation.x(), v.orientation.y(), v.orientation.z());
  return out;
}

[[noreturn]] void refuse(const std::string& path, const std::string& message) {
  throw IoError(path + ": " + message);
}

std::string shape_text(const py::array& array) {
  std::string text = "(";
  for (py::ssize_t d = 0; d < array.ndim(); ++d)
    text += (d ? ", " : "") + std::to_string(array.shape(d));
  return text + (array.ndim() == 1 ? ",)" : ")");
}

// (n, 3) -> points; shape mistakes are refused with the path, as the readers' errors.
std::vector<primlabel::Vec3f> points_from(const std::string& path, const char* what,
                                          const FloatArray& array, std::size_t n) {
  if (array.ndim() != 2 || array.shape(1) != 3 || static_cast<std::size_t>(array.shape(0)) != n)
    refuse(path, std::string(what) + " has shape " + shape_text(array) + ", expected (" +
                     std::to_string(n) + ", 3)");
  std::vector<primlabel::Vec3f> points(n);
  if (n) std::memcpy(points.front().data(), array.data(), n * 3 * sizeof(float));
  return points;
}

// One value a point: (n,) or (n, 1).
template <typename T, typename Array>
std::vector<T> values_from(const std::string& path, const std::string& what, const Array& array,
                           std::size_t n) {
  const bool column = array.ndim() == 2 && array.shape(1) == 1;
  if ((array.ndim() != 1 && !column) || static_cast<std::size_t>(array.shape(0)) != n)
    refuse(path,
           what + " has shape " + shape_text(array) + ", expected (" + std::to_string(n) + ",)");
  return std::vector<T>(array.data(), array.data() + n);
}

PointCloud cloud_from_python(const std::string& path, const FloatArray& xyz,
                             const std::optional<FloatArray>& normals,
                             const std::optional<FloatArray>& curvature,
                             const std::optional<UintArray>& labels,
                             const std::optional<UintArray>& rgba,
                             const std::vector<std::pair<std::string, FloatArray>>& fields,
                             std::optional<std::uint64_t> width, std::uint64_t height,
                             const std::vector<double>& viewpoint) {
  if (xyz.ndim() != 2) refuse(path, "xyz has shape " + shape_text(xyz) + ", expected (N, 3)");
  const std::size_t n = static_cast<std::size_t>(xyz.shape(0));
  PointCloud cloud;
  cloud.xyz = points_from(path, "xyz", xyz, n);
  if (normals) cloud.normals = points_from(path, "normals", *normals, n);
  if (curvature) cloud.curvature = values_from<float>(path, "curvature", *curvature, n);
  if (labels) cloud.labels = values_from<std::uint32_t>(path, "label", *labels, n);
  if (rgba) cloud.rgba = values_from<std::uint32_t>(path, "rgb", *rgba, n);
  for (const auto& [name, values] : fields) {
    const std::string what = "field '" + name + "'";
    if (values.ndim() == 2 && static_cast<std::size_t>(values.shape(0)) == n &&
        values.shape(1) > 0) {
      const auto count = static_cast<std::size_t>(values.shape(1));
      cloud.fields.push_back({name, static_cast<int>(count),
                              std::vector<float>(values.data(), values.data() + n * count)});
    } else {
      cloud.fields.push_back({name, 1, values_from<float>(path, what, values, n)});
    }
  }
  const std::uint64_t row = width.value_or(n);
  if (row * height != n)
    refuse(path, "width " + std::to_string(row) + " x height " + std::to_string(height) +
                     " is not " + std::to_string(n) + " points");
  if (row > UINT32_MAX || height > UINT32_MAX) refuse(path, "width or height above 4294967295");
  cloud.width = static_cast<std::uint32_t>(row);
  cloud.height = static_cast<std::uint32_t>(height);
  if (viewpoint.size() != 7) refuse(path, "viewpoint needs 7 values (tx ty tz qw qx qy qz)");
  cloud.viewpoint.origin =
      primlabel::Vec3f(static_cast<float>(viewpoint[0]), static_cast<float>(viewpoint[1]),
                       static_cast<float>(viewpoint[2]));
  cloud.viewpoint.orientation =
      Eigen::Quaternionf(static_cast<float>(viewpoint[3]), static_cast<float>(viewpoint[4]),
                         static_cast<float>(viewpoint[5]), static_cast<float>(viewpoint[6]));
  return cloud;
}

primlabel::PcdEncoding pcd_encoding(const std::string& path, const std::string& name) {
  if (name == "ascii") return primlabel::PcdEncoding::kAscii;
  if (name == "binary") return primlabel::PcdEncoding::kBinary;
  if (name == "binary_compressed") return primlabel::PcdEncoding::kBinaryCompressed;
  refuse(path, "encoding must be 'ascii', 'binary' or 'binary_compressed', got '" + name + "'");
}

primlabel::PlyEncoding ply_encoding(const std::string& path, const std::string& name) {
  if (name == "ascii") return primlabel::PlyEncoding::kAscii;
  if (name == "binary_little_endian") return primlabel::PlyEncoding::kBinaryLittleEndian;
  refuse(path, "encoding must be 'ascii' or 'binary_little_endian', got '" + name + "'");
}

template <typename Reader>
py::dict read_with(Reader reader, const std::string& path) {
  PointCloud cloud;
  {
    py::gil_scoped_release unlocked;  // a frame takes milliseconds: other threads may run
    cloud = reader(path);
  }
  return cloud_to_python(cloud);
}

// write_pcd and write_ply: the cloud as keyword arguments, the encoding by name; they differ only
// in the encodings they know and the writer they call.
template <typename Encoding, typename Write>
void def_writer(py::module_& module, const char* name,
                Encoding (*encoding_named)(const std::string&, const std::string&), Write write) {
  module.def(
      name,
      [encoding_named, write](
          const std::string& path, const FloatArray& xyz, const std::optional<FloatArray>& normals,
          const std::optional<FloatArray>& curvature, const std::optional<UintArray>& labels,
          const std::optional<UintArray>& rgba,
          const std::vector<std::pair<std::string, FloatArray>>& fields,
          std::optional<std::uint64_t> width, std::uint64_t height,
          const std::vector<double>& viewpoint, const std::string& encoding) {
        const Encoding kind = encoding_named(path, encoding);
        const PointCloud cloud = cloud_from_python(path, xyz, normals, curvature, labels, rgba,
                                                   fields, width, height, viewpoint);
        py::gil_scoped_release unlocked;  // writing and compressing a frame takes milliseconds
        write(path, cloud, kind);
      },
      py::arg("path"), py::arg("xyz"), py::arg("normals"), py::arg("curvature"), py::arg("labels"),
      py::arg("rgba"), py::arg("fields"), py::arg("width"), py::arg("height"), py::arg("viewpoint"),
      py::arg("encoding"));
}

}  // namespace

PYBIND11_MODULE(_cloud_files, module) {
  module.doc() = "core/geometry's PCD and PLY reader and writer (cloud_io.hpp)";
  // A ValueError, as the Python readers' PcdError and PlyError, whose messages start with the path.
  py::register_exception<IoError>(module, "IoError", PyExc_ValueError);

  module.def(
      "read_pcd", [](const std::string& path) { return read_with(primlabel::read_pcd, path); },
      py::arg("path"));
  module.def(
      "read_ply", [](const std::string& path) { return read_with(primlabel::read_ply, path); },
      py::arg("path"));
  // The "primlabel <key> <value>" header tags (the class list of a labeled file), a dict.
  module.def(
      "read_tags",
      [](const std::string& path) {
        py::gil_scoped_release unlocked;
        return primlabel::read_cloud_tags(path);
      },
      py::arg("path"));
  def_writer(module, "write_pcd", pcd_encoding,
             [](const std::string& path, const PointCloud& cloud, primlabel::PcdEncoding kind) {
               primlabel::write_pcd(path, cloud, kind);
             });
  def_writer(module, "write_ply", ply_encoding,
             [](const std::string& path, const PointCloud& cloud, primlabel::PlyEncoding kind) {
               primlabel::write_ply(path, cloud, kind);
             });
}
