#pragma once
// The resting-on-a-plane fast path of the particle collision pass (private to collision/):
// particles lying on the one ground plane of a scene, resolved lane by lane in a loop the
// compiler vectorises, with the arithmetic of the general slow path (resolve() in
// particle_response.cpp) in float lanes, relative to the plane's point (the sweep's distances and
// time of impact in double), so the results are the slow path's to a few roundings of a float
// (tests/sim/test_plane_rest.cpp; docs/benchmarks.md, issue 19 at stop 89). Coutinho §3.4 (the
// swept sphere against the plane), §3.6.1 (Coulomb friction with the critical coefficient),
// §3.6.3 (resting contact: the normal velocity and acceleration cancelled, friction on their
// impulse).

#include <cstddef>
#include <cstdint>

namespace simreel::sim::detail {

/// Lanes of one batch of PlaneRest.
inline constexpr std::size_t kPlaneRestLanes = 256;

/// Input and output lanes (structure of arrays) of plane_rest(): one particle per lane.
struct PlaneRestLanes {
  // in: end-of-step position (m) and velocity (m/s) as integrated and stored (floats), mass (kg),
  // radius (m), the particle's step dt = min(age, h) (s), and, for integrators that store it,
  // the start-of-step position (m)
  float bx[kPlaneRestLanes], by[kPlaneRestLanes], bz[kPlaneRestLanes];
  float vx[kPlaneRestLanes], vy[kPlaneRestLanes], vz[kPlaneRestLanes];
  float ax[kPlaneRestLanes], ay[kPlaneRestLanes], az[kPlaneRestLanes];
  double m[kPlaneRestLanes], r[kPlaneRestLanes], dt[kPlaneRestLanes];
  // out: position and velocity after the contact, rounded to float as they are stored (the
  // input, exactly, where ok is 0)
  float ox[kPlaneRestLanes], oy[kPlaneRestLanes], oz[kPlaneRestLanes];
  float ovx[kPlaneRestLanes], ovy[kPlaneRestLanes], ovz[kPlaneRestLanes];
  /// The lane's verdict. 0: anything but a resting contact (no contact, an impact that bounces, a
  /// second contact within the step, a non-finite value): the caller runs the general path
  /// instead. 1: the particle touched the plane this step in a resting contact (§3.6.3), the
  /// outputs hold its result, and the sphere at the output position as stored (floats) clears
  /// the plane. 2: the same, but rounding put the stored centre a hair inside (its gap, in
  /// double, not >= 0): the caller steps it out as the general path does. (One float for both
  /// answers, so that a settled block is checked on one array.)
  float ok[kPlaneRestLanes];
  /// Input: true when every lane's m, r and dt are lane 0's, bit for bit, and only lane 0 of them
  /// need be filled (gather_block() sets it when it finds the block's stored floats so); false:
  /// each lane holds its own, and plane_rest() checks whether they are shared.
  bool shared = false;
};

/// The plane, its material and the system's forces, as plane_rest() needs them.
struct PlaneRestParams {
  double n[3];          ///< unit normal
  double q[3];          ///< a point of the plane (m)
  double g[3];          ///< gravity (m/s²)
  double drag;          ///< k_d (kg/s)
  double drag_quadratic;  ///< c_2 (kg/m)
  double mu, mu_static;   ///< dynamic and static Coulomb coefficients
  double contact_speed;   ///< (m/s) the §3.6.3 threshold
  bool start_stored;      ///< the ax/ay/az lanes hold the start of the step (else recovered)
};

/// Resolves lanes [0, count) of `l` (count <= kPlaneRestLanes) against the plane `p`. Where
/// `l.shared`, reads m, r and dt from lane 0 alone. `origin_form`: an upright plane through
/// z = +0 takes the loop that drops the arithmetic around the plane's point (the same bits;
/// false, for tests, runs the general upright loop instead).
void plane_rest(PlaneRestLanes& l, std::size_t count, const PlaneRestParams& p,
                bool origin_form = true);

}  // namespace simreel::sim::detail
