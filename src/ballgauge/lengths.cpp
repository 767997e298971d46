#include "trueaxis/ballgauge/lengths.hpp"

#include <fmt/format.h>

#include <Eigen/Geometry>
#include <array>
#include <charconv>
#include <cmath>
#include <limits>
#include <memory>
#include <unordered_map>

#include "trueaxis/error.hpp"

namespace trueaxis::ballgauge {
namespace {

LengthStats stats(const std::vector<LengthRow>& rows, double LengthRow::*field) {
  LengthStats s;
  s.min = std::numeric_limits<double>::infinity();
  s.max = -s.min;
  double sum = 0, sq = 0;
  for (const auto& r : rows) {
    const double v = r.*field;
    s.min = std::min(s.min, v);
    s.max = std::max(s.max, v);
    sum += v;
    sq += v * v;
  }
  const double n = static_cast<double>(rows.size());
  s.mean = sum / n;
  s.rms = std::sqrt(sq / n);
  return s;
}

}  // namespace

Correction grid_correction(const map::ErrorMap& map, const map::EvalOptions& options) {
  map.validate();
  Correction c;
  c.name = "grid";
  c.apply = [map, options](Eigen::Ref<Eigen::Matrix3Xd> p) { map::correct(map, p, options); };
  if (map.uncertainty.cols() == map.nodes()) {
    // The node uncertainties interpolated as variances (linear: they stay non-negative).
    auto var = std::make_shared<map::ErrorMap>();
    var->axes = map.axes;
    var->error = map.uncertainty.array().square();
    map::EvalOptions lin;
    lin.outside = map::Outside::Clamp;
    const map::Interpolator u2(*var, lin);  // points into *var, which the lambda keeps alive
    c.length_uncertainty = [var, u2](const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
      const Eigen::Vector3d d = (b - a).normalized();
      return std::sqrt(std::max(0.0, d.cwiseAbs2().dot(u2(a) + u2(b))));
    };
  }
  return c;
}

void LengthOptions::validate() const {
  if (!(repeat_tolerance >= 0) || !std::isfinite(repeat_tolerance))
    throw Error("length verification: the repeat tolerance must be a finite number >= 0 mm");
  if (!(line_tolerance >= 0) || !std::isfinite(line_tolerance))
    throw Error("length verification: the line tolerance must be a finite number >= 0 mm");
}

namespace {

// A repeat group's hash key: its nominal length and the cell of its first end point.
struct CellKey {
  double nominal;
  std::array<long long, 3> cell;
  bool operator==(const CellKey& o) const { return nominal == o.nominal && cell == o.cell; }
};
struct CellKeyHash {
  std::size_t operator()(const CellKey& k) const {
    std::size_t h = std::hash<double>{}(k.nominal);
    for (long long c : k.cell) h = h * 1000003u ^ std::hash<long long>{}(c);
    return h;
  }
};

}  // namespace

LengthVerification verify_lengths(const std::vector<LengthMeasurement>& lengths,
                                  const Correction& corr, const LengthOptions& o) {
  o.validate();
  if (lengths.empty()) throw Error("length verification: no measurements");
  if (!corr.apply) throw Error("length verification: the correction has no function");
  LengthVerification v;
  v.correction = corr.name;
  std::vector<const LengthMeasurement*> first;             // first row of each repeat group
  const double cell = std::max(o.repeat_tolerance, 1e-6);  // mm
  const auto cell_of = [cell](const Eigen::Vector3d& p) {
    return std::array<long long, 3>{static_cast<long long>(std::floor(p.x() / cell)),
                                    static_cast<long long>(std::floor(p.y() / cell)),
                                    static_cast<long long>(std::floor(p.z() / cell))};
  };
  std::unordered_map<CellKey, std::vector<int>, CellKeyHash> groups;
  Eigen::Matrix3Xd ends(3, 2);
  // "<where>grid correction: length 3: " — the caller's location of the length (or end), then
  // the 1-based count.
  const auto refuse = [&](std::size_t i, int end, const std::string& why) {
    return Error(fmt::format("{}{} correction: length {}: {}",
                             o.locate ? o.locate(i, end) : std::string(), corr.name, i + 1, why));
  };
  for (std::size_t i = 0; i < lengths.size(); ++i) {
    const LengthMeasurement& m = lengths[i];
    if (!(m.nominal > 0) || !std::isfinite(m.nominal))
      throw refuse(i, 0, "the nominal length must be a positive number of mm");
    if (!m.a.allFinite() || !m.b.allFinite()) throw refuse(i, 0, "non-finite end point");
    if (!((m.b - m.a).norm() > 0)) throw refuse(i, 0, "the two end points coincide");
    LengthRow r;
    r.nominal = m.nominal;
    r.before = (m.b - m.a).norm() - m.nominal;
    ends.col(0) = m.a;
    ends.col(1) = m.b;
    try {
      corr.apply(ends);
    } catch (const Error& e) {
      // Error path only: which end the correction refuses, for the caller's location.
      int end = 0;
      for (int k = 0; k < 2 && end == 0; ++k) {
        Eigen::Matrix3Xd one = k == 0 ? m.a : m.b;
        try {
          corr.apply(one);
        } catch (const Error&) {
          end = k + 1;
        }
      }
      throw refuse(i, end, e.what());
    }
    r.after = (ends.col(1) - ends.col(0)).norm() - m.nominal;
    r.uncertainty = corr.length_uncertainty && !corr.length_uncertainties
                        ? corr.length_uncertainty(m.a, m.b)
                        : 0.0;
    // Repeat groups are looked up in a hash of cells at least the tolerance wide, over the 27
    // cells around the first end: linear time (a scan of every group was quadratic).
    r.position = -1;
    const std::array<long long, 3> here = cell_of(m.a);
    for (int dx = -1; dx <= 1; ++dx)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dz = -1; dz <= 1; ++dz) {
          const auto it =
              groups.find(CellKey{m.nominal, {here[0] + dx, here[1] + dy, here[2] + dz}});
          if (it == groups.end()) continue;
          for (int g : it->second)
            if ((r.position < 0 || g < r.position) &&
                (first[static_cast<std::size_t>(g)]->a - m.a).norm() <= o.repeat_tolerance &&
                (first[static_cast<std::size_t>(g)]->b - m.b).norm() <= o.repeat_tolerance)
              r.position = g;
        }
    if (r.position < 0) {
      r.position = static_cast<int>(first.size());
      first.push_back(&m);
      groups[CellKey{m.nominal, here}].push_back(r.position);
    }
    v.rows.push_back(r);
  }
  v.positions = static_cast<int>(first.size());
  // The set-ups' lines (ISO 10360-2's positions): a set-up joins the first line whose direction
  // agrees within 2° and whose axis passes within the tolerance of its middle. Few set-ups and
  // fewer lines: a scan of the lines is enough.
  {
    const double parallel = std::sin(2 * M_PI / 180);
    std::vector<Eigen::Vector3d> through;  // a point of each line (its first set-up's middle)
    std::vector<int> line_of(first.size());
    for (std::size_t g = 0; g < first.size(); ++g) {
      Eigen::Vector3d d = (first[g]->b - first[g]->a).normalized();
      Eigen::Index big = 0;
      d.cwiseAbs().maxCoeff(&big);
      if (d[big] < 0) d = -d;
      const Eigen::Vector3d mid = (first[g]->a + first[g]->b) / 2;
      int found = -1;
      for (std::size_t l = 0; l < through.size() && found < 0; ++l) {
        const Eigen::Vector3d& e = v.line_directions[l];
        const Eigen::Vector3d off = mid - through[l];
        if (d.cross(e).norm() <= parallel && (off - off.dot(e) * e).norm() <= o.line_tolerance)
          found = static_cast<int>(l);
      }
      if (found < 0) {
        found = static_cast<int>(through.size());
        through.push_back(mid);
        v.line_directions.push_back(d);
      }
      line_of[g] = found;
    }
    for (auto& r : v.rows) r.line = line_of[static_cast<std::size_t>(r.position)];
  }
  if (corr.length_uncertainties) {
    Eigen::Matrix3Xd a(3, static_cast<Eigen::Index>(lengths.size())), b = a;
    for (std::size_t i = 0; i < lengths.size(); ++i) {
      a.col(static_cast<Eigen::Index>(i)) = lengths[i].a;
      b.col(static_cast<Eigen::Index>(i)) = lengths[i].b;
    }
    const Eigen::VectorXd u = corr.length_uncertainties(a, b);
    for (std::size_t i = 0; i < lengths.size(); ++i)
      v.rows[i].uncertainty = u[static_cast<Eigen::Index>(i)];
  }
  v.before = stats(v.rows, &LengthRow::before);
  v.after = stats(v.rows, &LengthRow::after);
  // Pooled repeatability of the measured lengths (before correction: the correction is a smooth
  // function and does not change the spread of repeats beyond second order).
  std::vector<double> sum(first.size(), 0.0);
  std::vector<int> count(first.size(), 0);
  for (const auto& r : v.rows) {
    sum[static_cast<std::size_t>(r.position)] += r.before;
    ++count[static_cast<std::size_t>(r.position)];
  }
  double ss = 0, u2 = 0;
  long dof = 0;
  for (const auto& r : v.rows) {
    const auto g = static_cast<std::size_t>(r.position);
    ss += std::pow(r.before - sum[g] / count[g], 2);
    u2 += r.uncertainty * r.uncertainty;
  }
  for (int c : count) dof += c - 1;
  v.repeatability = dof > 0 ? std::sqrt(ss / static_cast<double>(dof)) : NAN;
  v.correction_u_rms = std::sqrt(u2 / static_cast<double>(v.rows.size()));
  v.predicted_after = std::hypot(v.repeatability, v.correction_u_rms);
  return v;
}

