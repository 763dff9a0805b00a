#pragma once
/// @file cloth.hpp
/// Mass-spring cloth (Coutinho §3.9.2): a rectangular grid of particles joined by stretch, shear
/// and bend springs (fig. 3.45), integrated by implicit Euler (Baraff & Witkin 1998; Coutinho
/// Appendix B) with the maximum-deformation pass of §3.9.2, pinned vertices (fixed or keyframed),
/// gravity, viscous damping, aerodynamic drag and lift per triangle in a gusty wind, and vertex
/// collisions with the world's colliders.
///
/// Model apart from state: a ClothTopology (springs, rest lengths, triangles, UVs, adjacency) is
/// built once per grid and may be shared by several Cloth instances; each Cloth owns its vertex
/// positions and velocities.
///
/// Grid convention: vertex (row r, column c) has index r * columns + c. In the cloth's local frame
/// the grid lies in the xy plane, centred on the origin, column 0 at x = -width/2, row 0 at
/// y = +height/2 (the "top" edge; rows go down -y). ClothDef::transform places it in the world.

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "simreel/sim/keyframes.hpp"
#include "simreel/sim/types.hpp"

namespace simreel::sim {

namespace detail {
struct Collider;
struct BodyImpulses;
class StateWriter;
class StateReader;
struct ClothAccess;
}

/// How a cloth's state is advanced over one internal step (Coutinho Appendix B).
enum class ClothIntegrator : std::uint8_t {
  implicit_euler,       ///< linearised backward Euler (Baraff & Witkin 1998): stable for stiff springs
  semi_implicit_euler,  ///< v += h a(x, v); x += h v  (symplectic Euler; for comparison)
  explicit_euler,       ///< x += h v; v += h a(x, v)  (forward Euler; for comparison)
};

/// The three spring families of fig. 3.45.
enum class SpringKind : std::uint8_t { stretch = 0, shear = 1, bend = 2 };

/// A damped spring family: f = k_s (l - L) n + k_d ((v_j - v_i)·n) n on vertex i (Coutinho §3.3).
struct SpringParams {
  double stiffness = 0.0;  ///< k_s (N/m) per spring, >= 0
  double damping = 0.0;    ///< k_d (N s/m) per spring along its axis, >= 0
};

/// A pinned vertex: its position is imposed, not integrated.
struct ClothPin {
  std::size_t row = 0;
  std::size_t column = 0;
  /// Empty: the vertex stays where the cloth's transform put it. Otherwise the vertex follows
  /// `path.sample(t).translation` (m, world frame); the rotation of the keys is ignored.
  KeyframePath path;
};

/// Uniform wind plus gusts. The gust is smooth value noise (cubic-interpolated random lattice
/// values, one per 1/gust_frequency seconds, deterministic from the world seed and the cloth
/// index) on each axis, travelling with the mean wind, so a gust sweeps across a sheet.
struct WindDef {
  Vec3 velocity = Vec3::Zero();  ///< (m/s) mean wind, world frame
  double gust_amplitude = 0.0;   ///< (m/s) peak gust per axis (vertical gusts at 1/3 of it), >= 0
  double gust_frequency = 0.5;   ///< (Hz) rate of gust changes, > 0
};

/// Aerodynamic force per triangle from the relative wind u = wind - (mean vertex velocity):
/// with n the unit normal turned to face the wind and cos θ = n·u/|u|,
///   F = ½ ρ |u|² A (C_d cos θ n + C_l cos θ sin θ l),  l = unit(n - cos θ u/|u|),
/// a pressure term along the normal and a lift term across the flow; a third to each vertex.
struct AeroDef {
  double drag_coefficient = 1.0;  ///< C_d, >= 0
  double lift_coefficient = 0.5;  ///< C_l, >= 0
  double air_density = 1.225;     ///< ρ (kg/m³), >= 0; 0 disables aerodynamics
};

/// A cloth made from any triangle mesh (issue 16) instead of the grid: stretch springs on its
/// edges, shear and bend springs between the opposite vertices of each pair of triangles that
/// share an edge (ClothTopology(const ClothMesh&)).
struct ClothMesh {
  std::vector<Vec3> vertices;            ///< (n) rest positions in the cloth's local frame (m)
  std::vector<std::uint32_t> triangles;  ///< (t x 3) vertex indices, counter-clockwise from +normal
  std::vector<float> uvs;                ///< (n x 2) or empty (then planar from local x, y)
  [[nodiscard]] bool empty() const { return vertices.empty(); }
};

/// Everything that defines a cloth. Validated by the Cloth constructor.
struct ClothDef {
  std::string name = "cloth";
  /// Non-empty: the cloth is this mesh, not the grid. The Cloth then sets rows = 1 and columns =
  /// the vertex count (width and height unused), and a pin's `column` is its vertex index.
  ClothMesh mesh;
  std::size_t rows = 16;     ///< vertices along the local y axis, >= 1 (rows * columns >= 2)
  std::size_t columns = 16;  ///< vertices along the local x axis, >= 1
  double width = 1.0;        ///< (m) local x extent, > 0 (ignored when columns == 1)
  double height = 1.0;       ///< (m) local y extent, > 0 (ignored when rows == 1)
  double mass = 1.0;         ///< (kg) total, > 0; shared equally by the vertices
  Transform transform;       ///< local grid -> world
  std::vector<ClothPin> pins;
  SpringParams stretch{2000.0, 0.5};  ///< (i,j)-(i+1,j) and (i,j)-(i,j+1)
  SpringParams shear{500.0, 0.2};     ///< both diagonals of each cell
  SpringParams bend{20.0, 0.02};      ///< (i,j)-(i+2,j) and (i,j)-(i,j+2)
  /// Maximum deformation of §3.9.2: no stretch or shear spring ends a step longer than
  /// (1 + max_strain) × rest length. >= 0; infinity disables the pass.
  double max_strain = 0.10;
  ClothIntegrator integrator = ClothIntegrator::implicit_euler;
  Vec3 gravity{0.0, 0.0, -9.81};  ///< (m/s²), world frame
  /// (1/s) viscous damping rate: force -damping · m_vertex · v on every vertex (mass-proportional,
  /// so it means the same at any grid resolution), >= 0. Air drag comes from `aero`.
  double damping = 0.05;
  WindDef wind;
  AeroDef aero;
  double thickness = 0.005;  ///< (m) vertices keep this distance from collider surfaces, >= 0
  double friction = 0.3;     ///< Coulomb coefficient for cloth-collider contact, >= 0
  /// Collide with the world's colliders: vertices against surfaces, and triangles and edges
  /// against collider corners, edges and axes (a thin pole, a box's edge), continuously in time.
  bool collide = true;
  /// Vertex–triangle and edge–edge contacts of the cloth with itself (folds never cross), at
  /// `thickness` (capped at a quarter of the shortest edge). Off by default: it costs time.
  bool self_collision = false;
  /// Contacts with other cloths that also allow it (both must), at the larger thickness.
  bool collide_cloths = true;
  /// Particles (rain, jets) of systems with ParticleSystemDef::collide hit the cloth's triangles;
  /// each impulse is shared by the triangle's vertices by barycentric weight (see World::advance).
  bool collide_particles = true;
  double restitution = 0.1;  ///< particle–cloth coefficient of restitution, in [0, 1]
  /// Implicit Euler: CG stops at |r| <= tol |b| (> 0). Loose by default: the solve only has to be
  /// stable and plausible, and the maximum-deformation pass bounds the stretch whatever the
  /// residual. The preconditioner is two-level (block Jacobi plus a coarse solve over patches
  /// of ~45 vertices, cloth/coarse_space.hpp): 1e-2 takes ~14 iterations per step on the
  /// 64 x 64 benchmark cloth and 1e-3 ~23 (block Jacobi alone took ~30 and ~70).
  double cg_tolerance = 1e-2;
  std::size_t cg_max_iterations = 200;  ///< implicit Euler: CG iteration cap, >= 1
};

/// Springs, rest lengths, triangles, UVs and adjacency of a rows × columns grid: built once,
/// shared by every cloth with the same grid (Jolt's SoftBodySharedSettings, MuJoCo's mjModel).
class ClothTopology {
 public:
  /// @throws std::invalid_argument unless rows, columns >= 1, rows * columns >= 2, and the
  ///         used extents are > 0 and finite.
  ClothTopology(std::size_t rows, std::size_t columns, double width, double height);
  /// The topology of a mesh cloth: rows = 1, columns = vertex count. Stretch springs on the
  /// edges, then (across every edge two triangles share) a spring between the opposite vertices:
  /// shear if shorter than 1.5 edge lengths, bend otherwise; one spring per vertex pair.
  /// @throws std::invalid_argument naming the triangle or vertices on bad input (index out of
  ///         range, zero-area triangle, joined vertices at one place, fewer than 3 vertices).
  explicit ClothTopology(const ClothMesh& mesh);

