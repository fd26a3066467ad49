#pragma once
// The subcommands of `primlabel`; each returns the process exit code (exit_codes.hpp) and
// prints its one-line errors itself. ClientErrors that end the whole run propagate.

#include <string>
#include <vector>

#include "primlabel/client/client.hpp"

namespace primlabel::client::tools {

int run_health(Client& client, const std::string& service);
int run_models(Client& client);
int run_info(Client& client, const std::string& model, const std::string& version);

struct LabelCommand {
  std::vector<std::string> inputs;
  std::string output;
  bool png = false;
  std::string view = "auto";  // of the PNG: auto, sensor, top or oblique (as primlabel-render)
  bool descriptors = false;
  bool probabilities = false;
  std::string primitives;  // --primitives: JSON file (one input) or directory (several)
  std::string objects;     // --objects (needs --tabletop): likewise, and an `object` field
  bool unary = false;
  bool quiet = false;
  LabelOptions options;
  // Set by run_label: several inputs (or a folder) write one file each into -o as a directory.
  bool into_directory = false;
};

int run_label(Client& client, LabelCommand command);

}  // namespace primlabel::client::tools
