// Virtual CMMs shared by the ball-gauge tests.
#pragma once

#include <cstdint>
#include <optional>

#include "trueaxis/sim/machine.hpp"

namespace trueaxis::test {

// A machine whose every error is a polynomial of degree ≤ 3 (the parametric model's family): a
// random machine without its sinusoids and tables.
inline sim::Machine cubic_machine(std::uint64_t seed) {
  sim::MachineOptions o;
  o.seed = seed;
  sim::Machine m = sim::random_machine(o);
  for (auto& axis : m.errors)
    for (auto& f : axis) {
      f.sines.clear();
      f.table_u.clear();
      f.table_value.clear();
      if (f.polynomial.size() > 4) f.polynomial.resize(4);
    }
  return m;
}

// What the CMM reads for a point whose true position is X (mm): the nominal tip position of the
// command that puts the tip at X (fixed-point iteration, |∇e| ≪ 1), with the machine's stylus or
// the one given (its offset, mm).
inline Eigen::Vector3d reading_of(const sim::Machine& machine, const Eigen::Vector3d& X,
                                  const std::optional<Eigen::Vector3d>& stylus = std::nullopt) {
  sim::Machine m = machine;
  if (stylus) m.offset = *stylus;
  Eigen::Vector3d cmd = X - m.offset;
  for (int it = 0; it < 8; ++it) cmd = X - m.offset - m.error(cmd);
  return cmd + m.offset;
}

}  // namespace trueaxis::test
