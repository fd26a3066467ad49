// primlabel-bench: benchmark tools, one subcommand each (see bench/README.md). This file only
// wires them: every benchmark binds its flags and runs in its own file (bench_commands.hpp).

#include <CLI/CLI.hpp>
#include <string>
#include <vector>

#include "bench_commands.hpp"
#include "features_bench.hpp"
#include "primlabel/build_version.hpp"
#include "primlabel/cli/subcommands.hpp"

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
  // Each benchmark was a binary of its own with --version; they keep it.
  return primlabel::cli::run_subcommands(
      app,
      {{add_features_command(app, features_options),
        [&features_options] { return run_features_bench(features_options); }},
       add_crf_command(app),
       add_pipeline_command(app),
       add_server_command(app),
       add_tabletop_command(app),
       add_primitives_command(app),
       add_can_radii_command(app),
       add_scaling_command(app),
       add_client_command(app),
       add_organised_command(app)},
      version, argc, argv);
}