std::string LengthVerification::summary() const {
  std::string s = fmt::format(
      "length verification, {} correction: {} lengths in {} set-ups (a gauge at one place)\n"
      "  before: {:+.2f} ... {:+.2f} µm (range {:.2f}), mean {:+.2f}, RMS {:.2f} µm\n"
      "  after:  {:+.2f} ... {:+.2f} µm (range {:.2f}), mean {:+.2f}, RMS {:.2f} µm\n",
      correction, rows.size(), positions, before.min * 1e3, before.max * 1e3, before.range() * 1e3,
      before.mean * 1e3, before.rms * 1e3, after.min * 1e3, after.max * 1e3, after.range() * 1e3,
      after.mean * 1e3, after.rms * 1e3);
  if (std::isnan(repeatability))
    s += fmt::format(
        "  no repeated positions: the repeatability is unknown; the correction's u is {:.2f} µm "
        "RMS\n",
        correction_u_rms * 1e3);
  else
    s += fmt::format(
        "  expected after: {:.2f} µm RMS (repeatability {:.2f} µm, correction u {:.2f} µm)\n",
        predicted_after * 1e3, repeatability * 1e3, correction_u_rms * 1e3);
  return s;
}

std::string direction_name(const Eigen::Vector3d& d) {
  // A component below sin 2° is taken as none: a set-up placed by hand is not exact.
  const double none = std::sin(2 * M_PI / 180);
  const char* axes = "XYZ";
  std::string signs;
  int along = 0, which = 0;
  for (int k = 0; k < 3; ++k)
    if (std::abs(d[k]) > none) {
      ++along;
      which = k;
      signs += fmt::format("{}{}", d[k] > 0 ? "+" : "−", axes[k]);  // minus sign: no break
    }
  if (along <= 1) return fmt::format("along {}", axes[which]);
  if (along == 2) {
    std::string plane;
    for (int k = 0; k < 3; ++k)
      if (std::abs(d[k]) > none) plane += axes[k];
    return fmt::format("{} plane diagonal ({})", plane, signs);
  }
  return fmt::format("space diagonal ({})", signs);
}

