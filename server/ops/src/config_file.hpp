#pragma once
// The server's config file: `key = value` lines named like the flags (without "--"), merged into
// the command line below the flags and the environment.

#include <CLI/CLI.hpp>
#include <string>
#include <vector>

namespace primlabel::ops {

// The command line with the config file's settings (--config, else PRIMLABEL_CONFIG) put in
// front of it, leaving out every setting that a flag or an environment variable gives: flags >
// environment > file. Throws ConfigError naming the file and line.
std::vector<std::string> with_config_file(CLI::App& app, int argc, const char* const* argv);

}  // namespace primlabel::ops
