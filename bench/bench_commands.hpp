#pragma once
// The benchmarks of `primlabel-bench`, one subcommand each. Every add_*_command is defined in its
// benchmark's own file: it binds the subcommand's flags and returns how to run it, so
// bench_main.cpp only wires them. (`features` keeps its options in features_bench.hpp.)

#include "primlabel/cli/subcommands.hpp"

namespace primlabel::bench {

using BenchCommand = cli::Subcommand;  // a benchmark: its flags and how to run it

BenchCommand add_crf_command(CLI::App& parent);         // crf_bench.cpp
BenchCommand add_pipeline_command(CLI::App& parent);    // pipeline_bench.cpp
BenchCommand add_server_command(CLI::App& parent);      // server_bench.cpp
BenchCommand add_tabletop_command(CLI::App& parent);    // tabletop_bench.cpp
BenchCommand add_primitives_command(CLI::App& parent);  // primitives_bench.cpp
BenchCommand add_can_radii_command(CLI::App& parent);   // can_radii_bench.cpp
BenchCommand add_scaling_command(CLI::App& parent);     // scaling_bench.cpp
BenchCommand add_client_command(CLI::App& parent);      // client_bench.cpp
BenchCommand add_organised_command(CLI::App& parent);   // organised_bench.cpp

}  // namespace primlabel::bench
