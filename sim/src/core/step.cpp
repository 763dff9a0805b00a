// World::advance: the internal steps, each running the stage table (stages.hpp), then the report
// of moved and removed objects (Coutinho §1.4.1).
#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include "core/stages.hpp"
#include "core/world_impl.hpp"
#include "simreel/sim/ranges.hpp"

namespace simreel::sim {

namespace {

/// Relative slack when splitting a sampling time into steps, so T/max_step = 2.0000000001 from
/// rounding takes 2 steps, not 3.
constexpr double kStepSlack = 1e-9;

void step(detail::WorldState& w, double t0, double t1) {
  for (const detail::Stage& stage : detail::kStages) stage.run(w, t0, t1);
  ++w.steps;
}

/// The moved list: kinematic and dynamic bodies whose pose changed since the last report, once each whatever
/// their shape count (dense order, which is registration order until a removal), then the
/// removals since the last advance().
void report(detail::WorldState& w) {
  w.moved.clear();
  std::vector<detail::Body>& bodies = w.bodies.dense();
  for (std::size_t i = 0; i < bodies.size(); ++i) {
    detail::Body& b = bodies[i];
    if (!b.kinematic() && !b.dynamic()) continue;
    const Quat q = b.pose.rotation.normalized();
    if (b.pose.translation == b.reported_translation &&
        q.coeffs() == b.reported_rotation.coeffs())
      continue;
    b.reported_translation = b.pose.translation;
    b.reported_rotation = q;
    MovedObject m = b.report_pose(w.shapes);
    m.handle = w.bodies.handle(i);
    w.moved.push_back(m);
  }
  for (const Handle& h : w.removed) {
    MovedObject m;
    m.handle = h;
    m.removed = true;
    w.moved.push_back(m);
  }
  w.removed.clear();
}

}  // namespace

const std::vector<MovedObject>& World::advance(double sampling_time) {
  Impl& w = *impl_;
  if (!(sampling_time > 0.0) || !std::isfinite(sampling_time)) {
    std::ostringstream m;
    m << "World::advance: sampling_time must be > 0 and finite (got " << sampling_time << ")";
    throw std::invalid_argument(m.str());
  }
  const double ratio = sampling_time / w.def.max_step;
  // Checked before the cast: a ratio beyond the cap (or +inf) must never reach an integer.
  if (!(ratio <= double(ranges::kMaxStepsPerAdvance) * (1.0 + kStepSlack))) {
    std::ostringstream m;
    m << "World::advance: sampling_time / max_step = " << sampling_time << " s / " << w.def.max_step
      << " s needs more than " << ranges::kMaxStepsPerAdvance
      << " internal steps per advance (raise max_step or shorten the sampling time)";
    throw std::invalid_argument(m.str());
  }
  const std::uint64_t n = std::max<std::uint64_t>(
      1, std::uint64_t(std::ceil(ratio - kStepSlack * std::max(1.0, ratio))));
  const double h = sampling_time / double(n);
  const double start = w.time;
  for (std::uint64_t i = 0; i < n; ++i) {
    const double t0 = start + double(i) * h;
    const double t1 = i + 1 == n ? start + sampling_time : start + double(i + 1) * h;
    step(w, t0, t1);
    w.time = t1;
  }
  report(w);
  return w.moved;
}

}  // namespace simreel::sim
