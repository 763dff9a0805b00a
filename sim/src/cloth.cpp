// Mass-spring cloth (Coutinho §3.9.2) with implicit Euler after Baraff & Witkin 1998 (Coutinho
// Appendix B, the implicit Euler method for stiff systems) and the maximum-deformation pass.
#include "simreel/sim/cloth.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>

#include "cloth_collide.hpp"
#include "validate.hpp"

namespace simreel::sim {

namespace {

[[noreturn]] void bad(const std::string& field, const std::string& expected, double got) {
  std::ostringstream m;
  m << "ClothDef." << field << " must be " << expected << " (got " << got << ")";
  throw std::invalid_argument(m.str());
}

void validate(const ClothDef& d) {
  require_in((long long)d.rows, ranges::kClothGrid, "ClothDef.rows");
  require_in((long long)d.columns, ranges::kClothGrid, "ClothDef.columns");
  if (d.rows * d.columns < 2) bad("rows * columns", ">= 2", double(d.rows * d.columns));
  require_in(d.width, ranges::kClothSize, "ClothDef.width");
  require_in(d.height, ranges::kClothSize, "ClothDef.height");
  require_in(d.mass, ranges::kClothMass, "ClothDef.mass");
  if (!d.transform.translation.allFinite() || !d.transform.rotation.coeffs().allFinite() ||
      d.transform.rotation.norm() == 0.0)
    throw std::invalid_argument("ClothDef.transform must be finite with a non-zero rotation");
  for (std::size_t i = 0; i < d.pins.size(); ++i) {
    const ClothPin& p = d.pins[i];
    if (p.row >= d.rows || p.column >= d.columns) {
      std::ostringstream m;
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

/// splitmix64 finaliser: a hash of the lattice coordinates for the gust noise.
std::uint64_t mix(std::uint64_t z) {
  z += 0x9e3779b97f4a7c15ULL;
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
  return z ^ (z >> 31);
}

/// Smooth value noise in [-1, 1]: random values at integer tau, smoothstep between them (C1).
double value_noise(std::uint64_t key, double tau) {
  const double fl = std::floor(tau);
  const double f = tau - fl;
  const auto k = std::int64_t(fl);
  auto at = [key](std::int64_t i) {
    return double(mix(key ^ mix(std::uint64_t(i))) >> 11) * 0x1.0p-53 * 2.0 - 1.0;
  };
  const double s = f * f * (3.0 - 2.0 * f);
  return at(k) + (at(k + 1) - at(k)) * s;
}

/// Symmetric 3x3 block (the system matrix is block-symmetric): 6 numbers, products written out
/// because a generic Eigen 3x3 product was not inlined in the CG loop (42 % of its time).
struct Sym3 {
  double xx = 0, xy = 0, xz = 0, yy = 0, yz = 0, zz = 0;
  static Sym3 outer(const Vec3& u, double s) {  // s u uᵀ
    return {s * u.x() * u.x(), s * u.x() * u.y(), s * u.x() * u.z(),
            s * u.y() * u.y(), s * u.y() * u.z(), s * u.z() * u.z()};
  }
  Vec3 operator*(const Vec3& v) const {
    return {xx * v.x() + xy * v.y() + xz * v.z(), xy * v.x() + yy * v.y() + yz * v.z(),
            xz * v.x() + yz * v.y() + zz * v.z()};
  }
  Sym3& operator+=(const Sym3& o) {
    xx += o.xx; xy += o.xy; xz += o.xz; yy += o.yy; yz += o.yz; zz += o.zz;
    return *this;
  }
  void add_diagonal(double d) { xx += d; yy += d; zz += d; }
  Sym3 scaled(double s) const { return {s * xx, s * xy, s * xz, s * yy, s * yz, s * zz}; }
  Sym3 inverse() const {  // adjugate / determinant; the blocks here are positive definite
    const double c_xx = yy * zz - yz * yz, c_xy = xz * yz - xy * zz, c_xz = xy * yz - xz * yy;
    const double det = xx * c_xx + xy * c_xy + xz * c_xz;
    const double id = 1.0 / det;
    return {c_xx * id, c_xy * id, c_xz * id, (xx * zz - xz * xz) * id,
            (xz * xy - xx * yz) * id, (xx * yy - xy * xy) * id};
  }
};

}  // namespace

// ---------------------------------------------------------------------------------------------
// Topology (fig. 3.45)

ClothTopology::ClothTopology(std::size_t rows_, std::size_t columns_, double width_,
                             double height_)
    : rows(rows_), columns(columns_), width(width_), height(height_) {
  if (rows < 1 || columns < 1 || rows * columns < 2)
    throw std::invalid_argument("ClothTopology: rows, columns >= 1 and rows * columns >= 2");
  if ((columns > 1 && (!(width > 0.0) || !std::isfinite(width))) ||
      (rows > 1 && (!(height > 0.0) || !std::isfinite(height))))
    throw std::invalid_argument("ClothTopology: width and height must be > 0 and finite");
  const std::size_t n = rows * columns;
  const double dx = columns > 1 ? width / double(columns - 1) : 0.0;
  const double dy = rows > 1 ? height / double(rows - 1) : 0.0;
  local_rest.resize(n);
  uvs.resize(2 * n);
  auto id = [this](std::size_t r, std::size_t c) { return std::uint32_t(r * columns + c); };
  for (std::size_t r = 0; r < rows; ++r)
    for (std::size_t c = 0; c < columns; ++c) {
      const std::size_t i = id(r, c);
      local_rest[i] = Vec3(columns > 1 ? -0.5 * width + double(c) * dx : 0.0,
                           rows > 1 ? 0.5 * height - double(r) * dy : 0.0, 0.0);
      uvs[2 * i] = columns > 1 ? float(double(c) / double(columns - 1)) : 0.5f;
      uvs[2 * i + 1] = rows > 1 ? float(double(r) / double(rows - 1)) : 0.5f;
    }
  auto add = [&](std::uint32_t a, std::uint32_t b, SpringKind k) {
    spring_a.push_back(std::min(a, b));
    spring_b.push_back(std::max(a, b));
    rest_length.push_back((local_rest[a] - local_rest[b]).norm());
    kind.push_back(k);
  };
  for (std::size_t r = 0; r < rows; ++r)
    for (std::size_t c = 0; c < columns; ++c) {
      if (r + 1 < rows) add(id(r, c), id(r + 1, c), SpringKind::stretch);
      if (c + 1 < columns) add(id(r, c), id(r, c + 1), SpringKind::stretch);
    }
  for (std::size_t r = 0; r + 1 < rows; ++r)
    for (std::size_t c = 0; c + 1 < columns; ++c) {
      add(id(r, c), id(r + 1, c + 1), SpringKind::shear);
      add(id(r + 1, c), id(r, c + 1), SpringKind::shear);
    }
  limited_count = spring_a.size();
  for (std::size_t r = 0; r < rows; ++r)
    for (std::size_t c = 0; c < columns; ++c) {
      if (r + 2 < rows) add(id(r, c), id(r + 2, c), SpringKind::bend);
      if (c + 2 < columns) add(id(r, c), id(r, c + 2), SpringKind::bend);
    }
  // Triangles: each cell split along (r, c)-(r+1, c+1) as in §3.9.2; counter-clockwise seen from
  // local +z (row index grows towards -y).
  for (std::size_t r = 0; r + 1 < rows; ++r)
    for (std::size_t c = 0; c + 1 < columns; ++c) {
      const std::uint32_t a = id(r, c), b = id(r, c + 1), cc = id(r + 1, c), d = id(r + 1, c + 1);
      triangles.insert(triangles.end(), {a, cc, d, a, d, b});
    }
  // Adjacency in CSR form, springs of each vertex in spring order (a fixed summation order).
  adj_start.assign(n + 1, 0);
  for (std::size_t s = 0; s < spring_a.size(); ++s) {
    ++adj_start[spring_a[s] + 1];
    ++adj_start[spring_b[s] + 1];
  }
  for (std::size_t i = 0; i < n; ++i) adj_start[i + 1] += adj_start[i];
  adj_spring.resize(adj_start[n]);
  adj_other.resize(adj_start[n]);
  std::vector<std::uint32_t> fill(adj_start.begin(), adj_start.end() - 1);
  for (std::size_t s = 0; s < spring_a.size(); ++s) {
    const std::uint32_t a = spring_a[s], b = spring_b[s];
    adj_spring[fill[a]] = std::uint32_t(s);
    adj_other[fill[a]++] = b;
    adj_spring[fill[b]] = std::uint32_t(s);
    adj_other[fill[b]++] = a;
  }
}

// ---------------------------------------------------------------------------------------------
// State

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
  std::vector<double> spring_length; // per spring: current length (m), set by forces()
  std::vector<Vec3> spring_dir;      // per spring: unit a -> b, set by forces()
  std::vector<Sym3> S;               // per spring: h k_d nnᵀ + h² ∂f/∂x block
  std::vector<Sym3> precond;         // per vertex: inverse of the diagonal block (0 if pinned)
  std::vector<Sym3> aero_damping;    // per vertex: -∂f_aero/∂v, lumped (implicit Euler only)
  std::vector<std::uint32_t> pinned;  // pinned vertex indices
  bool aero_active = false;
  std::vector<Vec3> dv, b, r, z, p, Ap;
  // Maximum-deformation pass workspace.
  std::vector<double> t, t_next;
  std::vector<std::int32_t> changed_in;  // per vertex: last pass that changed its t (-1: none)
  std::vector<Vec3> origin, path;
  std::vector<std::uint8_t> hit;
  std::vector<Vec3> nacc;            // vertex normal accumulator
  // Float copies for views.
  std::vector<float> fpos, fnor, fvel;
  std::size_t cg_iterations = 0, strain_passes = 0;

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
  void max_deformation_pass();
  void refresh_views();
  Vec3 wind(const Vec3& p, double t) const;
};

Vec3 Cloth::State::wind(const Vec3& p, double t) const {
  const WindDef& w = def.wind;
  if (w.gust_amplitude == 0.0) return w.velocity;
  const double speed = w.velocity.norm();
  // The gust pattern travels with the mean wind: what reaches p at t left the origin at t - s/|w|.
  const double tau = w.gust_frequency * (speed > 0.0 ? t - p.dot(w.velocity) / (speed * speed) : t);
  return w.velocity + w.gust_amplitude * Vec3(value_noise(noise_key ^ 1, tau),
                                               value_noise(noise_key ^ 2, tau),
                                               value_noise(noise_key ^ 3, tau) / 3.0);
}

void Cloth::State::forces(double t) {
  const ClothTopology& T = *topo;
  for (std::size_t i = 0; i < n; ++i) f[i] = vertex_mass * (def.gravity - def.damping * v[i]);
  for (std::size_t s = 0; s < T.spring_count(); ++s) {
    const std::uint32_t a = T.spring_a[s], b = T.spring_b[s];
    const Vec3 d = x[b] - x[a];
    const double l = d.norm();
    spring_length[s] = l;  // reused by the implicit step's Jacobian (x has not moved since)
    if (!(l > 0.0)) continue;
    const Vec3 u = d / l;
    spring_dir[s] = u;
    const Vec3 fa = (ks[s] * (l - T.rest_length[s]) + kds[s] * (v[b] - v[a]).dot(u)) * u;
    f[a] += fa;
    f[b] -= fa;
  }
  const AeroDef& ae = def.aero;
  const bool jac = def.integrator == ClothIntegrator::implicit_euler;
  if (aero_active && jac) std::fill(aero_damping.begin(), aero_damping.end(), Sym3{});
  if (aero_active) {
    for (std::size_t k = 0; k + 2 < T.triangles.size(); k += 3) {
      const std::uint32_t i0 = T.triangles[k], i1 = T.triangles[k + 1], i2 = T.triangles[k + 2];
      const Vec3 c = (x[i0] + x[i1] + x[i2]) / 3.0;
      const Vec3 u = wind(c, t) - (v[i0] + v[i1] + v[i2]) / 3.0;
      const double u2 = u.squaredNorm();
      Vec3 nrm = (x[i1] - x[i0]).cross(x[i2] - x[i0]);
      const double twice_area = nrm.norm();
      if (!(u2 > 0.0) || !(twice_area > 0.0)) continue;
      nrm /= twice_area;
      const double speed = std::sqrt(u2);
      double cos_t = nrm.dot(u) / speed;
      if (cos_t < 0.0) {  // turn the normal to face the wind
        nrm = -nrm;
        cos_t = -cos_t;
      }
      const double q = 0.5 * ae.air_density * u2 * 0.5 * twice_area;  // ½ ρ |u|² A
      Vec3 F = q * ae.drag_coefficient * cos_t * nrm;
      Vec3 l = nrm - cos_t * u / speed;
      const double sin_t = l.norm();
      if (sin_t > 1e-12) F += q * ae.lift_coefficient * cos_t * l;  // |l| = sin θ
      F /= 3.0;
      f[i0] += F;
      f[i1] += F;
      f[i2] += F;
      if (jac) {
        // The pressure term c |u| (n·u) n has ∂/∂u = c (|u| nnᵀ + cos θ n uᵀ); its symmetric
        // bound c |u| (1 + cos θ) nnᵀ, lumped on each vertex as if it carried the triangle, keeps
        // light cloth in a gale stable at the frame step (treated explicitly, h ρ C_d |u| A / m
        // reaches ~3 for a 0.3 kg flag at 30 m/s: beyond forward Euler's limit of 2).
        const Sym3 D = Sym3::outer(nrm, q * ae.drag_coefficient / speed * (1.0 + cos_t) / 3.0);
        aero_damping[i0] += D;
        aero_damping[i1] += D;
        aero_damping[i2] += D;
      }
    }
  }
}

/// Linearised backward Euler (Baraff & Witkin 1998, eq. 6):
///   (M - h ∂f/∂v - h² ∂f/∂x) Δv = h (f0 + h ∂f/∂x v0),  v1 = v0 + Δv,  x1 = x0 + h v1,
/// solved by preconditioned conjugate gradients, matrix-free over the spring blocks (the matrix
/// is M + Σ_springs S ⊗ (graph Laplacian), S = h k_d nnᵀ + h² K). The spring Jacobian
/// K = k_s (nnᵀ + max(0, 1 - L/l)(I - nnᵀ)) drops the transverse term of compressed springs so
/// the matrix stays positive definite (Choi & Ko 2002 make the same choice). Pinned vertices get
/// their velocity from their target; their Δv moves to the right-hand side.
void Cloth::State::integrate_implicit(double h, double t1) {
  const ClothTopology& T = *topo;
  const std::size_t ns = T.spring_count();
  const double h2 = h * h;
  const double diag_m = vertex_mass * (1.0 + h * def.damping);
  // Known Δv of the pinned vertices (from their targets); the free ones keep the previous step's
  // Δv as the CG warm start.
  for (std::size_t i = 0; i < n; ++i) {
    b[i] = h * f[i];
    precond[i] = Sym3{};
    precond[i].add_diagonal(diag_m);
    if (aero_active) precond[i] += aero_damping[i].scaled(h);
  }
  for (const std::uint32_t i : pinned) {
    dv[i] = (pin_target(i, t1) - x[i]) / h - v[i];
    b[i].setZero();
  }
  // Spring blocks, the h² ∂f/∂x v0 term and the pinned columns moved to the right-hand side.
  for (std::size_t s = 0; s < ns; ++s) {
    const std::uint32_t a = T.spring_a[s], c = T.spring_b[s];
    const double l = spring_length[s];  // from forces(), same x
    if (!(l > 0.0)) {
      S[s] = Sym3{};
      continue;
    }
    const Vec3& u = spring_dir[s];
    const double k = ks[s];
    const double transverse = k * std::max(0.0, 1.0 - T.rest_length[s] / l);
    Sym3 K = Sym3::outer(u, k - transverse);
    K.add_diagonal(transverse);  // k (nnᵀ + τ (I - nnᵀ))
    Sym3 Ss = K.scaled(h2);
    Ss += Sym3::outer(u, h * kds[s]);
    S[s] = Ss;
    const Vec3 w = h2 * (K * (v[c] - v[a]));
    if (free[a]) {
      b[a] += w;
      precond[a] += Ss;
      if (!free[c]) b[a] += Ss * dv[c];  // -A_ac Δv_c with A_ac = -S
    }
    if (free[c]) {
      b[c] -= w;
      precond[c] += Ss;
      if (!free[a]) b[c] += Ss * dv[a];
    }
  }
  for (std::size_t i = 0; i < n; ++i) precond[i] = free[i] ? precond[i].inverse() : Sym3{};
  // y -> A y over the free vertices; y and the result are zero at pinned vertices.
  auto apply = [&](const std::vector<Vec3>& y, std::vector<Vec3>& out) {
    if (aero_active)
      for (std::size_t i = 0; i < n; ++i) out[i] = diag_m * y[i] + h * (aero_damping[i] * y[i]);
    else
      for (std::size_t i = 0; i < n; ++i) out[i] = diag_m * y[i];
    for (std::size_t s = 0; s < ns; ++s) {
      const std::uint32_t a = T.spring_a[s], c = T.spring_b[s];
      const Vec3 w = S[s] * Vec3(y[a] - y[c]);
      out[a] += w;
      out[c] -= w;
    }
    for (const std::uint32_t i : pinned) out[i].setZero();
  };
  // Preconditioned CG (block Jacobi), fixed summation order.
  std::vector<Vec3>& sol = p;
  for (std::size_t i = 0; i < n; ++i) sol[i] = free[i] ? dv[i] : Vec3::Zero();
  apply(sol, Ap);
  double b2 = 0.0, rr = 0.0, rz = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    r[i] = free[i] ? Vec3(b[i] - Ap[i]) : Vec3::Zero();
    z[i] = precond[i] * r[i];
    b2 += b[i].squaredNorm();
    rr += r[i].squaredNorm();
    rz += r[i].dot(z[i]);
  }
  const double tol2 = def.cg_tolerance * def.cg_tolerance * b2;
  std::vector<Vec3>& dir = b;  // b is no longer needed
  for (std::size_t i = 0; i < n; ++i) dir[i] = z[i];
  std::size_t it = 0;
  while (it < def.cg_max_iterations && rr > tol2) {
    apply(dir, Ap);
    double pAp = 0.0;
    for (std::size_t i = 0; i < n; ++i) pAp += dir[i].dot(Ap[i]);
    if (!(pAp > 0.0)) break;
    const double alpha = rz / pAp;
    double rz_new = 0.0;
    rr = 0.0;
    for (std::size_t i = 0; i < n; ++i) {
      sol[i] += alpha * dir[i];
      r[i] -= alpha * Ap[i];
      z[i] = precond[i] * r[i];
      rz_new += r[i].dot(z[i]);
      rr += r[i].squaredNorm();
    }
    const double beta = rz_new / rz;
    rz = rz_new;
    for (std::size_t i = 0; i < n; ++i) dir[i] = z[i] + beta * dir[i];
    ++it;
  }
  cg_iterations = it;
  for (std::size_t i = 0; i < n; ++i) {
    if (free[i]) dv[i] = sol[i];
    v[i] += dv[i];
    x[i] += h * v[i];
    if (!free[i]) x[i] = pin_target(i, t1);  // exact, whatever the rounding of x + h v
  }
}

void Cloth::State::integrate_explicit(double h, double t1, bool semi) {
  for (std::size_t i = 0; i < n; ++i) {
    if (!free[i]) {
      const Vec3 target = pin_target(i, t1);
      v[i] = (target - x[i]) / h;
      x[i] = target;
      continue;
    }
    const Vec3 a = f[i] / vertex_mass;
    if (semi) {
      v[i] += h * a;
      x[i] += h * v[i];
    } else {
      x[i] += h * v[i];
      v[i] += h * a;
    }
  }
}

/// Coutinho §3.9.2, the maximum-deformation pass. Each vertex moved along the straight path
/// x_start -> x; a stretch or shear spring longer than (1 + max_strain) L brings its two vertices
/// back along their paths to the common parameter t_p where it is exactly at the limit (the larger
/// root in [0, 1] of |k1 + t k2|² = d_max², eq. 3.106); a vertex on several such springs takes the
/// minimum t_p. Pinned vertices do not move back (their path is imposed): their end is taken as
/// both ends of their path. The book's one pass uses a common t per spring; with per-vertex minima
/// a spring whose two vertices took different t can still be over the limit, so the pass is
/// repeated (each repeat only shortens paths, and t = 0 everywhere is the valid start state) until
/// no spring is over the limit: a departure from the book, counted in ClothStats::strain_passes.
void Cloth::State::max_deformation_pass() {
  strain_passes = 0;
  if (!std::isfinite(def.max_strain)) return;
  const ClothTopology& T = *topo;
  const double stretch_max = 1.0 + def.max_strain;
  // Solve for a limit a hair inside the true one so rounding never leaves a spring over it.
  const double target_scale = stretch_max * (1.0 - 1e-9);
  for (std::size_t i = 0; i < n; ++i) {
    origin[i] = free[i] ? x_start[i] : x[i];
    path[i] = x[i] - origin[i];
    t[i] = 1.0;
    changed_in[i] = -1;
  }
  constexpr std::size_t kMaxPasses = 64;
  bool any_moved = false;
  for (;;) {
    bool violated = false, changed = false;
    // The first pass is the book's: every t_p from the positions the integrator gave, minima
    // applied together. Repeats (if needed) update t in place, which converges faster.
    const bool book_pass = strain_passes == 0;
    std::vector<double>& tw = book_pass ? t_next : t;
    if (book_pass)
      for (std::size_t i = 0; i < n; ++i) t_next[i] = t[i];
    // A repeat only revisits springs with an end whose t changed in the previous pass or this
    // one: every other spring has the positions it had when last found within the limit, so
    // skipping it changes nothing (the result is the same as checking all of them).
    const auto pass = std::int32_t(strain_passes);
    for (std::size_t s = 0; s < T.limited_count; ++s) {
      const std::uint32_t a = T.spring_a[s], b = T.spring_b[s];
      if (!book_pass && changed_in[a] < pass - 1 && changed_in[b] < pass - 1) continue;
      const double L = T.rest_length[s];
      const Vec3 pa = origin[a] + t[a] * path[a], pb = origin[b] + t[b] * path[b];
      const double l2 = (pa - pb).squaredNorm();
      if (l2 <= stretch_max * stretch_max * L * L) continue;
      violated = true;
      double tp = 0.0;  // after kMaxPasses: both back to the start of the step (last resort)
      if (strain_passes < kMaxPasses) {
        const Vec3 k1 = origin[a] - origin[b];
        const Vec3 k2 = t[a] * path[a] - t[b] * path[b];
        const double A = k2.squaredNorm();
        const double B = 2.0 * k1.dot(k2);
        const double dmax = target_scale * L;
        const double C = k1.squaredNorm() - dmax * dmax;
        const double disc = B * B - 4.0 * A * C;
        if (A > 0.0 && disc >= 0.0) {
          const double sq = std::sqrt(disc);
          const double qq = -0.5 * (B + std::copysign(sq, B));  // stable roots
          double r1 = qq / A, r2 = qq != 0.0 ? C / qq : r1;
          if (r1 > r2) std::swap(r1, r2);
          if (r2 >= 0.0 && r2 <= 1.0) tp = r2;
          else if (r1 >= 0.0 && r1 <= 1.0) tp = r1;
          else tp = std::clamp(-B / (2.0 * A), 0.0, 1.0);  // start over the limit: closest point
        } else if (A > 0.0) {
          tp = std::clamp(-B / (2.0 * A), 0.0, 1.0);
        }
      }
      const double ta = t[a], tb = t[b];
      bool moved = false;
      if (free[a] && tp * ta < tw[a]) { tw[a] = tp * ta; changed = moved = true; changed_in[a] = pass; }
      if (free[b] && tp * tb < tw[b]) { tw[b] = tp * tb; changed = moved = true; changed_in[b] = pass; }
      if (!moved) changed_in[a] = changed_in[b] = pass;  // still over: look again next pass
    }
    if (!violated) break;
    ++strain_passes;
    any_moved = true;
    if (book_pass)
      for (std::size_t i = 0; i < n; ++i) t[i] = t_next[i];
    if (!changed && strain_passes > kMaxPasses) break;  // only the start state itself violates
  }
  if (!any_moved) return;
  for (std::size_t i = 0; i < n; ++i) {
    if (!free[i] || t[i] == 1.0) continue;
    x[i] = origin[i] + t[i] * path[i];
    // Velocity consistent with the corrected displacement over the step.
    v[i] *= t[i];
  }
}

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
  validate(def);
  State& S = *s_;
  S.def = def;
  S.def.transform.rotation.normalize();
  if (!topology)
    topology = std::make_shared<const ClothTopology>(def.rows, def.columns, def.width, def.height);
  if (topology->rows != def.rows || topology->columns != def.columns ||
      topology->width != def.width || topology->height != def.height)
    throw std::invalid_argument("Cloth: the shared topology does not match the ClothDef grid");
  S.topo = std::move(topology);
  S.noise_key = mix(seed ^ mix(index + 0x636c6f7468ULL));  // "cloth"
  S.n = def.rows * def.columns;
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
    const std::size_t i = def.pins[k].row * def.columns + def.pins[k].column;
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
  S.spring_length.assign(ns, 0.0);
  S.spring_dir.assign(ns, Vec3::Zero());
  S.precond.assign(n, Sym3{});
  for (std::size_t i = 0; i < n; ++i)
    if (!S.free[i]) S.pinned.push_back(std::uint32_t(i));
  S.aero_active = def.aero.air_density > 0.0 &&
                  (def.aero.drag_coefficient > 0.0 || def.aero.lift_coefficient > 0.0);
  S.aero_damping.assign(S.aero_active ? n : 0, Sym3{});
  for (auto* w : {&S.dv, &S.b, &S.r, &S.z, &S.p, &S.Ap, &S.origin, &S.path, &S.nacc})
    w->assign(n, Vec3::Zero());
  S.t.assign(n, 1.0);
  S.t_next.assign(n, 1.0);
  S.changed_in.assign(n, -1);
  S.hit.assign(n, 0);
  S.fpos.assign(3 * n, 0.0f);
  S.fnor.assign(3 * n, 0.0f);
  S.fvel.assign(3 * n, 0.0f);
  S.refresh_views();
}

Cloth::~Cloth() = default;
Cloth::Cloth(Cloth&&) noexcept = default;
Cloth& Cloth::operator=(Cloth&&) noexcept = default;

bool Cloth::step(double t0, double t1, const std::vector<detail::Collider>* colliders) {
  State& S = *s_;
  const double h = t1 - t0;
  S.x_start = S.x;
  S.forces(t0);
  switch (S.def.integrator) {
    case ClothIntegrator::implicit_euler: S.integrate_implicit(h, t1); break;
    case ClothIntegrator::semi_implicit_euler: S.integrate_explicit(h, t1, true); break;
    case ClothIntegrator::explicit_euler: S.integrate_explicit(h, t1, false); break;
  }
  const bool collide = S.def.collide && colliders != nullptr && !colliders->empty();
  if (collide) {
    std::fill(S.hit.begin(), S.hit.end(), std::uint8_t(0));
    detail::collide_cloth(S.x, S.v, S.x_start, S.free, *colliders, S.def.thickness,
                          S.def.friction, S.hit);
  }
  S.max_deformation_pass();
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
