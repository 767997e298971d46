#pragma once
#include <gtest/gtest.h>

#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>

#include "trueaxis/error.hpp"

namespace trueaxis::test {

// A directory of the running test's own (ctest runs tests in parallel processes).
inline std::string temp_dir() {
  const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
  const std::string d =
      std::string(TRUEAXIS_TEST_TMP) + "/" + info->test_suite_name() + "." + info->name();
  std::filesystem::create_directories(d);
  return d;
}

// The VmFlags line of the mapping that holds `p`, from /proc/self/smaps ("" if not found): " hg"
// in it marks memory the program asked to have in transparent huge pages.
inline std::string vm_flags_of_mapping(const void* p) {
  std::ifstream f("/proc/self/smaps");
  const auto addr = reinterpret_cast<std::uintptr_t>(p);
  std::string line;
  bool inside = false;
  while (std::getline(f, line)) {
    unsigned long lo = 0, hi = 0;
    if (std::sscanf(line.c_str(), "%lx-%lx ", &lo, &hi) == 2 && line.find(':') > line.find(' ')) {
      inside = lo <= addr && addr < hi;
      continue;
    }
    if (inside && line.rfind("VmFlags:", 0) == 0) return line;
  }
  return "";
}

// The message of the trueaxis::Error that `f` throws, or "(no error)".
template <class Fn>
std::string error_of(Fn&& f) {
  try {
    f();
  } catch (const trueaxis::Error& e) {
    return e.what();
  }
  return "(no error)";
}

inline std::string temp_file(const std::string& name, const std::string& content) {
  const std::string p = temp_dir() + "/" + name;
  std::ofstream(p) << content;
  return p;
}

// The whole content of the file at `path` ("" when it cannot be read).
inline std::string read_file(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

}  // namespace trueaxis::test
