#include "config_file.hpp"

#include <cstdlib>
#include <fstream>

#include "primlabel/ops/server_config.hpp"

namespace primlabel::ops {

namespace {

std::string trim(const std::string& text) {
  const auto first = text.find_first_not_of(" \t\r");
  if (first == std::string::npos) return {};
  const auto last = text.find_last_not_of(" \t\r");
  return text.substr(first, last - first + 1);
}

bool given_on_command_line(const std::vector<std::string>& args, const std::string& flag) {
  for (const std::string& arg : args)
    if (arg == flag || arg.rfind(flag + "=", 0) == 0) return true;
  return false;
}

}  // namespace

std::vector<std::string> with_config_file(CLI::App& app, int argc, const char* const* argv) {
  std::vector<std::string> args(argv + 1, argv + argc);
  std::string path;
  for (std::size_t i = 0; i < args.size(); ++i) {
    if (args[i] == "--config" && i + 1 < args.size()) path = args[i + 1];
    if (args[i].rfind("--config=", 0) == 0) path = args[i].substr(9);
  }
  if (const char* env = std::getenv("PRIMLABEL_CONFIG"); path.empty() && env) path = env;
  std::vector<std::string> out{argv[0]};
  if (!path.empty()) {
    std::ifstream in(path);
    if (!in) throw ConfigError{"cannot read the config file '" + path + "'", kExitUsage};
    std::string line;
    for (int number = 1; std::getline(in, line); ++number) {
      line = trim(line);
      if (line.empty() || line[0] == '#' || line[0] == ';') continue;
      const auto eq = line.find('=');
      const std::string where = path + ":" + std::to_string(number);
      if (eq == std::string::npos)
        throw ConfigError{where + ": expected `key = value`", kExitUsage};
      std::string key = trim(line.substr(0, eq)), value = trim(line.substr(eq + 1));
      if (key.rfind("--", 0) == 0) key = key.substr(2);
      if (value.size() >= 2 && (value.front() == '"' || value.front() == '\'') &&
          value.back() == value.front())
        value = value.substr(1, value.size() - 2);
      const std::string flag = "--" + key;
      const CLI::Option* option = app.get_option_no_throw(flag);
      if (!option || key == "config" || key == "help")
        throw ConfigError{where + ": unknown setting '" + key + "'", kExitUsage};
      const std::string env = option->get_envname();
      if (given_on_command_line(args, flag) || (!env.empty() && std::getenv(env.c_str()))) continue;
      out.push_back(flag + "=" + value);
    }
  }
  out.insert(out.end(), args.begin(), args.end());
  return out;
}

}  // namespace primlabel::ops
