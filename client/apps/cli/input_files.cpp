#include "input_files.hpp"

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <system_error>

namespace primlabel::client::tools {

namespace fs = std::filesystem;

namespace {

bool is_scan_file(const fs::path& path) {
  std::string ext = path.extension().string();
  for (char& c : ext) c = char(std::tolower(static_cast<unsigned char>(c)));
  const std::string stem = path.stem().string();
  // Labeling a folder twice must not label the first run's outputs.
  return (ext == ".pcd" || ext == ".ply") && !path.filename().string().starts_with(".") &&
         !stem.ends_with("_labeled");
}

}  // namespace

InputFiles expand_input_folders(const std::vector<std::string>& inputs) {
  InputFiles out;
  for (const std::string& input : inputs) {
    std::error_code ec;
    if (!fs::is_directory(input, ec)) {
      out.files.push_back(input);  // a file, or a missing one that reading will name
      continue;
    }
    out.from_folder = true;
    std::vector<std::string> found;
    for (fs::directory_iterator it(input, ec), end; !ec && it != end; it.increment(ec))
      if (it->is_regular_file(ec) && is_scan_file(it->path())) found.push_back(it->path().string());
    if (ec) {
      out.errors.push_back(input + ": cannot list the folder: " + ec.message());
      continue;
    }
    if (found.empty()) {
      out.errors.push_back(input + ": no .pcd or .ply file in the folder");
      continue;
    }
    std::sort(found.begin(), found.end());
    out.files.insert(out.files.end(), found.begin(), found.end());
  }
  return out;
}

}  // namespace primlabel::client::tools
