// Mass-spring cloth (Coutinho §3.9.2) with implicit Euler after Baraff & Witkin 1998 (Coutinho
// Appendix B, the implicit Euler method for stiff systems) and the maximum-deformation pass.
#include "simreel/sim/cloth.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>

#include "cloth/cloth_collide.hpp"
#include "cloth/cloth_state.hpp"
#include "cloth/gust_noise.hpp"
#include "core/state_io.hpp"
#include "core/validate.hpp"

namespace simreel::sim {

using detail::mix;

constexpr int kFeatureRounds = 3;  // feature contacts -> vertex pass -> strain limit, at most

namespace {

[[noreturn]] void bad(const std::string& field, const std::string& expected, double got) {
  std::ostringstream m;
  m << "ClothDef." << field << " must be " << expected << " (got " << got << ")";
  throw std::invalid_argument(m.str());
}

void validate(const ClothDef& d) {
  if (d.mesh.empty()) {
    require_in((long long)d.rows, ranges::kClothGrid, "ClothDef.rows");
    require_in((long long)d.columns, ranges::kClothGrid, "ClothDef.columns");
    if (d.rows * d.columns < 2) bad("rows * columns", ">= 2", double(d.rows * d.columns));
    require_in(d.width, ranges::kClothSize, "ClothDef.width");
    require_in(d.height, ranges::kClothSize, "ClothDef.height");
  }
  require_in(d.mass, ranges::kClothMass, "ClothDef.mass");
  if (!d.transform.translation.allFinite() || !d.transform.rotation.coeffs().allFinite() ||
      d.transform.rotation.norm() == 0.0)
    throw std::invalid_argument("ClothDef.transform must be finite with a non-zero rotation");
  for (std::size_t i = 0; i < d.pins.size(); ++i) {
    const ClothPin& p = d.pins[i];
    if (p.row >= d.rows || p.column >= d.columns) {
      std::ostringstream m;
      if (!d.mesh.empty())
        m << "ClothDef.pins[" << i << "] names vertex " << p.column << " (row " << p.row
          << ") of a mesh cloth with " << d.columns << " vertices";
      else
        m << "ClothDef.pins[" << i << "] (row " << p.row << ", column " << p.column
          << ") is outside the " << d.rows << " x " << d.columns << " grid";
      throw std::invalid_argument(m.str());
    }
    detail::validate(p.path, "ClothDef.pins[" + std::to_string(i) + "].path");
  }
  require_in(d.stretch.stiffness, ranges::kClothStiffness, "ClothDef.stretch.stiffness");
  require_in(d.stretch.damping, ranges::kClothSpringDamping, "ClothDef.stretch.damping");
  require_in(d.shear.stiffness, ranges::kClothStiffness, "ClothDef.shear.stiffness");
  require_in(d.shear.damping, ranges::kClothSpringDamping, "ClothDef.shear.damping");
  require_in(d.bend.stiffness, ranges::kClothStiffness, "ClothDef.bend.stiffness");
  require_in(d.bend.damping, ranges::kClothSpringDamping, "ClothDef.bend.damping");
  require_in(d.max_strain, ranges::kClothMaxStrain, "ClothDef.max_strain");
  if (!d.gravity.allFinite()) throw std::invalid_argument("ClothDef.gravity must be finite");
  require_in(d.damping, ranges::kClothDamping, "ClothDef.damping");
  if (!d.wind.velocity.allFinite()) throw std::invalid_argument("ClothDef.wind.velocity must be finite");
  require_in(d.wind.gust_amplitude, ranges::kClothGustAmplitude, "ClothDef.wind.gust_amplitude");
  require_in(d.wind.gust_frequency, ranges::kClothGustFrequency, "ClothDef.wind.gust_frequency");
  require_in(d.aero.drag_coefficient, ranges::kClothAero, "ClothDef.aero.drag_coefficient");
  require_in(d.aero.lift_coefficient, ranges::kClothAero, "ClothDef.aero.lift_coefficient");
  require_in(d.aero.air_density, ranges::kClothAero, "ClothDef.aero.air_density");
  require_in(d.thickness, ranges::kClothThickness, "ClothDef.thickness");
  require_in(d.friction, ranges::kClothFriction, "ClothDef.friction");
  require_in(d.restitution, ranges::kClothRestitution, "ClothDef.restitution");
  if (!(d.cg_tolerance > 0.0) || !std::isfinite(d.cg_tolerance))
    bad("cg_tolerance", "> 0 and finite", d.cg_tolerance);
  if (d.cg_max_iterations < 1) bad("cg_max_iterations", ">= 1", double(d.cg_max_iterations));
}

}  // namespace

void Cloth::State::refresh_views() {
  const ClothTopology& T = *topo;
  std::fill(nacc.begin(), nacc.end(), Vec3::Zero());
  for (std::size_t k = 0; k + 2 < T.triangles.size(); k += 3) {
    const std::uint32_t i0 = T.triangles[k], i1 = T.triangles[k + 1], i2 = T.triangles[k + 2];
    const Vec3 c = (x[i1] - x[i0]).cross(x[i2] - x[i0]);
    nacc[i0] += c;
    nacc[i1] += c;
    nacc[i2] += c;
  }
  const Vec3 fallback = def.transform.rotation.normalized() * Vec3::UnitZ();
  for (std::size_t i = 0; i < n; ++i) {
    const double len = nacc[i].norm();
    const Vec3 nn = len > 0.0 ? Vec3(nacc[i] / len) : fallback;
    for (int k = 0; k < 3; ++k) {
      fpos[3 * i + std::size_t(k)] = float(x[i][k]);
      fvel[3 * i + std::size_t(k)] = float(v[i][k]);
      fnor[3 * i + std::size_t(k)] = float(nn[k]);
    }
  }
}

// ---------------------------------------------------------------------------------------------
// Cloth

Cloth::Cloth(const ClothDef& def, std::uint64_t seed, std::uint64_t index)
    : Cloth(def, nullptr, seed, index) {}

Cloth::Cloth(const ClothDef& def, std::shared_ptr<const ClothTopology> topology,
             std::uint64_t seed, std::uint64_t index)
    : s_(std::make_unique<State>()) {
  State& S = *s_;
  S.def = def;
  if (!def.mesh.empty()) {  // a mesh cloth: one row of vertices (see ClothDef::mesh)
    S.def.rows = 1;
    S.def.columns = def.mesh.vertices.size();
  }
  validate(S.def);
  S.def.transform.rotation.normalize();
  if (!topology)
    topology = def.mesh.empty() ? std::make_shared<const ClothTopology>(def.rows, def.columns,
                                                                         def.width, def.height)
                                : std::make_shared<const ClothTopology>(def.mesh);
  if (def.mesh.empty() != !topology->from_mesh || topology->rows != S.def.rows ||
      topology->columns != S.def.columns ||
      (def.mesh.empty() && (topology->width != def.width || topology->height != def.height)))
    throw std::invalid_argument("Cloth: the shared topology does not match the ClothDef grid");
  S.topo = std::move(topology);
  S.noise_key = mix(seed ^ mix(index + 0x636c6f7468ULL));  // "cloth"
  S.n = S.def.rows * S.def.columns;
  const std::size_t n = S.n, ns = S.topo->spring_count();
  S.vertex_mass = def.mass / double(n);
  S.x.resize(n);
  for (std::size_t i = 0; i < n; ++i)
    S.x[i] = S.def.transform.rotation * S.topo->local_rest[i] + S.def.transform.translation;
  S.v.assign(n, Vec3::Zero());
  S.x_start = S.x;
  S.f.assign(n, Vec3::Zero());
  S.free.assign(n, 1);
  S.pin_of.assign(n, -1);
  S.pin_rest.assign(n, Vec3::Zero());
  for (std::size_t k = 0; k < def.pins.size(); ++k) {
    const std::size_t i = def.pins[k].row * S.def.columns + def.pins[k].column;
    S.free[i] = 0;
    S.pin_of[i] = int(k);
    S.pin_rest[i] = S.x[i];
    if (!def.pins[k].path.empty()) S.x[i] = def.pins[k].path.sample(0.0).translation;
  }
  S.S.assign(ns, Sym3{});
  S.ks.resize(ns);
  S.kds.resize(ns);
  for (std::size_t s = 0; s < ns; ++s) {
    S.ks[s] = S.k_of(s);
    S.kds[s] = S.kd_of(s);
  }
  S.stencil.build(*S.topo, S.ks, S.kds);
  S.soa.assign(3 * 3 * S.stencil.stride(), 0.0);
  S.spring_length.assign(ns, 0.0);
  S.spring_work.assign(ns, Vec3::Zero());
  S.vertex_work.assign(n, 0.0);
  S.vertex_work2.assign(n, 0.0);
  S.spring_dir.assign(ns, Vec3::Zero());
  for (std::size_t i = 0; i < n; ++i)
    if (!S.free[i]) S.pinned.push_back(std::uint32_t(i));
  S.aero_active = def.aero.air_density > 0.0 &&
                  (def.aero.drag_coefficient > 0.0 || def.aero.lift_coefficient > 0.0);
  S.aero_damping.assign(S.aero_active ? n : 0, Sym3{});
  const ClothTopology& T = *S.topo;
  S.aero_grid = S.aero_active && !T.from_mesh && T.rows >= 2 && T.columns >= 2 &&
                !S.stencil.empty() && S.stencil.pad() >= T.columns + 1;
  if (S.aero_grid) {
    const std::size_t st = S.stencil.stride();
    S.aero_work.assign(31 * st, 0.0);
    double* cells = S.aero_work.data() + S.stencil.pad() + 6 * st;
    for (std::size_t r = 0; r + 1 < T.rows; ++r)
      for (std::size_t c = 0; c + 1 < T.columns; ++c) cells[r * T.columns + c] = 1.0;
  } else {
    S.aero_work.assign(S.aero_active ? 12 * (T.triangles.size() / 3) : 0, 0.0);
  }
  for (auto* w : {&S.dv, &S.origin, &S.path, &S.nacc})
    w->assign(n, Vec3::Zero());
  S.t.assign(n, 1.0);
  S.t_next.assign(n, 1.0);
  S.changed_in.assign(n, -1);
  S.hit.assign(n, 0);
  S.held.assign(n, 0);
  S.pushed_normal.assign(n, Vec3::Zero());
  S.fpos.assign(3 * n, 0.0f);
  S.fnor.assign(3 * n, 0.0f);
  S.fvel.assign(3 * n, 0.0f);
  S.refresh_views();
}

Cloth::~Cloth() = default;
Cloth::Cloth(Cloth&&) noexcept = default;
Cloth& Cloth::operator=(Cloth&&) noexcept = default;

bool Cloth::step(double t0, double t1, const std::vector<detail::Collider>* colliders,
                 detail::BodyImpulses* impulses, int threads) {
  State& S = *s_;
  S.threads = std::max(1, threads);
  const double h = t1 - t0;
  S.step_h = h;
  S.x_start = S.x;
  S.forces(t0);
  switch (S.def.integrator) {
    case ClothIntegrator::implicit_euler: S.integrate_implicit(h, t1); break;
    case ClothIntegrator::semi_implicit_euler: S.integrate_explicit(h, t1, true); break;
    case ClothIntegrator::explicit_euler: S.integrate_explicit(h, t1, false); break;
  }
  const bool collide = S.def.collide && colliders != nullptr && !colliders->empty();
  // Only pins can take a body's momentum: a pinned cloth holds a dynamic body that lands in it
  // (hold_dynamic_bodies); a free one is carried along.
  detail::BodyContacts* held_bodies =
      collide && impulses != nullptr && !S.pinned.empty() ? &S.body_contacts : nullptr;
  if (held_bodies != nullptr) held_bodies->reset(S.n);
  if (collide) {
    std::fill(S.hit.begin(), S.hit.end(), std::uint8_t(0));
    detail::collide_cloth(S.x, S.v, S.x_start, S.free, *colliders, S.def.thickness,
                          S.def.friction, S.hit, S.vertex_mass, impulses, &S.pushed_normal,
                          held_bodies);
  }
  S.strain_passes = 0;
  S.max_deformation_pass();
  S.contact_stats = {};
  if (collide) {
    // Triangles and edges against collider corners, edges and axes (cloth_contacts.hpp); a
    // correction is followed by the vertex pass and the maximum-deformation pass again, so the
    // step ends within the strain limit and clear of the colliders when both can hold (a few
    // rounds). A vertex a kinematic body pushed is held by the pass (max_deformation.cpp): the
    // sheet around it follows, and when the sheet cannot (pinned elsewhere) the body wins and
    // the sheet stretches; nothing passes through it. Against static colliders and dynamic
    // bodies the strain limit has the last word; a pinned sheet's vertices that it pulled back
    // into a dynamic body then hold the body (hold_dynamic_bodies, below).
    S.contact_views.assign(1, S.contact_view());
    S.contact_views[0].self = S.contact_views[0].others = false;
    S.contact_scratch.rebuild = true;  // the contact tree: built once this step, then refitted
    for (int round = 0; round <= kFeatureRounds; ++round) {
      // These rounds undo the strain pass's pull back into the colliders. What a dynamic body
      // takes is logged once: the first vertex pass (the vertices' own momentum against it) and
      // the first round's feature contacts. Logging every round's push handed the body the same
      // correction once per round: a light body resting on a pinned sheet was thrown off it, and
      // the capsule of the cloth_pile demo, squeezed between a free sheet and the ground, was
      // spun up to 200 rad/s and on until the simulation diverged. On a pinned sheet no round
      // logs: hold_dynamic_bodies hands the tension over once, as the impulse that stops the
      // body.
      if (impulses != nullptr) impulses->muted = held_bodies != nullptr || round > 0;
      const detail::ContactStats st = detail::collide_cloth_features(
          S.contact_views, colliders, false, h, S.contact_scratch, impulses);
      S.contact_stats.contacts += st.contacts;
      if (st.contacts == 0) break;
      if (impulses != nullptr) impulses->muted = true;
      detail::collide_cloth(S.x, S.v, S.x_start, S.free, *colliders, S.def.thickness,
                            S.def.friction, S.hit, S.vertex_mass, impulses, &S.pushed_normal,
                            held_bodies);
      if (!S.max_deformation_pass()) break;
    }
  }
  if (impulses != nullptr) impulses->muted = false;
  if (held_bodies != nullptr)
    detail::hold_dynamic_bodies(S.x, S.v, S.free, S.def.thickness, h, *held_bodies, *impulses);
  bool finite = true;
  for (std::size_t i = 0; i < S.n; ++i) finite = finite && S.x[i].allFinite() && S.v[i].allFinite();
  if (!finite) return false;
  S.refresh_views();
  return true;
}

ClothView Cloth::view() const {
  const State& S = *s_;
  ClothView v;
  v.positions = S.fpos.data();
  v.normals = S.fnor.data();
  v.velocities = S.fvel.data();
  v.uvs = S.topo->uvs.data();
  v.triangles = S.topo->triangles.data();
  v.vertex_count = S.n;
  v.triangle_count = S.topo->triangles.size() / 3;
  v.rows = S.def.rows;
  v.columns = S.def.columns;
  return v;
}

ClothStats Cloth::stats() const {
  const State& S = *s_;
  const ClothTopology& T = *S.topo;
  ClothStats st;
  st.min_z = std::numeric_limits<double>::infinity();
  st.max_z = -std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < S.n; ++i) {
    st.kinetic_energy += 0.5 * S.vertex_mass * S.v[i].squaredNorm();
    st.momentum += S.vertex_mass * S.v[i];
    st.min_z = std::min(st.min_z, S.x[i].z());
    st.max_z = std::max(st.max_z, S.x[i].z());
  }
  for (std::size_t s = 0; s < T.spring_count(); ++s) {
    const double l = (S.x[T.spring_b[s]] - S.x[T.spring_a[s]]).norm();
    const double strain = l / T.rest_length[s] - 1.0;
    if (s < T.limited_count) st.max_strain = std::max(st.max_strain, strain);
    st.max_strain_any = std::max(st.max_strain_any, strain);
    const double ext = l - T.rest_length[s];
    st.spring_energy += 0.5 * S.k_of(s) * ext * ext;
  }
  st.cg_iterations = S.cg_iterations;
  st.strain_passes = S.strain_passes;
  return st;
}

