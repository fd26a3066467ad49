// primlabel-research calibrate-kinect: the simulated Kinect's parameters measured on the table
// planes of the mOSD scenes (*.pcd, label 1-9 table) in a folder: depth noise, disparity
// quantisation, density and missing returns (research/kinect_calibration.hpp); with
// --fit-simulation also the simulator's correlated depth error.
//
//   primlabel-research calibrate-kinect ../shared/data/mosd --fit-simulation

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <memory>
#include <stdexcept>
#include <string>
#include <system_error>
#include <vector>

#include "primlabel/cli/exit_codes.hpp"
#include "primlabel/geometry/atomic_file.hpp"
#include "primlabel/geometry/json_text.hpp"
#include "primlabel/research/kinect_calibration.hpp"
#include "research_commands.hpp"

namespace {

using namespace primlabel;

struct Arguments {
  std::string dir, calibration_json;
  bool fit_simulation = false, json = false, quiet = false;
};

// The .pcd files of DIR, sorted (the calibration's order does not depend on the file system).
std::vector<std::string> scene_files(const std::string& dir) {
  std::vector<std::string> files;
  std::error_code ec;
  for (const auto& entry : std::filesystem::directory_iterator(dir, ec))
    if (entry.path().extension() == ".pcd") files.push_back(entry.path().string());
  if (ec) throw std::runtime_error(dir + ": cannot be read (" + ec.message() + ")");
  if (files.empty()) throw std::runtime_error(dir + ": no .pcd file");
  std::sort(files.begin(), files.end());
  return files;
}

int run_calibrate_kinect(const Arguments& args) {
  const std::vector<std::string> files = scene_files(args.dir);
  std::function<void(const std::string&)> progress;
  if (!args.quiet)
    progress = [](const std::string& line) { std::fprintf(stderr, "%s\n", line.c_str()); };
  const research::KinectCalibration calibration =
      research::calibrate_mosd(files, research::KinectCalibrationOptions{}, progress);
  std::string json = research::kinect_calibration_json(calibration);
  std::string text = research::kinect_calibration_text(calibration);
  if (args.fit_simulation) {
    const research::KinectSimulationFit fit =
        research::fit_kinect_simulation(calibration, progress);
    text += research::kinect_simulation_fit_text(fit);
    json::Json root = json::Json::parse(json);
    root["simulation_fit"] = {
        {"depth_noise", json::rounded(fit.depth_noise, "%.6g")},
        {"noise_correlation_px", fit.noise_correlation_px},
        {"independent_noise_share", fit.independent_noise_share},
        {"autocorrelation_rms", json::rounded(fit.autocorrelation_rms, "%.6g")},
        {"simulated_depth_noise", json::rounded(fit.simulated.depth_noise, "%.6g")},
        {"simulated_autocorrelation", fit.simulated.autocorrelation}};
    json = json::dump(root) + "\n";
  }
  if (!args.calibration_json.empty()) atomic_write_file(args.calibration_json, json);
  std::fputs((args.json ? json : text).c_str(), stdout);
  return kExitOk;
}

}  // namespace

namespace primlabel::research_tool {

ResearchCommand add_calibrate_kinect_command(CLI::App& parent) {
  auto args = std::make_shared<Arguments>();
  CLI::App* cmd = parent.add_subcommand(
      "calibrate-kinect",
      "Measure depth noise, disparity quantisation, density and missing returns on the table "
      "planes of the mOSD scenes (*.pcd, label 1-9 table) in DIR; fit the simulated Kinect.");
  cmd->add_option("DIR", args->dir, "folder of mOSD scenes")->required();
  cmd->add_flag("--fit-simulation", args->fit_simulation,
                "also fit the simulator's correlated depth error by simulating bare-table frames "
                "(about 20 s of CPU)");
  cmd->add_option("--calibration-json", args->calibration_json,
                  "also write the calibration as JSON to FILE");
  cmd->add_flag("--json", args->json, "the calibration as JSON on stdout");
  cmd->add_flag("-q,--quiet", args->quiet, "no progress on stderr");
  return {cmd, [args] { return run_calibrate_kinect(*args); }};
}

}  // namespace primlabel::research_tool
