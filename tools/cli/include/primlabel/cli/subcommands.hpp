#pragma once
// A binary made of subcommands (primlabel-bench, primlabel-research): each subcommand binds its
// flags in its own file and hands back how to run; run_subcommands parses, runs the one named
// and turns every failure into the exit-code scheme with a one-line reason naming it.

#include <CLI/CLI.hpp>
#include <cstdio>
#include <exception>
#include <functional>
#include <stdexcept>
#include <string>
#include <vector>

#include "primlabel/cli/exit_codes.hpp"

namespace primlabel::cli {

struct Subcommand {
  CLI::App* command = nullptr;
  // Runs the subcommand with the parsed flags; returns the exit code (0 ok, 1 failure, 2 usage).
  std::function<int()> run;
};

// Thrown by a subcommand for arguments its flags' own checks could not refuse (exit 2).
struct UsageError : std::invalid_argument {
  using std::invalid_argument::invalid_argument;
};

// "primlabel-bench crf" once the command line named a subcommand, so messages say which one.
inline std::string command_name(const CLI::App& app) {
  const auto chosen = app.get_subcommands();
  return chosen.empty() ? app.get_name() : app.get_name() + " " + chosen.front()->get_name();
}

// Gives every subcommand the binary's --version, parses, and runs the one named: --help and
// --version exit 0; a parse error or UsageError is "NAME SUB: usage error: ..." and exit 2;
// any other exception "NAME SUB: error: ..." and exit 1.
inline int run_subcommands(CLI::App& app, const std::vector<Subcommand>& commands,
                           const std::string& version, int argc, char** argv) {
  for (const Subcommand& command : commands)
    command.command->set_version_flag("--version", version);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& error) {
    if (error.get_exit_code() == 0) return app.exit(error);  // --help, --version
    std::fprintf(stderr, "%s: usage error: %s (see --help)\n", command_name(app).c_str(),
                 error.what());
    return kExitUsage;
  }
  for (const Subcommand& command : commands) {
    if (!command.command->parsed()) continue;
    try {
      return command.run();
    } catch (const UsageError& error) {
      std::fprintf(stderr, "%s: usage error: %s\n", command_name(app).c_str(), error.what());
      return kExitUsage;
    } catch (const std::exception& error) {
      std::fprintf(stderr, "%s: error: %s\n", command_name(app).c_str(), error.what());
      return kExitFailure;
    }
  }
  return kExitUsage;
}

}  // namespace primlabel::cli
