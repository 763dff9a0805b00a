// Joint solver (joint_solver.hpp; Coutinho Ch. 5).
#include "rigid/joint_solver.hpp"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <limits>

#include <Eigen/Eigenvalues>

#include "rigid/integrate.hpp"

namespace simreel::sim::detail {
namespace {

constexpr double kPi = 3.141592653589793;
constexpr double kInf = std::numeric_limits<double>::infinity();

bool moves(const RigidBodies& r, std::uint32_t i) { return i != kStaticBody && r.is_dynamic(i); }

Vec3 angular_velocity(const RigidBodies& r, std::uint32_t i) {
  return i == kStaticBody ? Vec3::Zero() : r.angular_velocity[i];
}

Vec3 linear_velocity(const RigidBodies& r, std::uint32_t i) {
  return i == kStaticBody ? Vec3::Zero() : r.linear_velocity[i];
}

/// After a position correction turned body i: I_w⁻¹ at the new orientation with ω kept and L
/// following it. Keeping L (update_derived) would hand the angular momentum of a tumbling thin
/// link to its axis of least inertia whenever the correction turns that axis towards L: a spin
/// the momentum form then feeds step after step.
void turned(RigidBodies& r, std::uint32_t i) {
  const Mat3 R = r.orientation[i].toRotationMatrix();
  r.inv_inertia_world[i] = R * r.inv_inertia_body[i] * R.transpose();
  sync_angular_momentum(r, i);
}

/// Rotates q by the small world-frame rotation vector dtheta (first order, renormalised: the
/// same update as integrate_positions with ω h = dtheta).
void rotate(Quat& q, const Vec3& dtheta) {
  const Quat dq = Quat(0.0, dtheta.x(), dtheta.y(), dtheta.z()) * q;
  q.coeffs() += 0.5 * dq.coeffs();
  q.normalize();
}

double wrap_angle(double a) {
  while (a > kPi) a -= 2.0 * kPi;
  while (a <= -kPi) a += 2.0 * kPi;
  return a;
}

bool twist_limited(const JointModel& m) { return m.twist_lower > -kPi || m.twist_upper < kPi; }

/// A limit of joint m at frame f: the direction d whose relative angular speed increases the
/// margin C (>= 0 when respected). Up to four per joint (hinge lower/upper, cone, twist
/// lower/upper); returns how many.
int limits_of(const JointModel& m, const JointFrame& f, Vec3 d[4], double c[4]) {
  if (!m.limit_enabled) return 0;
  const JointAngles ang = joint_angles(m, f);
  int n = 0;
  if (m.type == JointType::hinge) {
    d[n] = f.axis_a;
    c[n++] = ang.hinge - m.lower_angle;
    d[n] = -f.axis_a;
    c[n++] = m.upper_angle - ang.hinge;
  } else if (m.type == JointType::spherical) {
    const Vec3 n_swing = f.axis_a.cross(f.axis_b);
    const double s = n_swing.norm();
    if (s > 1e-9) {
      // Turning b about a × b opens the swing: the margin grows along -(a × b).
      d[n] = -n_swing / s;
      c[n++] = m.cone_angle - ang.swing;
    }
    if (twist_limited(m)) {
      const Vec3 t = (f.axis_a + f.axis_b).normalized();
      d[n] = t;
      c[n++] = ang.twist - m.twist_lower;
      d[n] = -t;
      c[n++] = m.twist_upper - ang.twist;
    }
  }
  return n;
}

}  // namespace

JointFrame joint_frame(const RigidBodies& r, const JointModel& m, JointBodies j) {
  JointFrame f;
  auto side = [&](std::uint32_t i, const Vec3& la, const Vec3& ax, const Vec3& rf, Vec3& p,
                  Vec3& arm, Vec3& axis, Vec3& ref, Quat& q) {
    if (i == kStaticBody) {
      p = la;
      arm.setZero();
      axis = ax;
      ref = rf;
      q = Quat::Identity();
      return;
    }
    q = r.orientation[i];
    arm = q * la;
    p = r.position[i] + arm;
    axis = q * ax;
    ref = q * rf;
  };
  side(j.a, m.local_anchor_a, m.local_axis_a, m.local_ref_a, f.pa, f.ra, f.axis_a, f.ref_a, f.qa);
  side(j.b, m.local_anchor_b, m.local_axis_b, m.local_ref_b, f.pb, f.rb, f.axis_b, f.ref_b, f.qb);
  return f;
}

JointAngles joint_angles(const JointModel& m, const JointFrame& f) {
  JointAngles a;
  a.hinge = std::atan2(f.axis_a.dot(f.ref_a.cross(f.ref_b)), f.ref_a.dot(f.ref_b));
  a.swing = std::acos(std::clamp(f.axis_a.dot(f.axis_b), -1.0, 1.0));
  // Swing–twist: the rotation of b relative to a since registration, in a's frame.
  Quat delta = (f.qa.conjugate() * f.qb) * m.rel0.conjugate();
  if (delta.w() < 0.0) delta.coeffs() = -delta.coeffs();
  a.twist = wrap_angle(2.0 * std::atan2(delta.vec().dot(m.local_axis_a), delta.w()));
  return a;
}

void JointSolver::rows_for(const RigidBodies& r, const JointModel& m, JointBodies j,
                           std::uint32_t joint, double h, bool equality_only) {
  const bool da = moves(r, j.a), db = moves(r, j.b);
  if (!da && !db) return;
  const JointFrame f = joint_frame(r, m, j);
  const double ima = da ? r.inv_mass[j.a] : 0.0, imb = db ? r.inv_mass[j.b] : 0.0;
  const Mat3 Ia = da ? r.inv_inertia_world[j.a] : Mat3::Zero();
  const Mat3 Ib = db ? r.inv_inertia_world[j.b] : Mat3::Zero();
  // Velocity-product terms (eq. 5.8's ω × (ω × r); for the hinge's axis rows, the turning of
  // the axis with body a), from the velocities at the start of the step.
  auto eq_row = [&](std::uint8_t kind, const Vec3& lin, const Vec3& ang_a, const Vec3& ang_b) {
    EqRow row;
    row.a = j.a;
    row.b = j.b;
    row.joint = joint;
    row.kind = kind;
    row.ja_lin = -lin;
    row.ja_ang = -ang_a;
    row.jb_lin = lin;
    row.jb_ang = ang_b;
    row.ma_lin = ima * row.ja_lin;
    row.ma_ang = Ia * row.ja_ang;
    row.mb_lin = imb * row.jb_lin;
    row.mb_ang = Ib * row.jb_ang;
    eq_.push_back(row);
  };
  // Anchor rows (eq. 5.5): v_b + ω_b × r_b - v_a - ω_a × r_a = 0 along x, y, z.
  for (std::uint8_t k = 0; k < 3; ++k) {
    const Vec3 d = Vec3::Unit(k);
    eq_row(k, d, f.ra.cross(d), f.rb.cross(d));
  }
  if (m.type == JointType::hinge) {
    Vec3 t1, t2;
    tangent_basis(f.axis_a, t1, t2);
    eq_row(3, Vec3::Zero(), t1, t1);
    eq_row(4, Vec3::Zero(), t2, t2);
  } else if (m.type == JointType::fixed) {
    for (std::uint8_t k = 0; k < 3; ++k) eq_row(std::uint8_t(5 + k), Vec3::Zero(), Vec3::Unit(k), Vec3::Unit(k));
  }
  if (equality_only) return;
  auto ang_row = [&](const Vec3& d, double target, double lo, double hi, double gamma) {
    AngRow row;
    row.a = j.a;
    row.b = j.b;
    row.joint = joint;
    row.d = d;
    row.ia_d = Ia * d;
    row.ib_d = Ib * d;
    const double k = d.dot(row.ia_d) + d.dot(row.ib_d);
    if (k <= 0.0) return;
    row.mass = 1.0 / (k + gamma);
    row.gamma = gamma;
    row.target = target;
    row.lo = lo;
    row.hi = hi;
    row.acc = 0.0;
    ang_.push_back(row);
  };
  // Limits: speculative while open (the approach speed may close the margin C within the step,
  // no more), and stop any further approach once violated; the position projection removes a
  // violation (a velocity bias would add energy).
  Vec3 d[4];
  double c[4];
  const int nl = limits_of(m, f, d, c);
  for (int k = 0; k < nl; ++k) ang_row(d[k], c[k] > 0.0 ? -c[k] / h : 0.0, 0.0, kInf, 0.0);
  if (m.type == JointType::hinge && m.motor_enabled)
    ang_row(f.axis_a, m.motor_speed, -m.max_motor_torque * h, m.max_motor_torque * h, 0.0);
  if (m.damping > 0.0) {
    const double gamma = 1.0 / (m.damping * h);
    if (m.type == JointType::hinge)
      ang_row(f.axis_a, 0.0, -kInf, kInf, gamma);
    else if (m.type == JointType::spherical)
      for (int k = 0; k < 3; ++k) ang_row(Vec3::Unit(k), 0.0, -kInf, kInf, gamma);
  }
}

void JointSolver::prepare(const RigidBodies& r, std::span<const JointModel> models,
                          std::span<const JointBodies> bodies, double h) {
  assert(models.size() == bodies.size());
  eq_.clear();
  ang_.clear();
  impulse_.assign(models.size(), JointImpulse{});
  for (std::size_t i = 0; i < models.size(); ++i)
    rows_for(r, models[i], bodies[i], std::uint32_t(i), h, false);
  assemble(r);
}

void JointSolver::assemble(const RigidBodies& r) {
  const std::size_t n = eq_.size();
  factor_ok_ = false;
  if (n == 0) return;
  touch_.clear();
  for (std::uint32_t i = 0; i < n; ++i) {
    if (moves(r, eq_[i].a)) touch_.emplace_back(eq_[i].a, 2 * i);
    if (moves(r, eq_[i].b)) touch_.emplace_back(eq_[i].b, 2 * i + 1);
  }
  std::sort(touch_.begin(), touch_.end());
  triplets_.clear();
  pattern_.clear();
  double diag = 0.0;
  for (std::size_t s = 0; s < touch_.size();) {
    std::size_t e = s;
    while (e < touch_.size() && touch_[e].first == touch_[s].first) ++e;
    // Every pair of rows acting on this body couples: K_pq += J_p,body · M⁻¹ J_q,bodyᵀ.
    for (std::size_t p = s; p < e; ++p)
      for (std::size_t q = s; q <= p; ++q) {
        const EqRow& rp = eq_[touch_[p].second / 2];
        const EqRow& rq = eq_[touch_[q].second / 2];
        const bool bp = touch_[p].second & 1, bq = touch_[q].second & 1;
        const Vec3& jl = bp ? rp.jb_lin : rp.ja_lin;
        const Vec3& ja = bp ? rp.jb_ang : rp.ja_ang;
        const Vec3& ml = bq ? rq.mb_lin : rq.ma_lin;
        const Vec3& ma = bq ? rq.mb_ang : rq.ma_ang;
        const double v = jl.dot(ml) + ja.dot(ma);
        int row = int(touch_[p].second / 2), col = int(touch_[q].second / 2);
        if (row < col) std::swap(row, col);
        if (row == col) diag += v;
        triplets_.emplace_back(row, col, v);
        pattern_.push_back((std::uint64_t(row) << 32) | std::uint64_t(col));
      }
    s = e;
  }
  // Redundant rows (closed loops of hinges) make K singular: a regularisation far below the
  // solve's round-off keeps LDLᵀ defined without changing a well-posed answer.
  const double eps = 1e-10 * diag / double(n);
  for (std::size_t i = 0; i < n; ++i) triplets_.emplace_back(int(i), int(i), eps);
  if (pattern_ != last_pattern_ || K_.rows() != int(n)) {
    K_.resize(int(n), int(n));
    K_.setFromTriplets(triplets_.begin(), triplets_.end());
    ldlt_.analyzePattern(K_);
    last_pattern_ = pattern_;
    // The value slot of every triplet (the eps diagonal last): found once per pattern.
    slot_.resize(triplets_.size());
    const double* base = K_.valuePtr();
    for (std::size_t k = 0; k < triplets_.size(); ++k)
      slot_[k] = int(&K_.coeffRef(triplets_[k].row(), triplets_[k].col()) - base);
  } else {
    double* values = K_.valuePtr();
    std::fill(values, values + K_.nonZeros(), 0.0);
    for (std::size_t k = 0; k < triplets_.size(); ++k) values[slot_[k]] += triplets_[k].value();
  }
  ldlt_.factorize(K_);
  factor_ok_ = ldlt_.info() == Eigen::Success;
  rhs_.resize(int(n));
  lambda_.resize(int(n));
}

void JointSolver::apply(RigidBodies& r, const Eigen::VectorXd& lambda, bool record) {
  for (std::size_t i = 0; i < eq_.size(); ++i) {
    const EqRow& row = eq_[i];
    const double l = lambda[int(i)];
    if (moves(r, row.a)) {
      r.linear_velocity[row.a] += l * row.ma_lin;
      r.angular_velocity[row.a] += l * row.ma_ang;
    }
    if (moves(r, row.b)) {
      r.linear_velocity[row.b] += l * row.mb_lin;
      r.angular_velocity[row.b] += l * row.mb_ang;
    }
    if (record) {
      if (row.kind < 3)
        impulse_[row.joint].linear += l * row.jb_lin;
      else
        impulse_[row.joint].angular += l * row.jb_ang;
    }
  }
}

void JointSolver::solve_equality(RigidBodies& r) {
  if (!factor_ok_) return;
  for (std::size_t i = 0; i < eq_.size(); ++i) {
    const EqRow& row = eq_[i];
    double jv = 0.0;
    if (row.a != kStaticBody)
      jv += row.ja_lin.dot(linear_velocity(r, row.a)) + row.ja_ang.dot(angular_velocity(r, row.a));
    if (row.b != kStaticBody)
      jv += row.jb_lin.dot(linear_velocity(r, row.b)) + row.jb_ang.dot(angular_velocity(r, row.b));
    rhs_[int(i)] = -jv;
  }
  lambda_ = ldlt_.solve(rhs_);
  apply(r, lambda_, true);
}

void JointSolver::iterate_rows(RigidBodies& r) {
  for (AngRow& row : ang_) {
    const double rel = (angular_velocity(r, row.b) - angular_velocity(r, row.a)).dot(row.d);
    const double delta = -row.mass * (rel - row.target + row.gamma * row.acc);
    const double acc = std::clamp(row.acc + delta, row.lo, row.hi);
    const double applied = acc - row.acc;
    row.acc = acc;
    if (applied == 0.0) continue;
    if (moves(r, row.a)) r.angular_velocity[row.a] -= applied * row.ia_d;
    if (moves(r, row.b)) r.angular_velocity[row.b] += applied * row.ib_d;
    impulse_[row.joint].angular += applied * row.d;
    }
}

void JointSolver::finish(RigidBodies& r) const {
  for (const auto& t : touch_) sync_angular_momentum(r, t.first);
  for (const AngRow& row : ang_) {
    if (moves(r, row.a)) sync_angular_momentum(r, row.a);
    if (moves(r, row.b)) sync_angular_momentum(r, row.b);
  }
}

void JointSolver::project_positions(RigidBodies& r, std::span<const JointModel> models,
                                    std::span<const JointBodies> bodies, double h,
                                    std::span<const std::uint8_t> in_contact, int iterations,
                                    double tolerance) {
  if (eq_.empty() || !factor_ok_) return;
  dx_.resize(r.size());
  dtheta_.resize(r.size());
  moved_x_.resize(r.size());
  moved_theta_.resize(r.size());
  for (const auto& t : touch_) {
    moved_x_[t.first].setZero();
    moved_theta_[t.first].setZero();
  }
  // Position errors C of every row at the current positions into rhs_ (as -C); returns max |C|.
  auto measure = [&]() -> double {
    double worst = 0.0;
    std::uint32_t joint = kStaticBody;
    JointFrame f;
    Quat qerr = Quat::Identity();
    for (std::size_t i = 0; i < eq_.size(); ++i) {
      const EqRow& row = eq_[i];
      if (row.joint != joint) {
        joint = row.joint;
        f = joint_frame(r, models[joint], bodies[joint]);
        if (models[joint].type == JointType::fixed) {
          qerr = f.qb * (f.qa * models[joint].rel0).conjugate();
          if (qerr.w() < 0.0) qerr.coeffs() = -qerr.coeffs();
        }
      }
      double c;
      if (row.kind < 3)
        c = (f.pb - f.pa)[row.kind];
      else if (row.kind < 5)
        c = f.axis_a.cross(f.axis_b).dot(row.jb_ang);
      else
        c = 2.0 * qerr.vec()[row.kind - 5];
      worst = std::max(worst, std::abs(c));
      rhs_[int(i)] = -c;
    }
    return worst;
  };
  // One Newton round; `previous` is the error before the last round (0: none). The step's K is
  // kept while it converges (the error falls tenfold a round: ragdolls, pendulums) and rebuilt
  // at the current positions when it does not — a whipping chain turns its links by tenths of a
  // radian per step, where the old K makes the iteration overshoot, pump energy and blow up.
  // Relinearising always cost ragdolls 2.5x their time.
  auto equality_round = [&](double previous, bool relinearise) -> double {
    double worst = measure();
    if (worst <= tolerance) return worst;
    if (relinearise || (previous > 0.0 && worst > 0.1 * previous)) {
      eq_.clear();
      for (std::size_t i = 0; i < models.size(); ++i)
        rows_for(r, models[i], bodies[i], std::uint32_t(i), h, true);
      assemble(r);  // same rows, same pattern: a numeric refactorisation
      if (!factor_ok_) return 0.0;
      worst = measure();
    }
    lambda_ = ldlt_.solve(rhs_);
    for (const auto& t : touch_) {
      dx_[t.first].setZero();
      dtheta_[t.first].setZero();
    }
    for (std::size_t i = 0; i < eq_.size(); ++i) {
      const EqRow& row = eq_[i];
      const double l = lambda_[int(i)];
      if (moves(r, row.a)) {
        dx_[row.a] += l * row.ma_lin;
        dtheta_[row.a] += l * row.ma_ang;

      }
      if (moves(r, row.b)) {
        dx_[row.b] += l * row.mb_lin;
        dtheta_[row.b] += l * row.mb_ang;

      }
    }
    std::uint32_t last = kStaticBody;
    for (const auto& t : touch_) {
      if (t.first == last) continue;
      last = t.first;
      r.position[last] += dx_[last];
      rotate(r.orientation[last], dtheta_[last]);
      turned(r, last);
      moved_x_[last] += dx_[last];
      moved_theta_[last] += dtheta_[last];
    }
    return worst;
  };
  {
    double previous = 0.0;
    for (int it = 0; it < iterations; ++it) {
      const double worst = equality_round(previous, false);
      if (worst <= tolerance) break;
      previous = worst;
    }
  }
  // Limits: each violated one turned back by the rotation that removes its violation, shared by
  // the bodies in proportion to their inverse inertia (a nonlinear Gauss–Seidel step), then the
  // anchors re-projected.
  // Two rounds: the anchors' projection turns the links again and can reopen a violation
  // (a ragdoll's knee hitting a stair), and one more pass takes it back within a degree.
  for (int round = 0; round < 2; ++round) {
  bool any = false;
  for (std::size_t i = 0; i < models.size(); ++i) {
    const JointModel& m = models[i];
    const JointBodies j = bodies[i];
    if (!m.limit_enabled || (!moves(r, j.a) && !moves(r, j.b))) continue;
    Vec3 d[4];
    double c[4];
    const int n = limits_of(m, joint_frame(r, m, j), d, c);
    for (int k = 0; k < n; ++k) {
      if (c[k] >= 0.0) continue;
      const Vec3 ia = moves(r, j.a) ? Vec3(r.inv_inertia_world[j.a] * d[k]) : Vec3::Zero();
      const Vec3 ib = moves(r, j.b) ? Vec3(r.inv_inertia_world[j.b] * d[k]) : Vec3::Zero();
      const double kk = d[k].dot(ia) + d[k].dot(ib);
      if (kk <= 0.0) continue;
      const double p = -c[k] / kk;
      if (moves(r, j.a)) {
        rotate(r.orientation[j.a], -p * ia);
        turned(r, j.a);
        moved_theta_[j.a] -= p * ia;
      }
      if (moves(r, j.b)) {
        rotate(r.orientation[j.b], p * ib);
        turned(r, j.b);
        moved_theta_[j.b] += p * ib;
      }
      any = true;
    }
  }
  if (!any) break;
  double previous = 0.0;
  for (int it = 0; it < iterations; ++it) {
    const double worst = equality_round(previous, false);
    if (worst <= tolerance) break;
    previous = worst;
  }
  }
  // The projection's displacement becomes velocity (RATTLE / SHAKE: the position constraint's
  // multipliers act as impulses over the step), so the velocities are the chord of the
  // constrained motion. Without this the next step's velocity solve strips the normal part of
  // the motion the projection took away and the articulation bleeds energy at O(h ω²).
  if (!in_contact.empty()) {
    std::uint32_t last = kStaticBody;
    for (const auto& t : touch_) {
      if (t.first == last) continue;
      last = t.first;
      if (in_contact[last]) continue;
      r.linear_velocity[last] += moved_x_[last] / h;
      // As an angular impulse on L (then ω = I_w⁻¹ L at the final orientation): the impulses
      // (r × d) λ are normal to a link's long axis, so a thin link gets no spin from them; adding
      // Δθ/h to ω instead would turn orientation round-off into spin about the axis of least
      // inertia, which the momentum form then amplifies step after step.
      r.angular_velocity[last] += moved_theta_[last] / h;
      sync_angular_momentum(r, last);
    }
  }
}

void JointSolver::stiffen_inertia(RigidBodies& r, std::span<const JointModel> models,
                                  std::span<const JointBodies> bodies,
                                  std::span<const double> force_n, double h) {
  assert(models.size() == bodies.size() && force_n.size() == models.size());
  saved_inertia_.clear();
  // x0 = (ω h)² on this estimate: below 0.1 (ω h < 0.3) the step resolves the rotation and
  // nothing is added, so articulations that were stable keep their bits.
  constexpr double kResolved = 0.1;
  stiffness_.resize(r.size());
  for (std::size_t i = 0; i < models.size(); ++i) {
    const JointBodies j = bodies[i];
    if (j.a != kStaticBody) stiffness_[j.a] = 0.0;
    if (j.b != kStaticBody) stiffness_[j.b] = 0.0;
  }
  bool any = false;
  for (std::size_t i = 0; i < models.size(); ++i) {
    const double f = force_n[i];
    const JointBodies j = bodies[i];
    if (!(f > 0.0) || (!moves(r, j.a) && !moves(r, j.b))) continue;
    const JointFrame fr = joint_frame(r, models[i], j);
    if (moves(r, j.a)) stiffness_[j.a] += f * fr.ra.norm();
    if (moves(r, j.b)) stiffness_[j.b] += f * fr.rb.norm();
    any = true;
  }
  if (!any) return;
  const auto stiffen = [&](std::uint32_t b) {
    const double hk = h * h * stiffness_[b];
    stiffness_[b] = 0.0;  // each body once
    if (!(hk > 0.0)) return;
    Eigen::SelfAdjointEigenSolver<Mat3> eig;
    eig.computeDirect(r.inertia_body[b], Eigen::EigenvaluesOnly);
    const double x = hk / eig.eigenvalues()(0);
    if (!(x > kResolved)) return;
    const double added = hk * (x - kResolved) / (1.0 + x);
    saved_inertia_.emplace_back(b, r.inv_inertia_world[b]);
    const Mat3 R = r.orientation[b].toRotationMatrix();
    const Mat3 inv = (r.inertia_body[b] + added * Mat3::Identity()).inverse();
    r.inv_inertia_world[b] = R * inv * R.transpose();
  };
  for (std::size_t i = 0; i < models.size(); ++i) {
    const JointBodies j = bodies[i];
    if (moves(r, j.a)) stiffen(j.a);
    if (moves(r, j.b)) stiffen(j.b);
  }
}

void JointSolver::restore_inertia(RigidBodies& r) {
  for (const auto& [b, inv] : saved_inertia_) r.inv_inertia_world[b] = inv;
  saved_inertia_.clear();
}

}  // namespace simreel::sim::detail