  std::size_t rows = 0, columns = 0;
  double width = 0.0, height = 0.0;
  bool from_mesh = false;  ///< built from a ClothMesh (rows = 1, columns = vertex count)
  // Springs (s = 0 .. spring_count-1), ordered stretch, then shear, then bend.
  std::vector<std::uint32_t> spring_a, spring_b;  ///< vertex indices, a < b
  std::vector<double> rest_length;                ///< (m)
  std::vector<SpringKind> kind;
  std::size_t limited_count = 0;  ///< springs [0, limited_count) are stretch or shear
  // Adjacency (CSR): vertex v's springs are adj_spring[adj_start[v] .. adj_start[v+1]).
  std::vector<std::uint32_t> adj_start, adj_spring, adj_other;
  std::vector<std::uint32_t> triangles;  ///< (t x 3) indices, counter-clockwise seen from local +z
  std::vector<float> uvs;                ///< (n x 2) u = column / (columns-1), v = row / (rows-1)
  /// Unique triangle edges (e x 2, a < b), for the edge–edge contacts; edge_triangle[e] is the
  /// first triangle holding edge e, triangle_edges (t x 3) the edges of each triangle.
  std::vector<std::uint32_t> edges, edge_triangle, triangle_edges;
  /// (n) the first triangle holding each vertex, or UINT32_MAX for a vertex in none: the
  /// self-contacts test a vertex from that triangle only, as an edge from edge_triangle.
  std::vector<std::uint32_t> vertex_triangle;
  std::vector<Vec3> local_rest;          ///< (n) rest positions in the local frame (m)

