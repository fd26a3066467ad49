#include "primlabel/service/repository_path.hpp"

#include <algorithm>

namespace primlabel::service {

bool is_within(const std::filesystem::path& root, const std::filesystem::path& path) {
  auto root_end = root.end();
  if (root_end != root.begin() && std::prev(root_end)->empty()) --root_end;  // trailing '/'
  return std::mismatch(root.begin(), root_end, path.begin(), path.end()).first == root_end;
}

}  // namespace primlabel::service
