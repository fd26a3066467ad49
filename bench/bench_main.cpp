// primlabel-bench: benchmark tools, one subcommand each (see bench/README.md). This file only
// wires them: every benchmark binds its flags and runs in its own file (bench_commands.hpp).

#include <CLI/CLI.hpp>
#include <cstdio>
#include <exception>
#include <string>
#include <vector>

#include "bench_commands.hpp"
#include "features_bench.hpp"
#include "primlabel/build_version.hpp"
#include "primlabel/cli/exit_codes.hpp"

namespace {

// "primlabel-bench crf" once the command line named a benchmark, so messages say which one.
std::string command_name(const CLI::App& app) {
  const auto chosen = app.get_subcommands();
  return chosen.empty() ? app.get_name() : app.get_name() + " " + chosen.front()->get_name();
}

}  // namespace

int main(int argc, char** argv) {
  using namespace primlabel::bench;
  CLI::App app{"primlabel benchmarks: speed and accuracy, optionally against PCL and CGAL",
               "primlabel-bench"};
  const std::string version = primlabel::version_line("primlabel-bench");
  app.set_version_flag("--version", version);
  // Every option with a default shows it in --help ("[0.025]"); the subcommands inherit this.
  app.option_defaults()->always_capture_default();
  app.require_subcommand(1);

  FeaturesBenchOptions features_options;
  const std::vector<BenchCommand> commands = {
      {add_features_command(app, features_options),
       [&features_options] { return run_features_bench(features_options); }},
      add_crf_command(app),
      add_pipeline_command(app),
      add_server_command(app),
      add_tabletop_command(app),
      add_primitives_command(app),
      add_can_radii_command(app),
  };
  // Each benchmark was a binary of its own with --version; they keep it.
  for (const BenchCommand& bench : commands) bench.command->set_version_flag("--version", version);

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& error) {
    if (error.get_exit_code() == 0) return app.exit(error);  // --help, --version
    std::fprintf(stderr, "%s: usage error: %s (see --help)\n", command_name(app).c_str(),
                 error.what());
    return primlabel::kExitUsage;
  }

  for (const BenchCommand& bench : commands) {
    if (!bench.command->parsed()) continue;
    try {
      return bench.run();
    } catch (const std::exception& error) {
      std::fprintf(stderr, "%s: error: %s\n", command_name(app).c_str(), error.what());
      return primlabel::kExitFailure;
    }
  }
  return primlabel::kExitUsage;
}
