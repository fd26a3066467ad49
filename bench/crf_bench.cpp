// primlabel-bench crf: points/s of crf::infer on a synthetic scene shaped like a real scan's CRF
// (Rusu et al. 2009 report 76,997 points/s): points on a jittered grid, descriptors = one of K
// class prototypes + noise (d = 33), kNN-8 graph, and a hand-made model (nearest-prototype node
// weights, edge weights with random feature terms) or one trained by pseudo-likelihood on a
// smaller scene of the same family. Prints, never asserts; the last line is JSON. On a busy
// machine compare cpu_ms at 1 thread (OMP_WAIT_POLICY=passive keeps spinning out of cpu_ms).
//
//   primlabel-bench crf --points 70225 --threads 1,2 --repeat 5
//   primlabel-bench crf --model potts --coupling 1 --seed 1 --threads 2 --repeat 1
//     (the second: what the test CrfInference.Speed70k printed before it moved here)

#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <memory>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "bench_commands.hpp"
#include "crf_scenes.hpp"
#include "primlabel/crf/inference.hpp"
#include "primlabel/crf/training.hpp"
#include "primlabel/geometry/json_text.hpp"

namespace {

using namespace primlabel;
using namespace primlabel::crf;

struct Arguments {
  int points = 70225;
  int classes = 10;
  int neighbors = 8;
  float noise = 40.0f;
  std::vector<int> threads = {1, 2};
  int repeat = 5;
  std::string model = "prototype";  // prototype | potts | trained
  float coupling = 0.25f;           // potts: the one coupling
  std::uint32_t seed = 11;          // the scene's noise and jitter
  std::vector<std::string> methods = {"bp-sum", "bp-max", "mean-field", "node-only"};
};

struct Case {
  std::string name;
  InferenceMethod method;
  bool max_product;
  bool edges;  // false: node-only model
};

struct Row {
  std::string name;
  int threads = 0;
  bool marginals = false;
  bool workspace = false;
  double ms = 0.0;
  double cpu_ms = 0.0;  // process CPU time: robust to a busy machine, but counts spin-waiting
  double points_per_s = 0.0;
  int iterations = 0;
  bool converged = false;
  double accuracy = 0.0;
};

double cpu_seconds() {
  timespec t{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return double(t.tv_sec) + 1e-9 * double(t.tv_nsec);
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

double accuracy(const InferenceResult& r, const LabeledGraph& scene) {
  std::size_t correct = 0;
  for (std::size_t i = 0; i < r.labels.size(); ++i)
    correct += r.labels[i] == std::uint32_t(scene.labels[i] + 1);
  return r.labels.empty() ? 0.0 : double(correct) / double(r.labels.size());
}

int run_crf_bench(const Arguments& args) {
  testing::SceneSpec spec;
  spec.width = std::max(4, static_cast<int>(std::lround(std::sqrt(double(args.points)))));
  spec.height = spec.width;
  spec.num_classes = args.classes;
  spec.noise = args.noise;
  spec.neighbors = args.neighbors;
  spec.seed = args.seed;
  const LabeledGraph scene = testing::make_grid_scene(spec);
  const std::size_t n = scene.graph.num_nodes();

  CrfModel model;
  double train_s = 0.0;
  if (args.model == "trained") {
    testing::SceneSpec train_spec = spec;
    train_spec.width = 100;
    train_spec.height = 100;
    train_spec.seed = 5;
    const std::vector<LabeledGraph> training = {testing::make_grid_scene(train_spec)};
    std::vector<std::uint32_t> ids(spec.num_classes);
    for (int k = 0; k < spec.num_classes; ++k) ids[k] = static_cast<std::uint32_t>(k + 1);
    TrainingOptions options;
    options.objective = TrainingObjective::kPseudoLikelihood;
    options.max_iterations = 60;
    const auto start = std::chrono::steady_clock::now();
    model = train_crf(training, {}, ids, options).model;
    train_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  } else if (args.model == "potts") {
    // What piecewise training makes (the default models): node weights plus one coupling.
    model = testing::prototype_model(spec, 4.0f, args.coupling);
  } else {
    // Nearest-prototype node weights, and edge weights with a bias plus random feature terms, so
    // psi differs from edge to edge as with a trained model.
    model = testing::prototype_model(spec, 4.0f, 1.0f);
    std::mt19937 rng(3);
    std::normal_distribution<float> weight(0.0f, 0.02f);
    for (int k = 0; k < spec.num_classes; ++k)
      for (int f = 0; f < spec.dim; ++f) model.edge_weights(k, f) = weight(rng);
  }
  std::printf("scene: %zu points, %zu edges (kNN %d), K = %d, d = %d, model %s%s\n", n,
              scene.graph.num_edges(), spec.neighbors, spec.num_classes, spec.dim,
              args.model.c_str(),
              args.model == "trained" ? (" (" + std::to_string(train_s) + " s)").c_str() : "");

  CrfModel node_only = model;
  node_only.edge_weights.setZero();
  const std::vector<Case> cases = {
      {"bp-sum", InferenceMethod::kLoopyBp, false, true},
      {"bp-max", InferenceMethod::kLoopyBp, true, true},
      {"mean-field", InferenceMethod::kMeanField, false, true},
      {"node-only", InferenceMethod::kLoopyBp, false, false},
  };
  std::vector<Row> rows;
  std::printf("%-10s %7s %9s %9s %9s %9s %12s %5s %5s %8s\n", "method", "threads", "marginals",
              "workspace", "ms", "cpu_ms", "points/s", "iters", "conv", "accuracy");
  for (const Case& c : cases) {
    if (std::find(args.methods.begin(), args.methods.end(), c.name) == args.methods.end()) continue;
    for (const int threads : args.threads) {
      for (const bool marginals : {false, true}) {
        for (const bool keep_workspace : {false, true}) {
          InferenceSettings options;
          options.method = c.method;
          options.max_product = c.max_product;
          const InferenceOutputs outputs{.marginals = marginals};
          const RunContext context{threads};
          const CrfModel& m = c.edges ? model : node_only;
          InferenceWorkspace workspace;
          InferenceResult result =
              infer(m, scene.descriptors, scene.graph, options, outputs, context, workspace);
          std::vector<double> ms, cpu_ms;
          for (int r = 0; r < args.repeat; ++r) {
            const double cpu_start = cpu_seconds();
            const auto start = std::chrono::steady_clock::now();
            if (keep_workspace) {
              result =
                  infer(m, scene.descriptors, scene.graph, options, outputs, context, workspace);
            } else {
              result = infer(m, scene.descriptors, scene.graph, options, outputs, context);
            }
            ms.push_back(
                1e3 *
                std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
            cpu_ms.push_back(1e3 * (cpu_seconds() - cpu_start));
          }
          Row row;
          row.name = c.name;
          row.threads = threads;
          row.marginals = marginals;
          row.workspace = keep_workspace;
          row.ms = median(ms);
          row.cpu_ms = median(cpu_ms);
          row.points_per_s = n / (row.ms * 1e-3);
          row.iterations = result.iterations;
          row.converged = result.converged;
          row.accuracy = accuracy(result, scene);
          rows.push_back(row);
          std::printf("%-10s %7d %9s %9s %9.2f %9.2f %12.0f %5d %5s %8.4f\n", row.name.c_str(),
                      threads, marginals ? "yes" : "no", keep_workspace ? "kept" : "fresh", row.ms,
                      row.cpu_ms, row.points_per_s, row.iterations, row.converged ? "yes" : "no",
                      row.accuracy);
        }
      }
    }
  }

  namespace json = primlabel::json;
  json::Json results = json::Json::array();
  for (const Row& row : rows)
    results.push_back({{"method", row.name},
                       {"threads", row.threads},
                       {"marginals", row.marginals},
                       {"workspace", row.workspace},
                       {"ms", json::rounded(row.ms, "%.2f")},
                       {"cpu_ms", json::rounded(row.cpu_ms, "%.2f")},
                       {"points_per_s", json::whole(row.points_per_s)},
                       {"iterations", row.iterations},
                       {"converged", row.converged},
                       {"accuracy", json::rounded(row.accuracy, "%.4f")}});
  json::Json line = {{"bench", "crf"},
                     {"points", n},
                     {"edges", scene.graph.num_edges()},
                     {"classes", spec.num_classes},
                     {"dim", spec.dim},
                     {"model", args.model},
                     {"seed", args.seed}};
  if (args.model == "potts") line["coupling"] = json::rounded(args.coupling, "%.4g");
  line["results"] = std::move(results);
  std::printf("%s\n", json::dump(line).c_str());
  return 0;
}

}  // namespace

namespace primlabel::bench {

BenchCommand add_crf_command(CLI::App& parent) {
  auto args = std::make_shared<Arguments>();
  CLI::App* cmd =
      parent.add_subcommand("crf", "CRF inference throughput (points/s) on a synthetic kNN scene");
  cmd->add_option("--points", args->points, "points in the test scene (a square grid)");
  cmd->add_option("--classes", args->classes, "classes K");
  cmd->add_option("--neighbors", args->neighbors, "k of the kNN graph");
  cmd->add_option("--noise", args->noise, "descriptor noise (prototype values are in [0, 100])");
  cmd->add_option("--threads", args->threads, "thread counts to measure")->delimiter(',');
  cmd->add_option("--repeat", args->repeat, "timed runs per case (the median is reported)");
  cmd->add_option("--model", args->model,
                  "prototype (hand-made, feature-dependent couplings), potts (one coupling, as "
                  "piecewise training makes) or trained (pseudo-likelihood)")
      ->check(CLI::IsMember({"prototype", "potts", "trained"}));
  cmd->add_option("--coupling", args->coupling, "potts: the one coupling between neighbours")
      ->check(CLI::Range(0.0f, 100.0f));
  cmd->add_option("--seed", args->seed, "the scene's noise and jitter");
  cmd->add_option("--methods", args->methods, "bp-sum,bp-max,mean-field,node-only")->delimiter(',');
  return {cmd, [args] { return run_crf_bench(*args); }};
}

}  // namespace primlabel::bench