const ClothDef& Cloth::definition() const { return s_->def; }
const std::shared_ptr<const ClothTopology>& Cloth::topology() const { return s_->topo; }
const std::vector<Vec3>& Cloth::positions() const { return s_->x; }

void Cloth::save_state(detail::StateWriter& out) const {
  const State& S = *s_;
  out.value(std::uint64_t(S.n));
  out.array(S.x);
  out.array(S.v);
  out.array(S.x_start);
  out.array(S.dv);  // the conjugate gradient starts from the last step's Δv (implicit.cpp)
}

void Cloth::load_state(detail::StateReader& in) {
  State& S = *s_;
  in.count(S.n, ("vertices of cloth '" + S.def.name + "'").c_str());
  in.array(S.x, S.n, "cloth positions");
  in.array(S.v, S.n, "cloth velocities");
  in.array(S.x_start, S.n, "cloth start positions");
  in.array(S.dv, S.n, "cloth velocity changes");
  if (S.x.size() != S.n || S.v.size() != S.n || S.x_start.size() != S.n || S.dv.size() != S.n)
    throw StateError("state: cloth '" + S.def.name + "' arrays do not hold its " +
                     std::to_string(S.n) + " vertices");
  const std::string of = "cloth '" + S.def.name + "' ";
  detail::require_finite(S.x, S.n, of + "positions");
  detail::require_finite(S.v, S.n, of + "velocities");
  detail::require_finite(S.x_start, S.n, of + "start positions");
  detail::require_finite(S.dv, S.n, of + "velocity changes");
  S.refresh_views();
}
const std::vector<Vec3>& Cloth::velocities() const { return s_->v; }
const std::vector<Vec3>& Cloth::start_positions() const { return s_->x_start; }
double Cloth::inverse_mass(std::size_t i) const {
  return s_->free[i] ? 1.0 / s_->vertex_mass : 0.0;
}

void Cloth::apply_impulses(const std::vector<Vec3>& impulses) {
  State& S = *s_;
  if (impulses.size() != S.n)
    throw std::invalid_argument("Cloth::apply_impulses: expected one impulse per vertex");
  for (std::size_t i = 0; i < S.n; ++i)
    if (S.free[i]) S.v[i] += impulses[i] / S.vertex_mass;
  S.refresh_views();
}

void Cloth::set_state(const std::vector<Vec3>& positions, const std::vector<Vec3>& velocities) {
  State& S = *s_;
  if (positions.size() != S.n || velocities.size() != S.n)
    throw std::invalid_argument("Cloth::set_state: positions and velocities must hold n vectors");
  for (std::size_t i = 0; i < S.n; ++i)
    if (!positions[i].allFinite() || !velocities[i].allFinite())
      throw std::invalid_argument("Cloth::set_state: non-finite position or velocity");
  S.x = positions;
  S.v = velocities;
  std::fill(S.dv.begin(), S.dv.end(), Vec3::Zero());
  S.refresh_views();
}

Vec3 Cloth::wind_at(const Vec3& p, double t) const { return s_->wind(p, t); }

}  // namespace simreel::sim
