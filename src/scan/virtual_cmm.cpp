// The virtual CMM: servo-level moves, touches, design-value and autonomous scans against a
// simulated part.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "trueaxis/error.hpp"
#include "trueaxis/scan/machine.hpp"
#include "trueaxis/sim/part.hpp"
#include "virtual_cmm_detail.hpp"

namespace trueaxis::scan {
using namespace vcmm;
namespace {
bool same_plane(const design::Plane& a, const design::Plane& b) {
  const Eigen::Vector3d na = a.normal.normalized(), nb = b.normal.normalized();
  return na.cross(nb).norm() < 1e-9 && std::abs((b.origin - a.origin).dot(na)) < 1e-6;
}
}  // namespace

VirtualCmm::VirtualCmm(sim::Part part, const VirtualCmmOptions& options,
                       const Eigen::Vector3d& home)
    : part_(std::move(part)), o_(options), servo_(options.servo, home), probe_(options.probe) {
  part_.validate();
  for (const auto& s : part_.design.sections) {
    if (s.space_curve()) {
      spaces_.emplace_back(s.name, sim::true_space_curve(part_, s));
      // A space curve in one plane is also that plane's contour, for touches and autonomous
      // scans once the controller treats it as a plane section.
      if (auto planar = design::as_plane_section(s)) {
        planar->plane.normal.normalize();
        contours_.emplace_back(planar->plane, sim::true_contour(part_, *planar));
      }
      continue;
    }
    design::Plane pl = s.plane;
    pl.normal.normalize();
    contours_.emplace_back(pl, sim::true_contour(part_, s));
  }
  o_.stylus.validate(probe_.options().tip_radius);
  if (!(o_.overtravel > 0 && o_.overtravel <= 20))
    throw Error(fmt::format("probe overtravel {:g} mm: must be in (0, 20]", o_.overtravel));
  std::shared_ptr<const solid::Mesh> design_solid = o_.solid;
  if (!design_solid && !part_.design.solid.empty())
    design_solid = solid::load_step(part_.design.solid);
  if (design_solid && !design_solid->empty()) {
    solid_ = std::make_shared<const solid::Mesh>(design_solid->transformed(sim::transform(part_)));
    if (o_.table) table_z_ = solid_->box().min().z();
    touch_faces(nullptr);
    // The part's dents (and its form noise, to 4 standard deviations) are in its contours, not
    // in the solid: the stylus may enter the solid that deep (check_solid).
    for (const auto& b : part_.deviation.bumps) dent_ = std::max(dent_, -b.height);
    dent_ += 4 * part_.deviation.noise;
  }
  if (const auto& m = o_.geometry) {
    m->validate();
    // The part's bounding box, grown by the clearance, must lie within the travel.
    Eigen::Vector3d lo = Eigen::Vector3d::Constant(1e300), hi = -lo;
    for (const auto& [pl, c] : contours_) {
      lo = lo.cwiseMin(c.points().rowwise().minCoeff());
      hi = hi.cwiseMax(c.points().rowwise().maxCoeff());
    }
    for (const auto& [name, c] : spaces_) {
      lo = lo.cwiseMin(c.points().rowwise().minCoeff());
      hi = hi.cwiseMax(c.points().rowwise().maxCoeff());
    }
    lo.array() -= o_.clearance;
    hi.array() += o_.clearance;
    if (o_.part_origin) {
      origin_ = *o_.part_origin;
    } else {
      for (int k = 0; k < 3; ++k)
        origin_[k] = 0.5 * (m->range[k][0] + m->range[k][1]) - 0.5 * (lo[k] + hi[k]);
      origin_ += m->offset;
    }
    if (!origin_.allFinite()) throw Error("the part's origin on the machine must be finite");
    for (int k = 0; k < 3; ++k) {
      const double a = lo[k] + origin_[k] - m->offset[k], b = hi[k] + origin_[k] - m->offset[k];
      if (a < m->range[k][0] || b > m->range[k][1])
        throw Error(fmt::format(
            "the part does not fit on machine '{}': along {} it needs commands {:.1f} to {:.1f} "
            "mm ({:g} mm clearance included), the travel is {:g} to {:g} mm",
            m->name, "XYZ"[k], a, b, o_.clearance, m->range[k][0], m->range[k][1]));
    }
  }
}

void Stylus::validate(double tip_radius) const {
  auto bad = [](const char* what, double v, const char* why) {
    throw Error(fmt::format("stylus {} {:g} mm: {}", what, v, why));
  };
  if (!(length >= 2 * tip_radius && length <= 1000))
    bad("length", length, "must be at least the ball's diameter and at most 1000 mm");
  if (!(shaft_radius >= 0 && shaft(tip_radius) < tip_radius))
    bad("shaft radius", shaft_radius, "must be thinner than the ball (0: half its radius)");
  if (!(body_radius > 0 && body_radius <= 1000))
    bad("body radius", body_radius, "must be in (0, 1000]");
  if (!(body_length >= body_radius && body_length <= 1000))
    bad("body length", body_length, "must be at least the body's radius, at most 1000 mm");
}

struct VirtualCmm::Operation {
  VirtualCmm& m;
  std::vector<char> saved;
  Operation(VirtualCmm& cmm, const design::Plane& plane) : m(cmm), saved(cmm.touchable_) {
    m.touch_faces(&plane);
  }
  ~Operation() {
    m.touchable_ = std::move(saved);
    m.guard_clear_ = {-1, -1, -1};
  }
};

void VirtualCmm::orient(const Eigen::Vector3d& axis) {
  if (!axis.allFinite() || !(axis.norm() > 0.5))
    throw Error("orient: the stylus axis is not a direction");
  Machine::orient(axis);
  guard_clear_ = {-1, -1, -1};
}

void VirtualCmm::touch_faces(const design::Plane* plane) {
  guard_clear_ = {-1, -1, -1};
  if (!solid_) return;
  touchable_ = plane ? solid_->faces_crossing(plane->origin, plane->normal)
                     : std::vector<char>(static_cast<std::size_t>(solid_->face_count()), 0);
  plane_normal_ = plane ? Eigen::Vector3d(plane->normal.normalized()) : Eigen::Vector3d::Zero();
}

void VirtualCmm::check_solid() {
  if (!solid_) return;
  // The probe's body rides on the carriage; the stylus and its ball move with the deflection.
  const Eigen::Vector3d c = free_ball_centre(), ball = c + deflection_ + corner_;
  const double r = probe_.options().tip_radius, rs = o_.stylus.shaft(r);
  const Eigen::Vector3d& u = axis_;
  // The stem from the ball to the probe's nose; the body a capsule whose round nose ends where
  // the stem does.
  const double rb = o_.stylus.body_radius;
  const Eigen::Vector3d s0 = ball + r * u, s1 = ball + (o_.stylus.length + rb) * u,
                        n0 = c + (o_.stylus.length + rb) * u,
                        b1 = c + (o_.stylus.length + o_.stylus.body_length) * u;
  const char* what[3] = {"ball", "stylus", "probe body"};
  for (int k = 0; k < 3; ++k) {
    // Nothing can have been reached since the last check if the element moved less than the
    // clearance found then (every point of a translated element moves as far).
    const Eigen::Vector3d& at = k < 2 ? ball : c;
    if (guard_clear_[k] > 0 && (at - guard_at_[k]).norm() < guard_clear_[k]) continue;
    ++solid_checks_;
    double clear = 0, table = INFINITY;
    if (k == 0) {
      clear = solid_->distance(ball, r + kSolidLookout, touchable_) - (r - ball_allowance_);
      if (clear < 0 && clear > -solid::kScansOnDepth * r && plane_normal_.squaredNorm() > 0 &&
          solid::scans_on(*solid_, ball, touchable_, plane_normal_))
        clear = 0;  // on the scanned wall's continuation: checked again at the next tick
      table = ball.z() - r - table_z_;
    } else if (k == 1) {
      // Beside a dent the stem follows the ball into the design solid: into the face the section
      // cuts and past the edges beside it (the dent reaches through them, the solid holds none of
      // it). So the stem may enter the solid as deep as the part's deepest dent (dent_): a stem
      // driven into a face is caught that much later, a graze shallower than a dent not at all.
      clear = solid_->distance(s0, s1, rs + kSolidLookout) - rs + dent_ + stem_allowance_;
      table = std::min(s0.z(), s1.z()) - rs - table_z_;
    } else {
      clear = solid_->distance(n0, b1, rb + kSolidLookout) - rb;
      table = std::min(n0.z(), b1.z()) - rb - table_z_;
    }
    if (clear < 0 || table < -(k == 0 ? ball_allowance_ : 0)) {
      if (guarded_ && k < 2) {
        // The stylus gives way: the probe triggers, and the motion brakes (stop_on_contact).
        if (triggered_ < 0) {
          triggered_ = k;
          on_table_ = clear >= 0;
        }
        guard_clear_[k] = -1;
        continue;
      }
      settle();  // the machine stops
      throw Error(fmt::format(
          "collision: the {} ran into the {} with the ball centre at ({:.2f}, {:.2f}, {:.2f}) mm "
          "and the stylus along ({:.3f}, {:.3f}, {:.3f})",
          what[k], clear < 0 ? "part" : "table", ball.x(), ball.y(), ball.z(), u.x(), u.y(),
          u.z()));
    }
    guard_at_[k] = at;
    guard_clear_[k] = std::min(clear, table);
  }
}

Eigen::Vector3d VirtualCmm::machine_error(const Eigen::Vector3d& p) const {
  if (!o_.geometry) return Eigen::Vector3d::Zero();
  return o_.geometry->error(p + origin_ - o_.geometry->offset);
}

std::vector<const sim::Contour*> VirtualCmm::in_plane(const design::Plane& plane) const {
  std::vector<const sim::Contour*> out;
  for (const auto& [pl, c] : contours_)
    if (same_plane(pl, plane)) out.push_back(&c);
  if (out.empty()) throw Error("the simulated part has no section in this plane");
  return out;
}

double VirtualCmm::distance(const design::Plane& plane, const Eigen::Vector3d& p) const {
  double best = 1e300;
  for (const sim::Contour* c : in_plane(plane)) {
    const double d = c->nearest(p).distance;
    if (std::abs(d) < std::abs(best)) best = d;
  }
  return best;
}

const sim::SpaceCurve& VirtualCmm::space_curve(const std::string& name) const {
  for (const auto& [n, c] : spaces_)
    if (n == name) return c;
  throw Error("the simulated part has no space-curve section '" + name + "'");
}

double VirtualCmm::distance(const design::Section& section, const Eigen::Vector3d& p) const {
  if (section.space_curve()) return space_curve(section.name).nearest(p).distance;
  return distance(section.plane, p);
}

Eigen::Vector3d VirtualCmm::free_ball_centre() const {
  const Eigen::Vector3d& p = servo_.position();
  return o_.geometry ? Eigen::Vector3d(p + machine_error(p)) : p;
}

sim::ProbeReading VirtualCmm::read(const std::vector<const sim::Contour*>& part) {
  // The ball meets the nearest contour of the plane: the one met last is usually it, and the
  // others only need looking at within that distance.
  const Eigen::Vector3d pos = free_ball_centre();
  if (space_) {
    const sim::ProbeReading reading = probe_.read(space_->nearest(pos));
    deflection_ = reading.true_deflection;
    corner_.setZero();
    return reading;
  }
  std::size_t first = 0;
  for (std::size_t k = 0; k < part.size(); ++k)
    if (part[k] == last_contour_) first = k;
  last_contour_ = part[first];
  sim::Contour::Nearest best = part[first]->nearest(pos);
  for (std::size_t k = 0; k < part.size(); ++k) {
    if (k == first) continue;
    if (const auto n = part[k]->nearest_within(pos, std::abs(best.distance));
        n && std::abs(n->distance) < std::abs(best.distance)) {
      best = *n;
      last_contour_ = part[k];
    }
  }
  const sim::ProbeReading reading = probe_.read(best);
  deflection_ = reading.true_deflection;
  // The probe reads its contact with the nearest wall. Where the ball, pushed out of that one, is
  // still within its radius of another (a concave corner: the walls meet at less than 180°), it
  // rests against both: pushed out of each in turn (alternating projections onto the walls'
  // offsets, which meet where the ball touches both), as the solid check takes it. Otherwise
  // the stem, which follows the ball, would be caught inside the wall the ball cannot enter.
  corner_.setZero();
  if (reading.contact) {
    const double r = probe_.options().tip_radius;
    Eigen::Vector3d b = pos + deflection_;
    for (int it = 0; it < 16; ++it) {
      double worst = 0;
      Eigen::Vector3d push = Eigen::Vector3d::Zero();
      for (const sim::Contour* c : part)
        if (const auto n = c->nearest_within(b, r); n && r - n->distance > worst + 1e-12) {
          worst = r - n->distance;
          push = worst * n->normal;
        }
      if (worst <= 1e-9) break;
      b += push;
    }
    corner_ = b - pos - deflection_;
  }
  return reading;
}

Sample VirtualCmm::sample(const sim::ProbeReading& r, double arc) const {
  Sample s;
  s.t = servo_.time();
  s.arc = arc;
  s.contact = r.contact;
  s.overtravel = r.overtravel;
  const double m = r.deflection.norm();
  if (r.contact) s.deflection = m;
  if (r.contact && m > 0) {
    s.normal = r.deflection / m;
    s.surface = servo_.position() + r.deflection - probe_.options().tip_radius * s.normal;
  }
  return s;
}

double VirtualCmm::penetration(Eigen::Vector3d* push) const {
  // The ball against every section whose plane it straddles (the part is known there only).
  const Eigen::Vector3d pos = free_ball_centre();
  const double r = probe_.options().tip_radius;
  double worst = 0;
  if (push) push->setZero();
  for (const auto& [pl, c] : contours_) {
    if (std::abs((pos - pl.origin).dot(pl.normal)) > r) continue;
    if (const auto n = c.nearest_within(pos, r); n && r - n->distance > worst) {
      worst = r - n->distance;
      if (push) *push = worst * n->normal;
    }
  }
  return worst;
}

void VirtualCmm::settle() {
  // Hold where the carriage is now; it coasts to rest in the servo's lag (a scan stopped at
  // speed overshoots by about v·(1/kp + lag)).
  const Eigen::Vector3d hold = servo_.position();
  for (long k = 0; k < kMaxTicks && servo_.velocity().norm() > 1e-3; ++k)
    servo_.step(hold, Eigen::Vector3d::Zero());
}

std::optional<Touch> VirtualCmm::touch(const design::Plane& plane, const Eigen::Vector3d& start,
                                       const Eigen::Vector3d& direction, double distance,
                                       double speed, double trigger) {
  const auto c = in_plane(plane);
  const Operation op(*this, plane);
  move(start, o_.positioning_speed);
  const Eigen::Vector3d d = direction.normalized();
  const double dt = servo_.options().dt();
  std::optional<Touch> out;
  double s = 0;
  // The stem, or the ball on a face off the plane, meeting the part stops the touch as it would
  // a free move: the probe cannot tell where it is touched.
  const Guard guard(guarded_, triggered_);
  const double start_in = pushed_in();
  while (s <= distance) {
    servo_.step(start + d * s, d * speed);
    s += speed * dt;
    const auto r = read(c);
    if (!r.overtravel) check_solid();  // over-travel: the probe stops the machine first
    if (triggered_ >= 0) stop_on_contact(free_ball_centre(), start + d * s, d, speed, start_in, 0);
    if (r.overtravel) break;
    if (r.contact && r.deflection.norm() >= trigger) {
      const Sample smp = sample(r, 0);
      out = Touch{smp.surface, smp.normal, smp.t};
      break;
    }
  }
  // Retract along the approach direction, by 1 mm or back to the start if that is nearer.
  const double back = std::min(1.0, (servo_.position() - start).norm());
  settle();
  move(servo_.position() - d * back, o_.positioning_speed);
  return out;
}

ScanOutcome VirtualCmm::scan_path(const design::ScanPath& path, const ScanSettings& st,
                                  const Monitor& monitor) {
  // A space path meets the part's space curve of that name; a plane path the plane's contours.
  struct Meet {
    const sim::SpaceCurve*& slot;
    ~Meet() { slot = nullptr; }
  } meet{space_};
  std::vector<const sim::Contour*> c;
  if (path.space())
    space_ = &space_curve(path.section);
  else
    c = in_plane(path.plane);
  ScanOutcome out;
  std::optional<Operation> op;
  if (!path.space()) op.emplace(*this, path.plane);
  const double L = path.length(), dt = servo_.options().dt(), a = o_.path_acceleration;
  const auto p0 = path.at(0);
  // Approach: from outside the path, along the normal, until the probe is pushed by Ep.
  const Eigen::Vector3d outside = p0.p + st.approach_clearance * p0.normal;
  move(outside, o_.positioning_speed);
  const Guard guard(guarded_, triggered_);
  double cnorm = st.approach_clearance;  // the normal correction: offset from the path (mm)
  const double approach_speed = o_.approach_speed;
  for (;;) {
    servo_.step(p0.p + cnorm * p0.normal, -approach_speed * p0.normal);
    cnorm -= approach_speed * dt;
    const auto r = read(c);
    if (!r.overtravel) check_solid();  // over-travel: the probe stops the machine first
    if (triggered_ >= 0) {
      out.fault = brake(free_ball_centre(), p0.p + cnorm * p0.normal, -p0.normal, approach_speed,
                        penetration(), "on the approach to the scan");
      move(outside, o_.positioning_speed);
      return out;
    }
    Sample smp = sample(r, 0);
    smp.delta_l = (servo_.position() + r.deflection - p0.p).dot(p0.normal) - st.pushing;
    if (r.contact && r.deflection.norm() >= st.pushing) break;
    if (r.overtravel || cnorm < -st.approach_limit) {
      out.stop = smp;
      out.fault = r.overtravel ? "over-travel on the approach"
                               : fmt::format("no surface within {:g} mm of the path's start",
                                             st.approach_limit);
      move(outside, o_.positioning_speed);
      return out;
    }
  }
  if (!st.active) cnorm = 0;
  // Look-ahead: the speed allowed at each segment's start so that the carriage can slow down in
  // time for slower (tighter) segments ahead and stop at the end.
  const std::size_t ns = path.segments.size();
  std::vector<double> begin(ns + 1, 0.0), entry(ns + 1, 0.0);
  for (std::size_t i = 0; i < ns; ++i) begin[i + 1] = begin[i] + path.segments[i].length;
  for (std::size_t i = ns; i-- > 0;)
    entry[i] = std::min({path.segments[i].speed, path.segments[i].corner_speed,
                         std::sqrt(entry[i + 1] * entry[i + 1] + 2 * a * path.segments[i].length)});
  std::size_t seg = 0;
  double s = 0, v = 0, next_record = 0;
  auto here = path.at(s);
  for (long k = 0; k < kMaxTicks; ++k) {
    while (seg + 1 < ns && s >= begin[seg + 1]) ++seg;
    const double ahead =
        std::sqrt(entry[seg + 1] * entry[seg + 1] + 2 * a * std::max(0.0, begin[seg + 1] - s));
    v = std::min({here.speed, v + a * dt, ahead});
    servo_.step(here.p + cnorm * here.normal, here.tangent * v);
    s = std::min(L, s + v * dt);
    here = path.at(s);  // where the path is now, and where the next tick starts
    const auto& now = here;
    const auto r = read(c);
    if (!r.overtravel) check_solid();  // over-travel: the probe stops the machine first
    if (triggered_ >= 0) {
      out.fault = brake(free_ball_centre(), here.p + cnorm * here.normal, here.tangent, v,
                        penetration(), "scanning");
      break;
    }
    Sample smp = sample(r, s);
    // On a perfect part the ball centre runs Ep outside the (pushed-in) path.
    smp.delta_l = (servo_.position() + r.deflection - now.p).dot(now.normal) - st.pushing;
    if (st.active) {
      const double e = r.contact ? r.deflection.dot(now.normal) - st.pushing : -st.pushing;
      cnorm += o_.correction_gain * e * dt;
    }
    out.stop = smp;
    if (r.contact && s >= next_record) {
      out.samples.push_back(smp);
      next_record += st.record_spacing;
    }
    if (!monitor(smp)) break;
    if (r.overtravel) {
      out.fault = "over-travel: the probe was pushed beyond its measuring range";
      break;
    }
    if (s >= L && v < 1e-9) {
      out.completed = true;
      break;
    }
  }
  // Retract away from the surface.
  const auto end = path.at(s);
  settle();
  retract({end.normal, out.stop.normal}, st.approach_clearance, out);
  return out;
}

void VirtualCmm::retract(const std::vector<Eigen::Vector3d>& along, double distance,
                         ScanOutcome& out) {
  // Along the first direction whose move the probe does not stop on the part (a part off its
  // design may stand in the design normal's way at a corner), back to the scan's end between.
  // At the guarded speed: the way off a part that is not where its design is may meet it.
  const Eigen::Vector3d end = servo_.position();
  const double v = std::min(o_.positioning_speed, *guarded_speed());
  std::string met;
  for (const Eigen::Vector3d& d : along) {
    if (!(d.norm() > 0.5)) continue;
    try {
      move(end + distance * d.normalized(), v);
      return;
    } catch (const UnexpectedTouch& e) {
      met = e.what();
      move(end, v);
    }
  }
  if (out.fault.empty()) out.fault = "the retract from the surface: " + met;
}

ScanOutcome VirtualCmm::scan_unknown(const design::Plane& plane, const Eigen::Vector3d& start,
                                     const Eigen::Vector3d& approach, design::Side material,
                                     bool closed, double length, double speed,
                                     const ScanSettings& st) {
  const auto c = in_plane(plane);
  const Operation op(*this, plane);
  const Eigen::Vector3d n = plane.normal.normalized();
  const double dt = servo_.options().dt(), gain = 40;
  ScanOutcome out;
  move(start, o_.positioning_speed);
  const Guard guard(guarded_, triggered_);
  // Approach until pushed by Ep.
  const Eigen::Vector3d dir = approach.normalized();
  double s = 0;
  sim::ProbeReading r;
  for (;;) {
    servo_.step(start + s * dir, dir * o_.approach_speed);
    s += o_.approach_speed * dt;
    r = read(c);
    if (!r.overtravel) check_solid();  // over-travel: the probe stops the machine first
    if (triggered_ >= 0) {
      out.fault = brake(free_ball_centre(), start + s * dir, dir, o_.approach_speed, penetration(),
                        "on the approach to the scan");
      move(start, o_.positioning_speed);
      return out;
    }
    if (r.contact && r.deflection.norm() >= st.pushing) break;
    if (s > 2 * (st.approach_clearance + st.approach_limit) + 10) {
      out.fault = "autonomous scan: no surface found on the approach";
      out.missed_surface = true;
      move(start, o_.positioning_speed);
      return out;
    }
  }
  Eigen::Vector3d dhat = r.deflection.normalized();
  const Sample first = sample(r, 0);
  Eigen::Vector3d last_surface = first.surface;
  Eigen::Vector3d t0 =
      (material == design::Side::Left ? n.cross(dhat) : Eigen::Vector3d(dhat.cross(n)));
  double arc = 0, next_record = 0, lost = 0, v = 0;
  const double limit = closed ? 5 * length + 100 : length;
  for (long k = 0; k < kMaxTicks; ++k) {
    if (r.contact && r.deflection.norm() > 0) dhat = r.deflection.normalized();
    const Eigen::Vector3d d =
        material == design::Side::Left ? n.cross(dhat) : Eigen::Vector3d(dhat.cross(n));
    const double e = r.contact ? r.deflection.norm() - st.pushing : -st.pushing;
    v = std::min(speed, v + o_.path_acceleration * dt);
    const Eigen::Vector3d vel = v * d + gain * e * dhat;
    servo_.step(servo_.position(), vel);
    r = read(c);
    if (!r.overtravel) check_solid();  // over-travel: the probe stops the machine first
    if (triggered_ >= 0) {
      out.fault = brake(free_ball_centre(), servo_.position(), d, v, penetration(), "scanning");
      break;
    }
    Sample smp = sample(r, arc);
    if (r.contact) {
      arc += (smp.surface - last_surface).norm();
      last_surface = smp.surface;
      smp.arc = arc;
      lost = 0;
      if (arc >= next_record) {
        out.samples.push_back(smp);
        next_record += st.record_spacing;
      }
    } else {
      lost += v * dt;
    }
    out.stop = smp;
    if (r.overtravel) {
      out.fault = "over-travel in the autonomous scan";
      break;
    }
    if (lost > 5) {
      out.fault = "autonomous scan: contact lost for 5 mm";
      break;
    }
    if (closed && arc > 5 && (smp.surface - first.surface).norm() < 1 &&
        (smp.surface - first.surface).dot(t0) >= 0) {
      out.completed = true;
      break;
    }
    if (!closed && arc >= length) {
      out.completed = true;
      break;
    }
    if (arc > limit) {
      out.fault = "autonomous scan: did not return to its start";
      break;
    }
  }
  settle();
  retract({dhat, out.stop.normal}, st.approach_clearance, out);
  return out;
}

}  // namespace trueaxis::scan
