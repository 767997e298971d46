// trueaxis CLI — shared declarations between the command files.
#pragma once

#include <string>

namespace trueaxis::cli {

struct DemoOptions {
  std::string output = "demo-report/index.html";
  unsigned long seed = 7;
  long stations = 400;
  bool quiet = false;
};

// Runs every demo scenario and writes the HTML report. Returns the process exit code.
int run_demo(const DemoOptions& options);

}  // namespace trueaxis::cli
