#pragma once
// The inputs of `primlabel label` as files: a folder stands for the .pcd and .ply files directly
// in it (no subfolders, no hidden files, not this command's own *_labeled.* outputs), sorted by
// name.

#include <string>
#include <vector>

namespace primlabel::client::tools {

struct InputFiles {
  std::vector<std::string> files;
  bool from_folder = false;         // a folder was given: the outputs go as for several files
  std::vector<std::string> errors;  // one line each, e.g. a folder without a scan
};

InputFiles expand_input_folders(const std::vector<std::string>& inputs);

}  // namespace primlabel::client::tools
