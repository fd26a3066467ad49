#pragma once
// Whether a resolved path lies in the model repository: the registry resolves every model
// directory, version directory and model file (symlinks followed) and refuses those that lead
// outside it, so the server only ever reads files under its repository.

#include <filesystem>

namespace primlabel::service {

// True when `path` is `root` or lies below it; both canonical. Compared component by component,
// so "/models-evil" does not lie within "/models".
bool is_within(const std::filesystem::path& root, const std::filesystem::path& path);

}  // namespace primlabel::service
