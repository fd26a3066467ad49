#pragma once
// The readers take a path, not bytes: each fuzz input is written to one temp file of this process
// (on tmpfs when /dev/shm exists), rewritten for every input.

#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>

namespace primlabel::fuzz {

inline std::string input_file(const char* extension) {
  namespace fs = std::filesystem;
  const fs::path dir = fs::exists("/dev/shm") ? fs::path("/dev/shm") : fs::temp_directory_path();
  return (dir / ("primlabel-fuzz-" + std::to_string(::getpid()) + extension)).string();
}

// Writes the input to `path`; aborts when it cannot (a broken harness, not a finding).
inline void write_input(const std::string& path, const std::uint8_t* data, std::size_t size) {
  std::FILE* file = std::fopen(path.c_str(), "wb");
  if (!file || (size > 0 && std::fwrite(data, 1, size, file) != size) || std::fclose(file) != 0) {
    std::perror(path.c_str());
    std::abort();
  }
}

}  // namespace primlabel::fuzz