double Mpe::at(double length_mm) const {
  const double v = a + (k > 0 ? length_mm / k : 0.0);
  return std::min(v, cap);
}

Mpe Mpe::parse(const std::string& text) {
  Mpe m;
  m.text = text;
  std::string t;
  for (char c : text)
    if (c != ' ') t += c;
  auto number = [&](const std::string& s, const char* what) {
    double v = 0;
    const auto r = std::from_chars(s.data(), s.data() + s.size(), v);
    if (r.ec != std::errc() || r.ptr != s.data() + s.size() || !(v > 0) || !std::isfinite(v))
      throw Error(
          fmt::format("MPE '{}': {} '{}' must be a positive number (write A+L/K or "
                      "A+L/K,B in µm with L in mm, e.g. 1.5+L/300)",
                      text, what, s));
    return v;
  };
  std::string body = t;
  if (const auto comma = t.find(','); comma != std::string::npos) {
    m.cap = number(t.substr(comma + 1), "the cap B");
    body = t.substr(0, comma);
  }
  const auto plus = body.find("+L/");
  if (plus == std::string::npos) {
    m.a = number(body, "A");
  } else {
    m.a = number(body.substr(0, plus), "A");
    m.k = number(body.substr(plus + 3), "K");
  }
  return m;
}

MpeCheck check_mpe(const std::vector<LengthRow>& rows, const Mpe& mpe, bool after) {
  MpeCheck c;
  for (const auto& r : rows) {
    const double e = std::abs(after ? r.after : r.before) * 1e3;  // µm
    const double limit = mpe.at(r.nominal);
    ++c.lengths;
    if (e > limit) ++c.failed;
    c.worst_ratio = std::max(c.worst_ratio, e / limit);
  }
  return c;
}

}  // namespace trueaxis::ballgauge
