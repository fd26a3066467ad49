// primlabel-bench: benchmark tools, one subcommand each (see bench/README.md).

#include <CLI/CLI.hpp>
#include <exception>
#include <iostream>

#include "features_bench.hpp"
#include "primlabel/build_version.hpp"
#include "primlabel/cli/exit_codes.hpp"

int main(int argc, char** argv) {
  CLI::App app{"primlabel benchmarks: throughput and memory, optionally against PCL"};
  app.set_version_flag("--version", primlabel::version_line("primlabel-bench"));
  // Every option with a default shows it in --help ("[0.025]").
  app.option_defaults()->always_capture_default();
  app.require_subcommand(1);

  primlabel::bench::FeaturesBenchOptions features_options;
  CLI::App* features = primlabel::bench::add_features_command(app, features_options);

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& error) {
    // CLI11 prints the help or the reason; keep the project's exit codes (2 = bad usage).
    return app.exit(error) == 0 ? primlabel::kExitOk : primlabel::kExitUsage;
  }

  try {
    if (features->parsed()) return primlabel::bench::run_features_bench(features_options);
  } catch (const std::exception& error) {
    std::cerr << "primlabel-bench: " << error.what() << "\n";
    return primlabel::kExitFailure;
  }
  return primlabel::kExitUsage;
}
