// trueaxis CLI — progress of long runs on stderr, with an estimate of the time left.
#pragma once

#include <fmt/format.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>

namespace trueaxis::cli {

// "about 2 min 10 s left" from the time spent and the fraction done (0 < fraction <= 1).
inline std::string time_left(double elapsed_s, double fraction) {
  if (!(fraction > 0)) return "time left unknown";
  const double left = elapsed_s * (1 - fraction) / fraction;
  if (left < 1) return "less than a second left";
  if (left < 60) return fmt::format("about {:.0f} s left", left);
  if (left < 3600)
    return fmt::format("about {:.0f} min {:.0f} s left", std::floor(left / 60),
                       std::fmod(left, 60));
  return fmt::format("about {:.0f} h {:.0f} min left", std::floor(left / 3600),
                     std::fmod(left, 3600) / 60);
}

// Reports progress on stderr once a run has taken more than a few seconds: on a terminal one
// line rewritten in place every second, otherwise (a log file) a line every ten seconds.
// TRUEAXIS_PROGRESS=always reports every update (for tests and slow pipes).
class Progress {
 public:
  Progress(std::string what, bool quiet)
      : what_(std::move(what)), quiet_(quiet), tty_(isatty(fileno(stderr)) != 0) {
    const char* e = std::getenv("TRUEAXIS_PROGRESS");
    always_ = e != nullptr && std::string(e) == "always";
  }
  void update(double fraction) {
    if (quiet_) return;
    const double t = seconds();
    if (!always_ && (t < kQuietFor || t - last_ < (tty_ ? 1.0 : 10.0))) return;
    last_ = t;
    printed_ = true;
    fmt::print(stderr, "{}{}: {:.0f} % done, {}{}", tty_ && !always_ ? "\r" : "", what_,
               100 * fraction, time_left(t, fraction), tty_ && !always_ ? "   " : "\n");
    std::fflush(stderr);
  }
  // Leaves `seconds` out of the time spent (an operator's wait), so the time left counts only
  // the work.
  void exclude(double seconds) {
    start_ += std::chrono::duration_cast<std::chrono::steady_clock::duration>(
        std::chrono::duration<double>(seconds));
  }
  void done() {
    if (printed_ && tty_ && !always_) fmt::print(stderr, "\n");
  }

 private:
  static constexpr double kQuietFor = 3;  // seconds before the first report
  double seconds() const {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  }
  std::string what_;
  bool quiet_, tty_, always_ = false, printed_ = false;
  double last_ = 0;
  std::chrono::steady_clock::time_point start_ = std::chrono::steady_clock::now();
};

}  // namespace trueaxis::cli
