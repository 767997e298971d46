#pragma once
#include <filesystem>
#include <fstream>
#include <string>

namespace trueaxis::test {

inline std::string temp_file(const std::string& name, const std::string& content) {
  std::filesystem::create_directories(TRUEAXIS_TEST_TMP);
  const std::string p = std::string(TRUEAXIS_TEST_TMP) + "/" + name;
  std::ofstream(p) << content;
  return p;
}

}  // namespace trueaxis::test
