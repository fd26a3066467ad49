#include "truth_outputs.hpp"

#include <filesystem>
#include <stdexcept>
#include <system_error>

namespace primlabel::research_tool {

void make_directory(const std::string& dir) {
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec) throw std::runtime_error(dir + ": cannot be created (" + ec.message() + ")");
}

research::MosdTruthRequest truth_request(bool enabled, double radius, const std::string& truth_dir,
                                         const std::string& scene) {
  research::MosdTruthRequest request;
  request.enabled = enabled || !truth_dir.empty();
  request.options.label_radius = radius;
  if (!truth_dir.empty())
    request.write_path = (std::filesystem::path(truth_dir) /
                          (std::filesystem::path(scene).stem().string() + "_truth.pcd"))
                             .string();
  return request;
}

}  // namespace primlabel::research_tool
