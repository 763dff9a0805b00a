#pragma once
// Cloth vertices against the world's colliders (private). Coutinho §3.9.2: cloth collisions
// "follow the same principles" as particles (§3.4); a vertex is a point kept `thickness` away from
// every collider surface.

#include <cstdint>
#include <vector>

#include "collision/body_impulses.hpp"
#include "collision/collider_impl.hpp"
#include "simreel/sim/types.hpp"

namespace simreel::sim::detail {

/// Projects every vertex with free[i] != 0 that ends the step closer than `thickness` to a
/// collider's surface (or inside it) back onto the surface grown by `thickness`, through the face
/// its path x_start -> x entered by (the nearest face if it started inside). Its velocity relative
/// to the collider loses the normal component pointing in (perfectly inelastic: cloth does not
/// bounce) and the tangential part is reduced by friction × the normal speed removed (Coulomb,
/// §3.6.1), to zero at most. `hit[i]` is set to 1 for every vertex touched,
/// 2 for one touched by a kinematic body's shape (kept at 2 for the rest of the step), whose
/// outward normal then goes to `pushed_normal[i]` when given.
/// With `impulses`, each response against a dynamic body's shape logs the vertex's momentum
/// change vertex_mass (v_before - v_after) (N s) on the body at the contact (§3.7, two-way).
/// A switch on the collider kind: plane, box, and (swept, see cloth_collide.cpp) sphere,
/// cylinder, capsule and triangle mesh, static or kinematic.
/// With `body_contacts` (and `impulses`), each vertex's last contact with a dynamic body's shape
/// this step is recorded there (for hold_dynamic_bodies).
struct BodyContacts;
void collide_cloth(std::vector<Vec3>& x, std::vector<Vec3>& v, const std::vector<Vec3>& x_start,
                   const std::vector<std::uint8_t>& free, const std::vector<Collider>& colliders,
                   double thickness, double friction, std::vector<std::uint8_t>& hit,
                   double vertex_mass = 0.0, BodyImpulses* impulses = nullptr,
                   std::vector<Vec3>* pushed_normal = nullptr, BodyContacts* body_contacts = nullptr);

/// Per vertex, its last contact this step with a shape of a dynamic body: the shape (index into
/// the colliders, BodyImpulses::kNone if none), where the vertex was put (on the surface grown
/// by the thickness) and the shape's outward normal there. Workspace, allocated once.
struct BodyContacts {
  std::vector<std::uint32_t> shape;
  std::vector<Vec3> point, normal;
  /// Rows of the hold (hold_dynamic_bodies), reused from step to step.
  struct Row {
    std::uint32_t shape, rigid;
    Vec3 point, normal;   ///< (m) body surface point, outward unit normal; world
    double target = 0.0;  ///< (m/s) the largest normal speed the body may have there
    double m_eff = 0.0;   ///< (kg) 1 / (1/m + (r × n)ᵀ I⁻¹ (r × n))
    double lambda = 0.0;  ///< (N s) accumulated impulse on the body along -normal
    double depth = 0.0;   ///< (m) how far the vertex is inside the grown surface
  };
  struct Push {
    Vec3 direction;  ///< Σ depth (-normal) over the body's rows
    double depth_sum, depth_max;
    std::uint32_t shape;  ///< a shape of the body (to log on)
  };
  std::vector<Push> push;                   ///< per slot
  std::vector<Row> rows;
  std::vector<std::int32_t> slot;           ///< per rigid index: its entry in vel/omega, or -1
  std::vector<Vec3> vel, omega;             ///< the held bodies' velocities during the solve
  std::vector<std::uint32_t> held_bodies;   ///< rigid index per slot
  void reset(std::size_t n) {
    shape.assign(n, 0xffffffffu);
    point.resize(n);
    normal.resize(n);
  }
};

/// Issue 16: a pinned sheet holds a dynamic body that lands in it, however heavy or fast. The
/// vertex pass responds to a body as if it were immovable and hands it only the vertices' own
/// momentum (§3.7), and the maximum-deformation pass then pulls the vertices under the body back
/// towards the pins, into the body: the tension of the taut sheet never reached the body, and a
/// body much heavier than the sheet went through it. Here every vertex that the final pass left
/// more than a hair inside the grown surface of the dynamic body it last touched (depth d along
/// the recorded outward normal n) holds the body: the body's velocity at the surface point p
/// must not approach the vertex, w(p)·n <= max(v_i·n, 0) (a vertex moving into the body weighs
/// next to nothing and does not throw it; every target >= 0, so w = 0 always satisfies all rows
/// and the solve cannot ask for two speeds at once). The impulses λ >= 0 along -n are solved by
/// projected Gauss–Seidel over all such rows together (sequential impulses, Catto 2005, with the
/// body's effective mass 1 / (1/m + (r × n)ᵀ I_w⁻¹ (r × n)) at p), starting from the velocity the
/// bodies stage will start from: the body's, plus its gravity over the step and this step's
/// impulses already logged. The overlap is then undone by giving the body's centre at least the
/// speed min(β d_max / h, 0.2 m/s) |Σ d (-n)| / Σ d along Σ d (-n) (β = 0.1, Baumgarte
/// stabilisation with Box2D's cap on the push speed; pushes from opposite sides cancel).
/// The impulses are logged on the bodies like any other impulse. A sleeping body is
/// held as the awake body it becomes. Only a cloth with pinned vertices holds a body this way:
/// only pins can take the momentum (a free sheet is carried along). Vertices and rows are
/// visited in index order (deterministic). h is the step (s).
void hold_dynamic_bodies(const std::vector<Vec3>& x, const std::vector<Vec3>& v,
                         const std::vector<std::uint8_t>& free, double thickness, double h,
                         BodyContacts& contacts, BodyImpulses& impulses);

}  // namespace simreel::sim::detail
