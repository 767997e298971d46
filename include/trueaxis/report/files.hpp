// trueaxis::report — the report of any result file trueaxis writes, chosen by its "kind" (what
// `trueaxis report FILE` and Python's trueaxis.report draw).
#pragma once

#include <string>

#include "trueaxis/report/html.hpp"

namespace trueaxis::report {

struct FileReport {
  std::string kind;   // the file's kind
  std::string title;  // the page's title ("trueaxis positioning report")
  Section section;    // titled by what it shows; its source is the file's name
};

// Throws Error: a file that is not a result, or a kind drawn only with another (a parametric
// model, drawn with its ball-gauge map).
FileReport file_report(const std::string& path);

}  // namespace trueaxis::report
