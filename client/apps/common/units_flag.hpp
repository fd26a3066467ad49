#pragma once
// --units mm|cm|m: the unit of a cloud's coordinates, for files written in millimetres (many
// depth-camera tools) or centimetres. The client scales points and viewpoint on the way out
// (LabelOptions::metres_per_unit); the files written back keep the input's own coordinates.

#include <CLI/CLI.hpp>

namespace primlabel::client::tools {

// Adds --units to `app`, writing metres per unit (0.001, 0.01 or 1) into `metres_per_unit`.
CLI::Option* add_units_flag(CLI::App& app, float& metres_per_unit);

}  // namespace primlabel::client::tools
