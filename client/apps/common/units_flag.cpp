#include "units_flag.hpp"

#include <map>
#include <string>

namespace primlabel::client::tools {

CLI::Option* add_units_flag(CLI::App& app, float& metres_per_unit) {
  const std::map<std::string, float> units{{"mm", 0.001f}, {"cm", 0.01f}, {"m", 1.0f}};
  return app
      .add_option("--units", metres_per_unit,
                  "Unit of the cloud's coordinates: mm, cm or m (default m); the server works "
                  "in metres, the written files keep the input's coordinates")
      ->transform(CLI::CheckedTransformer(units, CLI::ignore_case));
}

}  // namespace primlabel::client::tools
