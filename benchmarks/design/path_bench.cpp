// Scanning-path conversion of a 50-edge section: the offset and cubic segments (make_path),
// against two baselines in the same run: OCCT's planar offset alone (work make_path cannot avoid)
// and the same offset turned into a polyline within the same chordal tolerance by OCCT's
// tangential-deflection sampler (the usual alternative to cubic segments).
#include <benchmark/benchmark.h>

#include <BRepAdaptor_Curve.hxx>
#include <BRepBuilderAPI_MakePolygon.hxx>
#include <BRepOffsetAPI_MakeOffset.hxx>
#include <GCPnts_TangentialDeflection.hxx>
#include <TopExp_Explorer.hxx>
#include <TopoDS.hxx>
#include <cmath>

#include "trueaxis/design/design.hpp"

namespace {

using namespace trueaxis;

// A 50-edge star (radii 50 and 40 mm), material inside.
design::Section star() {
  design::Section s;
  s.name = "star";
  s.polyline.resize(3, 51);
  for (int i = 0; i <= 50; ++i) {
    const double a = 2 * M_PI * (i % 50) / 50, r = (i % 2) ? 40 : 50;
    s.polyline.col(i) << r * std::cos(a), r * std::sin(a), 0;
  }
  return s;
}

TopoDS_Shape occt_offset(const design::Section& s, double d) {
  BRepBuilderAPI_MakePolygon poly;
  for (Eigen::Index i = 0; i + 1 < s.polyline.cols(); ++i)
    poly.Add(gp_Pnt(s.polyline(0, i), s.polyline(1, i), s.polyline(2, i)));
  poly.Close();
  BRepOffsetAPI_MakeOffset mo(poly.Wire(), GeomAbs_Arc);
  mo.Perform(d);
  return mo.Shape();
}

void BM_PathStar50(benchmark::State& st) {
  const auto s = star();
  design::PathOptions o;
  std::size_t segs = 0;
  for (auto _ : st) {
    const auto p = design::make_path(s, o);
    segs = p.segments.size();
    benchmark::DoNotOptimize(p.segments.data());
  }
  st.counters["segments"] = static_cast<double>(segs);
}
BENCHMARK(BM_PathStar50)->Unit(benchmark::kMillisecond);

void BM_OcctOffsetOnlyStar50(benchmark::State& st) {
  const auto s = star();
  for (auto _ : st) benchmark::DoNotOptimize(occt_offset(s, 0.7).IsNull());
}
BENCHMARK(BM_OcctOffsetOnlyStar50)->Unit(benchmark::kMillisecond);

void BM_OcctPolylineStar50(benchmark::State& st) {
  const auto s = star();
  const design::PathOptions o;
  std::size_t points = 0;
  for (auto _ : st) {
    points = 0;
    const TopoDS_Shape sh = occt_offset(s, o.tip_radius - o.pushing);
    for (TopExp_Explorer e(sh, TopAbs_EDGE); e.More(); e.Next()) {
      BRepAdaptor_Curve c(TopoDS::Edge(e.Current()));
      GCPnts_TangentialDeflection td(c, M_PI, o.chordal_tolerance);
      points += static_cast<std::size_t>(td.NbPoints());
    }
    benchmark::DoNotOptimize(points);
  }
  st.counters["points"] = static_cast<double>(points);
}
BENCHMARK(BM_OcctPolylineStar50)->Unit(benchmark::kMillisecond);

}  // namespace
