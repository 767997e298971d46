// Shared by the libFuzzer targets: every reader takes a path, so each input is written to a
// file of this process's own first. trueaxis::Error is the expected answer to a bad input; any
// other exception escapes and is a finding (libFuzzer reports the uncaught exception).
#pragma once

#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <string>

#include "trueaxis/error.hpp"

namespace trueaxis::fuzz {

inline std::string scratch_dir() {
  static const std::string dir = [] {
    const char* t = std::getenv("TMPDIR");
    std::string d = std::string(t ? t : "/tmp") + "/trueaxis-fuzz-" + std::to_string(getpid());
    std::filesystem::create_directories(d);
    return d;
  }();
  return dir;
}

// Writes the bytes to `name` in the scratch directory and returns its path.
inline std::string write_input(const std::string& name, const std::uint8_t* data, std::size_t n) {
  const std::string p = scratch_dir() + "/" + name;
  std::FILE* f = std::fopen(p.c_str(), "wb");
  if (f == nullptr) std::abort();
  if (n > 0 && std::fwrite(data, 1, n, f) != n) std::abort();
  std::fclose(f);
  return p;
}

template <class Fn>
void expect_only_trueaxis_errors(Fn&& fn) {
  try {
    fn();
  } catch (const trueaxis::Error&) {
  }
}

}  // namespace trueaxis::fuzz