  [[nodiscard]] std::size_t vertex_count() const { return rows * columns; }
  [[nodiscard]] std::size_t spring_count() const { return spring_a.size(); }

 private:
  void finish();  // unique edges and the adjacency, from the springs and triangles
};

/// Read-only state for the renderer and exports; valid until the cloth next changes.
struct ClothView {
  const float* positions = nullptr;     ///< (n x 3) (m), world frame
  const float* normals = nullptr;       ///< (n x 3) unit, area-weighted vertex normals (local +z side)
  const float* velocities = nullptr;    ///< (n x 3) (m/s), world frame
  const float* uvs = nullptr;           ///< (n x 2)
  const std::uint32_t* triangles = nullptr;  ///< (t x 3) vertex indices, fixed for the cloth's life
  std::size_t vertex_count = 0;
  std::size_t triangle_count = 0;
  std::size_t rows = 0, columns = 0;
};

/// Diagnostics of the current state.
struct ClothStats {
  double max_strain = 0.0;        ///< max over stretch and shear springs of l / L - 1
  double max_strain_any = 0.0;    ///< the same including bend springs
  double kinetic_energy = 0.0;    ///< (J) ½ Σ m v²
  double spring_energy = 0.0;     ///< (J) ½ Σ k_s (l - L)²
  double min_z = 0.0, max_z = 0.0;  ///< (m) vertex height range
  std::size_t cg_iterations = 0;  ///< CG iterations of the last implicit step
  std::size_t strain_passes = 0;  ///< maximum-deformation passes of the last step (1 = the book's)
  Vec3 momentum = Vec3::Zero();   ///< (kg m/s) Σ m v, double precision
};

/// One cloth instance.
class Cloth {
 public:
  /// Builds the topology. @throws std::invalid_argument naming the ClothDef field on bad input.
  explicit Cloth(const ClothDef& def, std::uint64_t seed = 0, std::uint64_t index = 0);
  /// Shares an existing topology; it must match def.rows/columns/width/height.
  Cloth(const ClothDef& def, std::shared_ptr<const ClothTopology> topology, std::uint64_t seed = 0,
        std::uint64_t index = 0);
  ~Cloth();
  Cloth(Cloth&&) noexcept;
  Cloth& operator=(Cloth&&) noexcept;

