#include "primlabel/cli/cli_common.hpp"

#include <unistd.h>

#include <cstdio>
#include <sstream>
#include <stdexcept>

namespace primlabel::cli {

Vec3f parse_vec3(const std::string& text) {
  std::stringstream in(text);
  Vec3f v;
  for (int i = 0; i < 3; ++i) {
    std::string part;
    if (!std::getline(in, part, ','))
      throw std::invalid_argument("expected X,Y,Z but got '" + text + "'");
    try {
      std::size_t used = 0;
      v[i] = std::stof(part, &used);
      if (used != part.size()) throw std::invalid_argument(part);
    } catch (const std::exception&) {
      throw std::invalid_argument("'" + part + "' in '" + text + "' is not a number");
    }
  }
  std::string rest;
  if (std::getline(in, rest)) throw std::invalid_argument("expected X,Y,Z but got '" + text + "'");
  if (!is_finite(v)) throw std::invalid_argument("'" + text + "' is not a finite position");
  return v;
}

ProgressPrinter::ProgressPrinter(bool quiet) : quiet_(quiet), tty_(isatty(STDERR_FILENO) == 1) {}

ProgressFn ProgressPrinter::stage(const std::string& name) {
  done();
  name_ = name;
  stage_start_ = last_print_ = std::chrono::steady_clock::now();
  last_decile_ = -1;
  printed_ = false;
  if (quiet_) return {};
  return [this](std::size_t done, std::size_t total) { report(done, total); };
}

void ProgressPrinter::report(std::size_t done, std::size_t total) {
  using namespace std::chrono;
  const auto now = steady_clock::now();
  if (now - stage_start_ < seconds(1) || total == 0) return;  // short stages stay quiet
  const int percent = static_cast<int>(100.0 * double(done) / double(total));
  if (tty_) {
    if (now - last_print_ < milliseconds(250) && done != total) return;
    std::fprintf(stderr, "\r%s: %3d%% (%zu/%zu)", name_.c_str(), percent, done, total);
  } else {
    if (percent / 10 == last_decile_) return;
    last_decile_ = percent / 10;
    std::fprintf(stderr, "%s: %d%% (%zu/%zu)\n", name_.c_str(), percent, done, total);
  }
  last_print_ = now;
  printed_ = true;
}

void ProgressPrinter::done() {
  if (printed_ && tty_) std::fputc('\n', stderr);
  printed_ = false;
}

}  // namespace primlabel::cli
