// ISO 10360-2's length measuring error E0 and repeatability range R0, and the virtual CMM's
// touch (acceptance.hpp).
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <memory>
#include <random>

#include "trueaxis/acceptance/acceptance.hpp"
#include "trueaxis/error.hpp"
#include "trueaxis/sim/cmm.hpp"

namespace trueaxis::acceptance {

const char* to_string(Verdict v) {
  switch (v) {
    case Verdict::Conforms:
      return "conforms";
    case Verdict::DoesNotConform:
      return "does not conform";
    case Verdict::NotProven:
      break;
  }
  return "not proven";
}

void VirtualProbeOptions::validate() const {
  if (!(lobing >= 0) || !(lobing <= 0.1) || !(noise >= 0) || !(noise <= 0.1))
    throw Error("virtual probe: the lobing and the noise must be 0 … 0.1 mm");
}

Touch virtual_touch(const sim::Machine& machine, const VirtualProbeOptions& options) {
  options.validate();
  machine.validate();
  struct State {
    sim::Machine m;
    VirtualProbeOptions o;
    std::mt19937_64 rng;
    std::normal_distribution<double> gauss{0.0, 1.0};
  };
  auto s = std::make_shared<State>(State{machine, options, std::mt19937_64(options.seed), {}});
  return [s](const Eigen::Vector3d& at, const Eigen::Vector3d& direction) -> Eigen::Vector3d {
    // Where the tip's centre really is at contact: `at` less a radius along the approach. The
    // command that puts it there solves actual(c) = P (|∇e| ≪ 1: a few fixed-point steps); the
    // CMM reads its nominal tip position c + offset. The tip radius is the qualified one, so the
    // reading plus the radius along the direction is the measured surface point.
    const double r = 1;  // any: it cancels, as the qualification makes it
    const Eigen::Vector3d P = at - r * direction;
    Eigen::Vector3d c = P - s->m.offset;
    for (int it = 0; it < 6; ++it) c = P - s->m.offset - s->m.error(c);
    if (!s->m.contains(c, 1e-6))
      throw Error(fmt::format("the point ({:.1f}, {:.1f}, {:.1f}) is beyond the machine's travel",
                              at.x(), at.y(), at.z()));
    const double pretravel = sim::pretravel_lobing(s->o.lobing, direction);
    const double noise = s->o.noise > 0 ? s->o.noise * s->gauss(s->rng) : 0.0;
    return c + s->m.offset + (r + pretravel + noise) * direction;
  };
}

std::string el_name(const std::optional<Eigen::Vector3d>& stylus_offset) {
  return stylus_offset ? fmt::format("E{:.0f}", stylus_offset->norm()) : std::string("E0");
}

std::string E0Result::name() const {
  return el_name(stylus_offset);
}

void validate_stylus_offset(const Eigen::Vector3d& lateral) {
  if (!lateral.allFinite() || !(lateral.norm() > 0) || !(lateral.norm() <= 500))
    throw Error("stylus offset: give its length, > 0 and up to 500 mm (e.g. 150 for E150)");
  if (std::abs(lateral.z()) > 1e-9 * lateral.norm())
    throw Error(fmt::format(
        "stylus offset ({:g}, {:g}, {:g}) mm: ISO 10360-2's E_L offsets the tip across the ram, "
        "so its Z component must be 0",
        lateral.x(), lateral.y(), lateral.z()));
}

sim::Machine with_stylus(sim::Machine machine, const Eigen::Vector3d& lateral) {
  validate_stylus_offset(lateral);
  machine.offset += lateral;
  return machine;
}

E0Result run_e0(const Setup& setup, const Volume& volume, const Touch& touch,
                const E0Options& options) {
  E0Result result;
  std::vector<std::string> only = options.positions;
  if (options.stylus_offset) {
    validate_stylus_offset(*options.stylus_offset);
    // ISO 10360-2 measures E_L in two positions; by default the set-up's first two space
    // diagonals, the lines along which every carriage moves and rotates.
    if (only.empty())
      for (const auto& line : lines(setup))
        if (line.space_diagonal && only.size() < 2) only.push_back(line.name);
    if (only.empty())
      throw Error(
          "E_L: the set-up has no space diagonal to measure with the stylus offset; name the "
          "positions");
  } else if (!only.empty()) {
    throw Error(
        "E0 is measured in every position of the set-up; choosing positions is for E_L, with a "
        "stylus offset");
  }
  result.positions = positions(setup, volume, only);
  std::size_t total = 0;
  for (const auto& pos : result.positions)
    total += pos.placements.size() * static_cast<std::size_t>(setup.repetitions);
  std::size_t done = 0;
  try {
    for (std::size_t k = 0; k < result.positions.size(); ++k) {
      const auto& pos = result.positions[k];
      if (options.before_position) options.before_position(pos, k, result.positions.size());
      for (const auto i : pos.placements) {
        const auto& p = setup.placements[i];
        const auto& block = setup.block(p.block);
        const Eigen::Vector3d fa = p.centre - block.length / 2 * p.direction,
                              fb = p.centre + block.length / 2 * p.direction;
        for (int rep = 1; rep <= setup.repetitions; ++rep) {
          LengthResult row;
          row.position = pos.name;
          row.block = p.block;
          row.repetition = rep;
          row.nominal = block.length;
          row.a = touch(fa, p.direction);   // face A from outside: along +direction
          row.b = touch(fb, -p.direction);  // face B: along −direction
          row.measured = (row.b - row.a).dot(p.direction);
          result.lengths.push_back(row);
          if (options.progress) options.progress(++done, total);
        }
      }
    }
  } catch (const Error& e) {
    result.complete = false;
    result.stopped = e.what();
  }
  judge_e0(setup, options, result);
  return result;
}

void judge_e0(const Setup& setup, const E0Options& options, E0Result& result) {
  result.mpe_text = options.mpe.text;
  result.r0_text = options.r0 ? options.r0->text : "";
  result.stylus_offset = options.stylus_offset;
  result.e0_max = 0;
  bool all_within = true, some_beyond = false;
  for (auto& row : result.lengths) {
    const auto& block = setup.block(row.block);
    const double L = block.length;
    row.error = row.measured - row.nominal;
    row.mpe = options.mpe.at(L) * 1e-3;
    const double u =
        std::sqrt(block.u * block.u + std::pow(L * block.alpha * setup.u_temperature, 2) +
                  std::pow(L * block.u_alpha * (setup.temperature - 20), 2) +
                  setup.u_alignment * setup.u_alignment + setup.u_fixturing * setup.u_fixturing);
    row.U = 2 * u;
    result.e0_max = std::max(result.e0_max, std::abs(row.error));
    if (std::abs(row.error) > row.mpe - row.U) all_within = false;
    if (std::abs(row.error) > row.mpe + row.U) some_beyond = true;
  }
  // R0: the range of each length's repetitions at its position (a range needs two).
  struct Span {
    double lo = INFINITY, hi = -INFINITY;
    int n = 0;
  };
  std::map<std::pair<std::string, std::string>, Span> span;
  std::vector<std::pair<std::string, std::string>> order;
  for (const auto& row : result.lengths) {
    auto& sp = span[{row.position, row.block}];
    if (sp.n++ == 0) order.emplace_back(row.position, row.block);
    sp.lo = std::min(sp.lo, row.measured);
    sp.hi = std::max(sp.hi, row.measured);
  }
  result.r0.clear();
  result.r0_max = 0;
  for (const auto& key : order) {
    const auto& sp = span[key];
    if (sp.n < 2) continue;
    result.r0.push_back({key.first, key.second, setup.block(key.second).length, sp.hi - sp.lo});
    result.r0_max = std::max(result.r0_max, sp.hi - sp.lo);
  }
  if (options.r0) {
    bool ok = true;
    for (const auto& r : result.r0) ok = ok && r.range <= options.r0->at(r.nominal) * 1e-3;
    result.r0_pass = ok;
  }
  result.verdict = some_beyond ? Verdict::DoesNotConform
                   : all_within && result.complete && !result.lengths.empty() ? Verdict::Conforms
                                                                              : Verdict::NotProven;
  result.rule = fmt::format(
      "ISO 14253-1: conformance with {},MPE = {} µm is proven when every |E| ≤ MPE − U, "
      "non-conformance when some |E| > MPE + U; U (k = 2) from the lengths' calibration, "
      "temperature ({:g} ± {:g} °C), expansion coefficient, alignment and fixturing (ISO/TS "
      "23165)",
      el_name(options.stylus_offset), options.mpe.text, setup.temperature, setup.u_temperature);
}

std::string E0Result::summary() const {
  const std::string e = name();
  std::string s =
      lengths.empty()
          ? fmt::format("{}: no length measured ({} positions set up): {}", e, positions.size(),
                        to_string(verdict))
          : fmt::format("{}: {} lengths in {} positions; largest |E| {:.2f} µm (MPE {}), {}: {}", e,
                        lengths.size(), positions.size(), e0_max * 1e3, mpe_text,
                        r0.empty() ? std::string("R0 not determined (no repetitions)")
                                   : fmt::format("R0 largest {:.2f} µm", r0_max * 1e3),
                        to_string(verdict));
  if (r0_pass) s += fmt::format("; R0 {} (MPE {})", *r0_pass ? "within" : "beyond", r0_text);
  if (stylus_offset)
    s += fmt::format("; stylus offset ({:g}, {:g}, {:g}) mm", stylus_offset->x(),
                     stylus_offset->y(), stylus_offset->z());
  if (!complete) s += "; stopped: " + stopped;
  return s;
}

}  // namespace trueaxis::acceptance