  /// Advances from t0 to t1 (s): forces, the integrator, collisions with `colliders` (the World's;
  /// nullptr: none), the maximum-deformation pass (§3.9.2) and velocities from the corrected
  /// positions. `impulses` (the World's, when it has dynamic bodies): each vertex's momentum
  /// change against a dynamic body's shape is logged there, equal and opposite, for the body
  /// (two-way coupling, Coutinho §3.7). @returns false if the state became non-finite (the World
  /// then reports it). `threads`: OpenMP threads for the spring and vertex loops of the
  /// implicit step (WorldDef::threads); the result is the same bits at any count.
  bool step(double t0, double t1, const std::vector<detail::Collider>* colliders = nullptr,
            detail::BodyImpulses* impulses = nullptr, int threads = 1);

  [[nodiscard]] ClothView view() const;
  [[nodiscard]] ClothStats stats() const;
  [[nodiscard]] const ClothDef& definition() const;
  [[nodiscard]] const std::shared_ptr<const ClothTopology>& topology() const;
  /// Positions (m) and velocities (m/s) in double precision, n each, world frame.
  [[nodiscard]] const std::vector<Vec3>& positions() const;
  [[nodiscard]] const std::vector<Vec3>& velocities() const;
  /// Overwrites the state (tests, tools); pins keep their imposed positions from the next step.
  /// @throws std::invalid_argument unless both hold n finite vectors.
  void set_state(const std::vector<Vec3>& positions, const std::vector<Vec3>& velocities);
  /// Positions (m, world) at the start of the last step (the paths of the swept tests).
  [[nodiscard]] const std::vector<Vec3>& start_positions() const;
  /// 1 / vertex mass (1/kg) of vertex i; 0 for a pinned vertex (its motion is imposed).
  [[nodiscard]] double inverse_mass(std::size_t i) const;
  /// Adds impulse J_i (N s, world frame) to every free vertex i: v_i += J_i / m_vertex; pinned
  /// vertices ignore theirs. Used by the particle contact pass. @throws std::invalid_argument
  /// unless `impulses` holds n entries.
  void apply_impulses(const std::vector<Vec3>& impulses);
  /// Wind velocity (m/s) at world point p and time t, gusts included.
  [[nodiscard]] Vec3 wind_at(const Vec3& p, double t) const;

  /// The state that carries from one step to the next (positions, velocities, start-of-step
  /// positions, the implicit solver's last Δv: its next warm start), for World::save_state.
  void save_state(detail::StateWriter& out) const;
  /// Restores what save_state wrote for a cloth of the same grid, then refreshes the views.
  /// @throws StateError when the vertex count differs or the bytes are truncated.
  void load_state(detail::StateReader& in);

 private:
  friend struct detail::ClothAccess;
  struct State;
  std::unique_ptr<State> s_;
};

}  // namespace simreel::sim
