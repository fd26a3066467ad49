// primlabel-research fig4: the paper's Fig. 4 from synthetic LMS400 training scenes: class-mean
// FPFH signatures and their HIK distance matrix, as CSV and PNG in DIR (research/fig4.hpp).
// Prints the matrix, or one JSON line with --json.
//
//   primlabel-research fig4 fig4/ --scenes 3

#include <CLI/CLI.hpp>
#include <cstdio>
#include <memory>
#include <string>

#include "primlabel/cli/exit_codes.hpp"
#include "primlabel/geometry/json_text.hpp"
#include "primlabel/geometry/taxonomy.hpp"
#include "primlabel/research/fig4.hpp"
#include "research_commands.hpp"

namespace {

using namespace primlabel;

struct Arguments {
  std::string dir;
  int scenes = 3, threads = 0;
  bool json = false, quiet = false;
};

std::string class_name(std::uint32_t id) {
  const auto c = class_from_id(id);
  return c ? std::string(name(*c)) : std::to_string(id);
}

int run_fig4(const Arguments& args) {
  research::Fig4Options options;
  options.scenes = args.scenes;
  options.threads = args.threads;
  if (!args.quiet)
    options.progress = [](const std::string& line) { std::fprintf(stderr, "%s\n", line.c_str()); };
  const research::Fig4 result = research::run_fig4(options);
  research::write_fig4(result, args.dir);
  if (!args.json) {
    std::printf("%s", research::hik_text(result).c_str());
    return kExitOk;
  }
  const research::ClassSignatures& s = result.signatures;
  json::Json classes = json::Json::array(), points = json::Json::array();
  for (std::uint32_t id : s.class_ids) classes.push_back(class_name(id));
  for (const auto count : s.points) points.push_back(count);
  json::Json hik = json::Json::array();
  for (Eigen::Index r = 0; r < result.hik.rows(); ++r) {
    json::Json row = json::Json::array();
    // 6 decimals, as primlabel-eval's scores; null when undefined (NaN).
    for (Eigen::Index c = 0; c < result.hik.cols(); ++c)
      row.push_back(json::rounded(result.hik(r, c), "%.6f"));
    hik.push_back(std::move(row));
  }
  const json::Json line = {
      {"classes", std::move(classes)}, {"points", std::move(points)}, {"hik", std::move(hik)}};
  std::printf("%s\n", json::dump(line).c_str());
  return kExitOk;
}

}  // namespace

namespace primlabel::research_tool {

ResearchCommand add_fig4_command(CLI::App& parent) {
  auto args = std::make_shared<Arguments>();
  CLI::App* cmd = parent.add_subcommand(
      "fig4",
      "Write the paper's Fig. 4 (class-mean FPFH signatures, HIK distance matrix; CSV and PNG) "
      "from synthetic LMS400 training scenes.");
  cmd->add_option("DIR", args->dir, "output folder")->required();
  cmd->add_option("--scenes", args->scenes, "training scenes")->check(CLI::PositiveNumber);
  cmd->add_flag("--json", args->json, "the classes, their points and the matrix as one JSON line");
  cmd->add_option("--threads", args->threads, "worker threads")
      ->check(CLI::PositiveNumber)
      ->default_str("all cores");
  cmd->add_flag("-q,--quiet", args->quiet, "no progress on stderr");
  return {cmd, [args] { return run_fig4(*args); }};
}

}  // namespace primlabel::research_tool
