// NIST's I++ DME test suite files, as the ippdme tests read them.
#pragma once

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

namespace trueaxis::test {

inline const std::filesystem::path kNist =
    std::filesystem::path(TRUEAXIS_TEST_DATA) / "ippdme" / "nist";

inline std::string slurp(const std::filesystem::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

}  // namespace trueaxis::test
