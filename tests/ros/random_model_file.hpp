#pragma once
// The small random-weight model (tests/random_label_model.hpp) as a model file, from a C++20
// translation unit: the ROS test itself is C++17 (the ROS message headers need it) and does not
// include the model headers.

#include <string>

namespace primlabel::rostest {

// Writes random_label_model(name) to `path`.
void write_random_label_model(const std::string& path, const std::string& name);

}  // namespace primlabel::rostest
