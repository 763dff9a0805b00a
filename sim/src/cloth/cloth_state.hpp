#pragma once
// The per-instance state of a Cloth (private to cloth/): positions, velocities, pins and the
// workspaces of the implicit solver and the maximum-deformation pass (Coutinho §3.9.2). The
// topology (ClothTopology) is the shared model; this is the state.

#include <cstdint>
#include <memory>
#include <vector>

#include "cloth/cloth_collide.hpp"
#include "cloth/cloth_contacts.hpp"
#include "cloth/coarse_space.hpp"
#include "cloth/spring_stencil.hpp"
#include "cloth/sym3.hpp"
#include "simreel/sim/cloth.hpp"

namespace simreel::sim {

using detail::Sym3;

struct Cloth::State {
  ClothDef def;
  std::shared_ptr<const ClothTopology> topo;
  std::uint64_t noise_key = 0;
  std::size_t n = 0;
  double vertex_mass = 0.0;
  std::vector<Vec3> x, v;            // current state
  std::vector<Vec3> x_start;         // start of the step (the paths of the §3.9.2 pass begin here)
  std::vector<Vec3> f;               // force accumulator
  std::vector<std::uint8_t> free;    // 0 for pinned vertices
  std::vector<int> pin_of;           // index into def.pins or -1
  std::vector<Vec3> pin_rest;        // fixed pins: initial world position
  // Implicit Euler workspace (n or spring_count entries; allocated once).
  std::vector<double> ks, kds;       // per spring: k_s, k_d of its family
  // Per spring (the spring-by-spring loops of a mesh cloth; a grid cloth keeps these in the
  // stencil and copies out only listed_springs' length and block): current length (m) and unit
  // direction a -> b, set by forces(); the h k_d nnᵀ + h² ∂f/∂x block, set by the implicit step.
  std::vector<double> spring_length;
  std::vector<Vec3> spring_dir;
  std::vector<Sym3> S;
  std::vector<Sym3> aero_damping;    // per vertex: -∂f_aero/∂v, lumped (implicit Euler only)
  std::vector<std::uint32_t> pinned;  // pinned vertex indices
  bool aero_active = false;
  std::vector<Vec3> dv;              // Δv of the last implicit step (the next one's warm start)
  // The CG's vectors (solution, residual, preconditioned residual, direction, product, right-hand
  // side); the inverse diagonal blocks and each vertex's own block m' I + h aero (2 x 6 arrays
  // xx xy xz yy yz zz), in the stencil's layout; 1/0 per free/pinned vertex. Sized at the first
  // implicit step.
  std::vector<double> cg_vectors, cg_precond, free_mask;
  // x, v and f as structures of arrays in the stencil's layout (3 vectors), for the stencil's
  // spring loops (grid cloths) and the aerodynamic kernel; sized at construction.
  std::vector<double> soa;
  // Aerodynamics workspace (aero.hpp): a grid cloth's (aero_grid: 31 arrays in the stencil's
  // layout: the wind at both triangles of each cell, the cells' mask, their terms, the damping
  // blocks), or a mesh cloth's (12 arrays of one per triangle: wind, force, damping block).
  std::vector<double> aero_work;
  bool aero_grid = false;
  // Springs whose block and length the coarse level and the pinned columns read one by one
  // (stencil path: copied into S and spring_length after the blocks are made).
  std::vector<std::uint32_t> listed_springs;
  std::vector<Vec3> spring_work;     // per spring: force (forces()), h² K Δv0 or S y (implicit)
  std::vector<double> vertex_work, vertex_work2;  // per vertex: terms of the CG sums
  detail::CoarseSpace coarse;        // the CG's coarse level, built at the first implicit step
  detail::SpringStencil stencil;     // springs as a stencil (grid cloths) and the CG's layout
  bool coarse_built = false;         // coarse and cg_* are set at the first implicit step
  /// OpenMP threads for the spring and vertex loops (WorldDef::threads); every loop writes only
  /// its own element and every sum runs in index order, so any count gives the same bits.
  int threads = 1;
  [[nodiscard]] bool parallel() const { return threads > 1 && n >= kParallelVertices; }
  static constexpr std::size_t kParallelVertices = 2048;
  // Maximum-deformation pass workspace.
  std::vector<double> t, t_next;
  std::vector<std::int32_t> changed_in;  // per vertex: last pass that changed its t (-1: none)
  std::vector<Vec3> origin, path;
  std::vector<std::uint8_t> hit;     // per vertex: 1 touched a collider this step, 2 a kinematic one
  std::vector<std::uint8_t> held;    // per vertex: the pass does not move it (pinned or hit == 2)
  std::vector<Vec3> pushed_normal;   // per vertex with hit == 2: the kinematic body's outward normal
  detail::BodyContacts body_contacts;  // per vertex: last dynamic-body contact (pinned cloth only)
  std::vector<Vec3> nacc;            // vertex normal accumulator
  // Float copies for views.
  std::vector<float> fpos, fnor, fvel;
  std::size_t cg_iterations = 0, strain_passes = 0;
  detail::ContactScratch contact_scratch;  // triangle and edge contacts (cloth_contacts.hpp)
  std::vector<detail::ContactCloth> contact_views;
  detail::ContactStats contact_stats;      // of the last step's collider-feature pass

  [[nodiscard]] detail::ContactCloth contact_view() {
    return {&x, &v, &x_start, &free, topo.get(), vertex_mass, def.thickness, def.friction,
            def.self_collision, def.collide_cloths, &hit, &pushed_normal};
  }

  [[nodiscard]] double k_of(std::size_t s) const {
    switch (topo->kind[s]) {
      case SpringKind::stretch: return def.stretch.stiffness;
      case SpringKind::shear: return def.shear.stiffness;
      case SpringKind::bend: return def.bend.stiffness;
    }
    return 0.0;
  }
  [[nodiscard]] double kd_of(std::size_t s) const {
    switch (topo->kind[s]) {
      case SpringKind::stretch: return def.stretch.damping;
      case SpringKind::shear: return def.shear.damping;
      case SpringKind::bend: return def.bend.damping;
    }
    return 0.0;
  }
  [[nodiscard]] Vec3 pin_target(std::size_t i, double t1) const {
    const ClothPin& pin = def.pins[std::size_t(pin_of[i])];
    return pin.path.empty() ? pin_rest[i] : pin.path.sample(t1).translation;
  }

  void forces(double t);
  void integrate_implicit(double h, double t1);
  void integrate_explicit(double h, double t1, bool semi);
  /// Returns true if it moved a vertex; adds its passes to strain_passes.
  bool max_deformation_pass();
  /// Brings the pass's start positions (origin) within `scale` × rest length (Provot 1995).
  bool project_origin(double scale);
  double step_h = 0.0;  ///< (s) the current step, set by Cloth::step
  void refresh_views();
  Vec3 wind(const Vec3& p, double t) const;
};

}  // namespace simreel::sim
