// I++ DME line parsing at the rate scan data arrive: 10 000 data lines of six numbers each
// (x, y, z, i, j, k as OnScanReport sends them), parsed and their numbers read. Baselines in the
// same run: copying the same bytes (memcpy), and reading the numbers alone with strtod, which
// any reader must at least do.
#include <benchmark/benchmark.h>

#include <cstdlib>
#include <cstring>
#include <random>
#include <string>
#include <vector>

#include "trueaxis/ippdme/protocol.hpp"

namespace {

using namespace trueaxis;

const std::vector<std::string>& lines() {
  static const std::vector<std::string> l = [] {
    std::vector<std::string> out;
    std::mt19937_64 rng(1);
    std::uniform_real_distribution<double> u(-500, 500), n(-1, 1);
    char buf[160];
    for (int i = 0; i < 10000; ++i) {
      std::snprintf(buf, sizeof buf, "%05d # %.5f, %.5f, %.5f, %.6f, %.6f, %.6f", i % 99999 + 1,
                    u(rng), u(rng), u(rng), n(rng), n(rng), n(rng));
      out.emplace_back(buf);
    }
    return out;
  }();
  return l;
}

std::size_t bytes() {
  std::size_t b = 0;
  for (const auto& s : lines()) b += s.size() + 2;  // with CR LF
  return b;
}

void BM_IppCopyBaseline(benchmark::State& st) {
  std::vector<char> out(bytes());
  for (auto _ : st) {
    std::size_t at = 0;
    for (const auto& s : lines()) {
      std::memcpy(out.data() + at, s.data(), s.size());
      at += s.size() + 2;
    }
    benchmark::DoNotOptimize(out.data());
    benchmark::ClobberMemory();
  }
  st.SetBytesProcessed(static_cast<std::int64_t>(st.iterations() * bytes()));
}
BENCHMARK(BM_IppCopyBaseline);

void BM_IppStrtodBaseline(benchmark::State& st) {
  for (auto _ : st) {
    double sum = 0;
    for (const auto& s : lines()) {
      const char* p = s.c_str() + 8;
      char* end = nullptr;
      for (int k = 0; k < 6; ++k) {
        sum += std::strtod(p, &end);
        p = end + (*end ? 2 : 0);
      }
    }
    benchmark::DoNotOptimize(sum);
  }
  st.SetBytesProcessed(static_cast<std::int64_t>(st.iterations() * bytes()));
}
BENCHMARK(BM_IppStrtodBaseline);

void BM_IppParseDataLines(benchmark::State& st) {
  for (auto _ : st) {
    double sum = 0;
    for (const auto& s : lines()) {
      const auto r = ippdme::parse_response(s);
      for (const auto& v : r.value->items) sum += v.number();
    }
    benchmark::DoNotOptimize(sum);
  }
  st.SetBytesProcessed(static_cast<std::int64_t>(st.iterations() * bytes()));
}
BENCHMARK(BM_IppParseDataLines);

}  // namespace
