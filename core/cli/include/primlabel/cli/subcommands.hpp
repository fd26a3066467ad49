#pragma once
// A binary made of subcommands (primlabel-bench, primlabel-research): each subcommand binds its
// flags in its own file and hands back how to run; run_subcommands parses, runs the one named
// and turns every failure into the exit-code scheme with a one-line reason naming it.

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cstddef>
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

// "health, models, info, label": the subcommands' names, in the order they were added.
inline std::string command_names(const CLI::App& app) {
  std::string out;
  for (const CLI::App* sub : app.get_subcommands({}))
    out += (out.empty() ? "" : ", ") + sub->get_name();
  return out;
}

// " (did you mean 'label'?)" when a subcommand is within two edits of `word`, else "".
inline std::string did_you_mean(const std::string& word, const CLI::App& app) {
  const auto distance = [](const std::string& a, const std::string& b) {
    std::vector<std::size_t> row(b.size() + 1);
    for (std::size_t j = 0; j <= b.size(); ++j) row[j] = j;
    for (std::size_t i = 1; i <= a.size(); ++i) {
      std::size_t diagonal = row[0];
      row[0] = i;
      for (std::size_t j = 1; j <= b.size(); ++j) {
        const std::size_t above = row[j];
        row[j] = std::min({row[j] + 1, row[j - 1] + 1, diagonal + (a[i - 1] == b[j - 1] ? 0 : 1)});
        diagonal = above;
      }
    }
    return row[b.size()];
  };
  std::string best;
  std::size_t best_distance = 3;
  for (const CLI::App* sub : app.get_subcommands({}))
    if (const std::size_t d = distance(word, sub->get_name()); d < best_distance)
      best = sub->get_name(), best_distance = d;
  return best.empty() ? std::string() : " (did you mean '" + best + "'?)";
}

// The usage error for a word taken where a subcommand was expected ("primlabel lable x.pcd"),
// or "" when the parse failed otherwise: "unknown command 'lable' (did you mean 'label'?); the
// commands: ...".
inline std::string unknown_command_message(const CLI::App& app) {
  if (!app.get_subcommands().empty()) return {};
  const std::vector<std::string> left = app.remaining();
  if (left.empty() || left.front().starts_with("-")) return {};
  return "unknown command '" + left.front() + "'" + did_you_mean(left.front(), app) +
         "; the commands: " + command_names(app);
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
    const std::string unknown = unknown_command_message(app);
    std::fprintf(stderr, "%s: usage error: %s (see --help)\n", command_name(app).c_str(),
                 unknown.empty() ? error.what() : unknown.c_str());
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
