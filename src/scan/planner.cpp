// Motion planning against the part's solid (planner.hpp).
#include "trueaxis/scan/planner.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <vector>

#include "trueaxis/error.hpp"

namespace trueaxis::scan {
namespace {

// Distances are looked for this far beyond the margin (mm): farther counts as this far.
constexpr double kLookout = 20;
// Steps of a conservative advance are at least this long (mm): a clearance within it of the
// margin counts as touching it.
constexpr double kLeast = 1e-3;
// How much less than its start's clearance the first leg of a way round the part may keep (mm):
// backing away stops where the margin is reached along the clearance's slope, which need not be
// the most clearance across the way out.
constexpr double kLeaveDip = 0.1;
// Ways round the part at a move's level: how far out across the move they go (mm).
constexpr std::array<double, 12> kRoundAboutOffsets{2, 3, 5, 8, 12, 18, 27, 40, 60, 90, 135, 200};

std::string at(const Eigen::Vector3d& p) {
  return fmt::format("({:.2f}, {:.2f}, {:.2f})", p.x(), p.y(), p.z());
}

}  // namespace

Planner::Planner(std::shared_ptr<const solid::Mesh> part, double tip_radius, const Stylus& stylus,
                 double margin, double clearance, double fallback_top)
    : part_(std::move(part)),
      r_(tip_radius),
      margin_(margin),
      clearance_(clearance),
      fallback_top_(fallback_top),
      stylus_(stylus) {
  stylus_.validate(r_);
  if (part_ && part_->empty()) part_.reset();
  if (part_) table_z_ = part_->box().min().z();
}

Planner Planner::moved(const Eigen::Affine3d& t) const {
  Planner p = *this;
  p.placement_ = t * placement_;
  if (part_ && !t.isApprox(Eigen::Affine3d::Identity(), 1e-15)) {
    p.part_ = std::make_shared<const solid::Mesh>(part_->transformed(t));
    p.table_z_ = table_z_;  // the table stays where it is
  }
  return p;
}

double Planner::element(int k, const Eigen::Vector3d& lo, const Eigen::Vector3d& hi,
                        const Eigen::Vector3d& u, const std::vector<char>& skip, double look,
                        bool table) const {
  const double rs = stylus_.shaft(r_), rb = stylus_.body_radius;
  const double table_z = table ? table_z_ : -INFINITY;
  if (look < 0) look = margin_ + kLookout;
  // As the virtual CMM checks it: the stem up to the probe's round nose, then the body. Moving
  // along its own axis, each element sweeps a segment of that line: from its lower end at the
  // lowest ball centre to its higher end at the highest.
  if (k == 0) {
    // Signed: a ball whose centre is inside the solid (a real part off its design lets the ball
    // stand where the design has material) is that far in, so that backing away leads out.
    double d =
        lo == hi ? part_->distance(lo, r_ + look, skip) : part_->distance(lo, hi, r_ + look, skip);
    if (skip.empty() && part_->inside(lo)) d = -d;
    return std::min(d - r_, std::min(lo.z(), hi.z()) - r_ - table_z);
  }
  const Eigen::Vector3d a = lo + (k == 1 ? r_ : stylus_.length + rb) * u,
                        b = hi +
                            (k == 1 ? stylus_.length + rb : stylus_.length + stylus_.body_length) *
                                u;
  const double radius = k == 1 ? rs : rb;
  return std::min(part_->distance(a, b, radius + look, skip) - radius,
                  std::min(a.z(), b.z()) - radius - table_z);
}

double Planner::clearance(const Eigen::Vector3d& c, const Eigen::Vector3d& axis,
                          const std::vector<char>& skip) const {
  if (!part_) return INFINITY;
  return std::min(
      {element(0, c, c, axis, skip), element(1, c, c, axis, skip), element(2, c, c, axis, skip)});
}

double Planner::part_clearance(const Eigen::Vector3d& c, const Eigen::Vector3d& axis) const {
  if (!part_) return INFINITY;
  return std::min({element(0, c, c, axis, {}, -1, false), element(1, c, c, axis, {}, -1, false),
                   element(2, c, c, axis, {}, -1, false)});
}

double Planner::swept_along_axis(const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                                 const Eigen::Vector3d& u) const {
  const bool up = (b - a).dot(u) >= 0;
  const Eigen::Vector3d& lo = up ? a : b;
  const Eigen::Vector3d& hi = up ? b : a;
  return std::min(
      {element(0, lo, hi, u, {}), element(1, lo, hi, u, {}), element(2, lo, hi, u, {})});
}

bool Planner::clear(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& axis,
                    double margin) const {
  if (!part_) return true;
  const double L = (b - a).norm();
  const Eigen::Vector3d d = L > 0 ? Eigen::Vector3d((b - a) / L) : Eigen::Vector3d::Zero();
  // Along the stylus's own axis (a retract, a descent), the swept elements are checked at once:
  // stepping by the clearance less the margin would crawl up a wall the stylus stands beside.
  const Eigen::Vector3d u = axis.normalized();
  if (L > 0 && d.cross(u).norm() < 1e-12) return swept_along_axis(a, b, u) >= margin + kLeast;
  // Every point of the stylus moves as far as its ball: the clearance cannot fall by more than
  // the distance moved.
  for (double t = 0;;) {
    const double c = clearance(a + t * d, axis);
    if (c < margin + kLeast) return false;
    if (t >= L) return true;
    t = std::min(L, t + (c - margin));
  }
}

double Planner::length(const Eigen::Vector3d& a, const std::vector<Eigen::Vector3d>& way) {
  double L = 0;
  Eigen::Vector3d p = a;
  for (const Eigen::Vector3d& q : way) {
    L += (q - p).norm();
    p = q;
  }
  return L;
}

std::vector<Eigen::Vector3d> Planner::route(const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                                            const Eigen::Vector3d& axis, bool rise,
                                            const WayCost& cost, double least_per_mm) const {
  const Eigen::Vector3d u = axis.normalized();
  std::vector<Eigen::Vector3d> out;
  // Back away from the part first if the ball stands nearer than the margin: in small steps up
  // the clearance's slope (its gradient by central differences).
  Eigen::Vector3d from = a;
  if (part_) {
    for (int k = 0; k < 100; ++k) {
      const double c = clearance(from, u);
      if (c >= margin_) break;
      constexpr double h = 0.02;
      Eigen::Vector3d g;
      for (int i = 0; i < 3; ++i) {
        Eigen::Vector3d e = Eigen::Vector3d::Zero();
        e[i] = h;
        g[i] = (clearance(from + e, u) - clearance(from - e, u)) / (2 * h);
      }
      if (!(g.norm() > 1e-6)) break;
      const Eigen::Vector3d next = from + std::min(0.25, margin_ - c + kLeast) * g.normalized();
      if (clearance(next, u) <= c) break;
      from = next;
      out.push_back(from);
    }
  }
  // Without the solid the part is known only by its sections: always over the top.
  if (!rise && part_ && clear(from, b, u, margin_)) {
    out.push_back(b);
    return out;
  }
  const Eigen::Vector3d start = from;
  const WayCost by_length = [&](const std::vector<Eigen::Vector3d>& way) { return length(a, way); };
  const WayCost& measure = cost ? cost : by_length;
  const double per_mm = cost ? least_per_mm : 1.0;
  auto whole = [&](const std::vector<Eigen::Vector3d>& w) {
    std::vector<Eigen::Vector3d> way = out;
    way.insert(way.end(), w.begin(), w.end());
    return way;
  };
  std::vector<Eigen::Vector3d> best;
  double least = INFINITY;
  std::string blocked;
  try {
    best = whole(over_the_top(a, start, b, u));
    least = measure(best);
  } catch (const NoWay& e) {
    blocked = e.what();
  }
  // Round the part, where a way could cost less than over the top: no longer than that cost
  // allows at the least cost a millimetre can have.
  if (!rise && part_)
    for (const auto& w : round_about(start, b, u, least / per_mm)) {
      std::vector<Eigen::Vector3d> way = whole(w);
      if (const double c = measure(way); c < least) {
        least = c;
        best = std::move(way);
      }
    }
  if (best.empty()) throw NoWay(blocked);
  return best;
}

std::vector<Eigen::Vector3d> Planner::over_the_top(const Eigen::Vector3d& a,
                                                   const Eigen::Vector3d& start,
                                                   const Eigen::Vector3d& b,
                                                   const Eigen::Vector3d& u) const {
  // The level along the axis the stylus crosses at: the part's highest point under the move
  // (within the probe body's reach of its line), the ball's radius and the clearance above it.
  const double reach = std::max(r_, stylus_.body_radius) + margin_;
  const double top = part_ ? part_->highest_near(u, start, b, reach) : fallback_top_;
  const double level = std::max({start.dot(u), b.dot(u), top + r_ + clearance_});
  const Eigen::Vector3d a1 = start + (level - start.dot(u)) * u, b1 = b + (level - b.dot(u)) * u;
  // If backing away could not reach the margin, the retract must at least not come nearer.
  const double leave = std::min(margin_, clearance(start, u) - 2 * kLeast);
  if (!clear(start, a1, u, leave))
    throw NoWay(
        fmt::format("no free way from {} to {} mm: the part is in the way of the retract "
                    "along the stylus to {}",
                    at(a), at(b), at(a1)));
  if (!clear(a1, b1, u, margin_))
    throw NoWay(
        fmt::format("no free way from {} to {} mm: the part is in the way at the "
                    "clearance level, between {} and {}",
                    at(a), at(b), at(a1), at(b1)));
  if (!clear(b1, b, u, margin_))
    throw NoWay(
        fmt::format("no free way to {} mm: the part is in the way of the approach along "
                    "the stylus from {}",
                    at(b), at(b1)));
  std::vector<Eigen::Vector3d> out;
  if ((a1 - start).norm() > 1e-9) out.push_back(a1);
  if ((b1 - a1).norm() > 1e-9) out.push_back(b1);
  out.push_back(b);
  return out;
}

std::vector<std::vector<Eigen::Vector3d>> Planner::round_about(const Eigen::Vector3d& a,
                                                               const Eigen::Vector3d& b,
                                                               const Eigen::Vector3d& u,
                                                               double longest) const {
  std::vector<std::vector<Eigen::Vector3d>> found;
  const Eigen::Vector3d d = b - a;
  const Eigen::Vector3d side = u.cross(d);
  // A move along the stylus has no level to go round at.
  if (!(side.norm() > 1e-6 * std::max(1.0, d.norm()))) return found;
  const Eigen::Vector3d n = side.normalized();
  // Out across the move by h on either side, then along it and in (a box), or through one
  // intermediate point a quarter, half or three quarters along at that offset.
  struct Candidate {
    double length;
    int group;
    std::vector<Eigen::Vector3d> way;
  };
  std::vector<Candidate> all;
  int group = 0;
  for (const double h : kRoundAboutOffsets)
    for (const double sign : {1.0, -1.0}) {
      const Eigen::Vector3d off = sign * h * n;
      all.push_back({2 * h + d.norm(), group, {a + off, b + off, b}});
      for (const double t : {0.25, 0.5, 0.75}) {
        const Eigen::Vector3d w = a + t * d + off;
        all.push_back({(w - a).norm() + (b - w).norm(), group, {w, b}});
      }
      ++group;
    }
  std::stable_sort(all.begin(), all.end(),
                   [](const Candidate& x, const Candidate& y) { return x.length < y.length; });
  // The shortest clear way of each offset no longer than `longest`: a longer way further out may
  // still cost less where it leaves the band the caller slows down in.
  std::vector<char> taken(static_cast<std::size_t>(group), 0);
  // A start that backing away left just at the margin may lie on a ridge of the clearance across
  // the way out: the first leg keeps its own clearance less kLeaveDip.
  const double leave = std::min(margin_, clearance(a, u) - kLeaveDip);
  for (const Candidate& c : all) {
    if (c.length > longest) break;
    if (taken[static_cast<std::size_t>(c.group)]) continue;
    // Waypoints within the margin first: one query each, not a leg's advance.
    bool free = true;
    for (std::size_t k = 0; k + 1 < c.way.size() && free; ++k)
      free = clearance(c.way[k], u) >= margin_ + kLeast;
    if (!free) continue;
    Eigen::Vector3d p = a;
    for (const Eigen::Vector3d& q : c.way) {
      if (!clear(p, q, u, p == a ? leave : margin_)) {
        free = false;
        break;
      }
      p = q;
    }
    if (!free) continue;
    taken[static_cast<std::size_t>(c.group)] = 1;
    found.push_back(c.way);
  }
  return found;
}

std::vector<char> Planner::faces_crossing(const design::Plane& plane) const {
  if (!part_) return {};
  return part_->faces_crossing(plane.origin, plane.normal);
}

bool Planner::from_above(const Eigen::Vector3d& c, const Eigen::Vector3d& axis) const {
  if (!part_) return true;
  const Eigen::Vector3d u = axis.normalized();
  const double level = std::max(c.dot(u), part_->highest(u) + r_ + clearance_);
  return clear(c + (level - c.dot(u)) * u, c, u, margin_);
}

std::vector<Planner::Blocked> Planner::unreachable(const design::ScanPath& path,
                                                   const Eigen::Vector3d& axis, double step) const {
  std::vector<Blocked> out;
  if (!part_ || path.space()) return out;
  const std::vector<char> skip = faces_crossing(path.plane), none;
  const Eigen::Vector3d u = axis.normalized();
  // The stylus and body keep a tenth of a millimetre from everything (a Ø1 stem beside a wall it
  // scans has 0.2 mm); the ball, from what it does not measure.
  constexpr double kReach = 0.1;
  // The least advance of a pushed ball between checks (mm): a stem or lip thinner than this
  // between two checks is the only thing the push could step over.
  constexpr double kPushStep = 0.05;
  // Until a trajectory error stops it, the ball follows the design path while the real part may
  // stand off its design by up to the margin in any direction: from every such place the ball
  // can get to without crossing the contour, the ball must stay clear of the faces it does not
  // measure and the stylus and body of every face. In the plane, eight directions at the margin.
  // Across it, as far as a move on the table takes the part across (the part rests on the table,
  // which keeps its height: a move of up to the margin in x and y, none in z), offsets every
  // kAcross either way, where the ball's contour is cut from the faces crossing the plane the
  // real part is then cut in: where the plane runs along an edge, or through a face at a small
  // angle to it, the real part's section there is not the design's, or not there at all, and the
  // ball is pushed on (CTC 05 cut at y = 0 runs along the edge of a wall and a face at 33° to the
  // plane: a part 1.6 mm off across the plane lost the wall the ball scanned, and the stem met
  // the part's top edge). Off the plane the ball may
  // touch the faces that plane crosses, and others only where their normal lies near the plane
  // (solid::scans_on: the scanned wall's continuation, where the CAD file splits a wall at or
  // near the plane), as the virtual CMM judges it. As in the plane, these are samples: between
  // two offsets a clearance can fall below the reach by at most half their spacing, so the
  // stylus and body never touch.
  static const char* why[6] = {
      "the ball would touch the part off the section's plane",
      "the stylus would run into the part",
      "the probe body would run into the part",
      "the ball would touch the part off the section's plane if the part stood off its design",
      "the stylus would run into the part if the part stood off its design",
      "the probe body would run into the part if the part stood off its design",
  };
  const Eigen::Vector3d pn = path.plane.normal.normalized();
  constexpr int kInPlane = 8;
  constexpr double kAcross = 0.2;  // == 2 kReach
  const double across_max = margin_ * (pn - pn.z() * Eigen::Vector3d::UnitZ()).norm();
  const int per_side = static_cast<int>(std::ceil(across_max / kAcross - 1e-9));
  const int placements = kInPlane + 2 * per_side;
  // For each placement (the path itself first), its offset across the plane and every face but
  // those the plane it is cut in crosses.
  std::vector<double> across(static_cast<std::size_t>(placements + 1), 0.0);
  std::vector<std::vector<char>> crossings(static_cast<std::size_t>(placements + 1)),
      contours(static_cast<std::size_t>(placements + 1));
  for (int j = -1; j < placements; ++j) {
    const auto i = static_cast<std::size_t>(j + 1);
    if (j >= kInPlane) {
      const int k = j - kInPlane;
      across[i] = (k % 2 ? -1 : 1) * std::min(across_max, kAcross * (k / 2 + 1));
    }
    const std::vector<char>& crossing = crossings[i] =
        across[i] == 0 ? skip : part_->faces_crossing(path.plane.origin + across[i] * pn, pn);
    contours[i].resize(crossing.size());
    for (std::size_t f = 0; f < crossing.size(); ++f) contours[i][f] = !crossing[f];
  }
  const double contact = std::max(0.0, path.offset - 0.05);
  // Each element's clearance is 1-Lipschitz in the ball centre (the capped distance to a fixed
  // set of faces, and the height above the table): where it was last computed, e at x, it is at
  // least e − |x' − x| at x'. The checks below visit thousands of places a fraction of a
  // millimetre apart, and the ball (off its plane) and the body mostly stand far from
  // everything: that lower bound decides them while it stays kTrust above the reach, and stands
  // for the clearance in the push's step (a shorter step, never a longer one). Clearances are
  // looked for only kLook far (the push never goes beyond the margin): a nearer bound makes each
  // query visit fewer of the solid's boxes.
  constexpr double kTrust = 0.25;
  const double kLook = margin_ + 2;
  struct Known {
    Eigen::Vector3d x = Eigen::Vector3d::Zero();
    double e = -INFINITY;
  };
  // One per element and placement (the path itself, then the shifts): consecutive stations'
  // places of one placement are about a step apart.
  std::vector<std::array<Known, 3>> known(static_cast<std::size_t>(placements + 1));
  auto clear_of = [&](int k, int j, const Eigen::Vector3d& x) {
    Known& m = known[static_cast<std::size_t>(j + 1)][static_cast<std::size_t>(k)];
    const double bound = m.e - (x - m.x).norm();
    if (bound >= kReach + kTrust) return bound;
    m.x = x;
    const std::vector<char>& sk = crossings[static_cast<std::size_t>(j + 1)];
    m.e = element(k, x, x, u, k == 0 ? sk : none, kLook);
    if (k == 0 && j >= kInPlane && m.e < kReach && m.e > -solid::kScansOnDepth * r_ &&
        x.z() - r_ - table_z_ >= kReach && solid::scans_on(*part_, x, sk, pn))
      m.e = kReach;
    return m.e;
  };
  auto blocked = [&](double s) -> int {
    const design::PathPoint q = path.at(s);
    const Eigen::Vector3d c = q.p;
    for (int k = 0; k < 3; ++k)
      if (clear_of(k, -1, c) < kReach) return k;
    const Eigen::Vector3d a = q.normal, b = pn.cross(q.normal).normalized();
    for (int j = -1; j < placements; ++j) {
      const auto i = static_cast<std::size_t>(j + 1);
      const double t = std::numbers::pi / 4 * j;
      const Eigen::Vector3d shift =
          j < 0          ? Eigen::Vector3d(Eigen::Vector3d::Zero())
          : j < kInPlane ? Eigen::Vector3d(margin_ * (std::cos(t) * a + std::sin(t) * b))
                         : Eigen::Vector3d(across[i] * pn);
      const std::vector<char>& contour = contours[i];
      // The ball where the part, off by `shift`, leaves it: on the path, and pushed on from
      // there towards the material side where the part is not there (up to the margin, before
      // the trajectory error stops it). A place inside the part, or nearer the contour than the
      // ball stands from it while scanning, is a contact: the ball stops on the surface there,
      // and goes no further. Every place on the way counts (a stem can meet a lip above a
      // groove the ball is pushed into before the ball meets anything): the push advances by
      // no more than the stylus and body have room for, nor than the ball has before contact.
      for (double push = j < 0 ? kPushStep : 0.0;;) {
        const Eigen::Vector3d x = c + shift - push * a;
        if (part_->inside(x)) break;
        const double to_contact = part_->distance(x, contact + margin_, contour) - contact;
        if (to_contact < 0) break;
        double room = to_contact;
        for (int k = 0; k < 3; ++k) {
          const double e = clear_of(k, j, x);
          if (e < kReach) return 3 + k;
          room = std::min(room, e - kReach);
        }
        if (push >= margin_) break;
        push = std::min(margin_, push + std::max(room, kPushStep));
      }
    }
    return -1;
  };

  const double L = path.length();
  const int n = std::max(2, static_cast<int>(std::ceil(L / step)));
  // The boundary between a blocked and a clear arc, to a hundredth of the step.
  auto edge = [&](double clear, double stuck) {
    for (int i = 0; i < 7; ++i) {
      const double mid = 0.5 * (clear + stuck);
      (blocked(mid) < 0 ? clear : stuck) = mid;
    }
    return 0.5 * (clear + stuck);
  };
  double prev_s = 0;
  int prev = blocked(0);
  if (prev >= 0) out.push_back({0, L, why[prev]});
  for (int i = 1; i <= n; ++i) {
    const double s = L * i / n;
    const int now = blocked(s);
    if (now >= 0 && prev < 0) out.push_back({edge(prev_s, s), L, why[now]});
    if (now < 0 && prev >= 0) out.back().to = edge(s, prev_s);
    prev = now;
    prev_s = s;
  }
  return out;
}

}  // namespace trueaxis::scan
