#pragma once
// Particle–particle collisions (private): a hashed uniform grid finds the candidate pairs
// (Coutinho §2.3.1, cell = 2 x mean diameter), and a sequential-impulse (projected Gauss–Seidel)
// solver resolves all contacts of a step together. With the restitution target of each contact
// fixed from the velocities before the solve, its fixed point is the solution of the §3.6.2
// linear system of simultaneous impulses (when every impulse comes out compressive), and each
// pair's impulse follows §3.6.1: equal and opposite (momentum is conserved exactly up to
// rounding), normal part reaching v_n' = -e v_n, Coulomb friction clamped to mu P_n so sliding
// stops when mu reaches the critical coefficient (eqs. 3.56–3.57). Contacts slower than the
// contact speed are resting (e = 0, §3.6.3). Order is fixed (run() sorts the particles by grid
// cell; contacts follow the cells, and the sweeps go over slabs of cells, the even slabs then the
// odd ones, which may run in parallel), so results are deterministic at any thread count.
//
// Resting contact with colliders (§3.6.3–3.6.4): impacts on colliders are resolved by the swept
// pass (collider.cpp) before this solve, but a particle under a pile is pushed back into the
// surface by the pair impulses of the particles above it. So the solve also holds one-body
// constraints for every particle whose sphere is within a margin of a collider's closest feature
// at the end of the step: inelastic (e = 0; the swept pass already gave the impacts their
// restitution), speculative when there is a gap (the particle may still close it this step), and
// with Coulomb friction at the static coefficient while not sliding. Resting impulses are warm
// started from the previous step (keyed by particle id, the other particle's id or the collider
// and its normal), so a stack's impulses m g h per layer carry over and do not have to travel
// through the stack within one step's sweeps. Overlaps are then reduced by a position projection
// over the same contacts (colliders immovable) that leaves a small slop and does not touch
// velocities, so it neither injects energy nor pushes the bottom of a pile into a collider.
//
// Known limits: particle pairs are found at the end of the step, overlapping or (slow ones)
// within the margin, not swept like particle vs collider. Particles are frictional points that
// cannot roll and pairs have one (dynamic) coefficient, so the surface of a pile steeper than
// atan(mu) still slides now and then.

#include <cstddef>
#include <cstdint>
#include <vector>

#include "core/counting_sort.hpp"
#include "core/raw_vector.hpp"
#include "core/run_claims.hpp"
#include "collision/collider_impl.hpp"
#include "particles/particle_store.hpp"
#include "simreel/sim/types.hpp"

namespace simreel::sim::detail {

class StateWriter;
class StateReader;

/// A particle as the contact sweeps read it: its velocity (m/s, world) and inverse mass (1/kg,
/// 0 asleep) in one aligned row of four doubles, so that four of them transpose into the
/// sweep's four lanes (x, y, z, 1/m) with whole-row loads and stores.
struct alignas(32) SolveBody {
  double v[3];
  double inv_mass;
};

/// One participating particle set (a system) and its surface parameters.
struct ParticleGroupMember {
  ParticleStore* store = nullptr;
  double restitution = 0.5;
  double friction = 0.1;
  bool collide = true;  ///< the system collides with colliders (its corrections are swept)
  std::uint32_t system = 0;  ///< registration serial of the system: warm-start key (stable
                             ///< when other systems are removed)
  /// Its particles may sleep (WorldState::sleep_allowed; the store keeps `rest`): otherwise any
  /// sleeping ones are woken.
  bool sleep = false;
  /// (m/s²) magnitude of the system's gravity: a pair is an impact (restitution, a sleeper
  /// woken) when it approaches faster than the contact speed plus the g h of one step.
  double gravity = 0.0;
};

/// The widest contact update of the sweeps this CPU runs (8: two groups of four AVX2 lanes, or
/// 4: AVX2; 2: SSE2; else 1), at most max_lanes (checked once per CPU feature).
int solve_lanes(int max_lanes);

class ParticleCollider {
 public:
  int iterations = 16;            ///< Gauss–Seidel sweeps per step
  int position_iterations = 2;    ///< Gauss–Seidel sweeps of the overlap projection
  double position_fraction = 0.8; ///< share of an overlap beyond the slop removed per step
  double slop_fraction = 0.01;    ///< overlap of a pair left alone, times the smaller radius
  double margin_fraction = 0.25;  ///< collider contacts within this gap, times the radius
  double pair_margin_fraction = 0.05;  ///< pair contacts within this gap, times the smaller radius
  bool warm_start = true;
  int threads = 1;  ///< OpenMP threads for the solve of a large step (results do not depend on it)
  /// The sweeps visit the contacts in wavefront order (see schedule(); the same bits, faster);
  /// false: in contact order, the reference the tests compare it with.
  bool wavefront = true;
  /// The most contacts of one wave the wavefront sweeps solve at once (8, 4, 2 or 1): where the
  /// CPU has AVX2, runs of eight as two groups of four lanes whose updates are interleaved step
  /// by step (the processor overlaps their chains of dependent operations), and four; two
  /// (SSE2) otherwise; never more than this. The bits are the same at every width (the solver
  /// test compares 8, 4, 2 and 1). Eight AVX-512 lanes in one register were slower than four
  /// on a Xeon (their particles' rows need gathers and scatters).
  int max_lanes = 8;
  /// The AVX2 sweeps use AVX-512VL's 32 vector registers where the CPU has them (the same
  /// instructions and bits; two groups' updates then fit without spilling: the cold solve of
  /// 118k contacts in 0.89x the 16 registers' time on a Xeon); false: the 16 of AVX2, which
  /// the solver test compares.
  bool avx512_registers = true;
  /// The most candidates the pair search tests at once (8, 4 or 1): eight AVX-512VL lanes or
  /// four AVX2 lanes where the CPU has them, the kept ones compressed to the front, else one by
  /// one. The same pairs in the same order at every width (the pair-search test compares them);
  /// four AVX2 lanes made the 100k cloud's steady step ~20 % faster on an AMD EPYC without
  /// AVX-512 (the scalar gather had taken a fifth of it).
  int pair_search_lanes = 8;
  /// With particles asleep (run()), the sorted grid's pair search starts from the awake ones
  /// alone, over all 27 cells around each, when at most 1 / awake_search_share of the
  /// particles are awake (0: never): the same contacts in the same order (the pair-search test
  /// compares them), at a cost in the awake count instead of every particle's half stencil. A
  /// settled pile of 5,000 beads with 20 awake spent half its step in the full search.
  int awake_search_share = 4;
  /// A lone contact (no other contact touches either of its particles) is solved by the first
  /// sweep: its normal impulse reaches its target and its friction impulse the Coulomb-clamped
  /// value that cancels the sliding (a pair's relative velocity changes by the impulse over
  /// m_eff, so the next sweep finds the same unclamped value), and nothing else moves its
  /// particles. true: the later sweeps leave the lone contacts out (schedule() puts them at the
  /// end of each band's range, which changes no bit of the first sweep: they share no particle
  /// with anything); the results differ from all sweeps over them only by rounding. false: every
  /// sweep visits them, the reference the tests compare it with.
  bool lone_contacts = true;
  /// run() takes restitution, friction and `collide` from the members when they are alike
  /// instead of filling the per-particle arrays (the same bits, a cheaper fill); false: always
  /// the arrays, the reference the tests compare it with.
  bool uniform_surface = true;

  /// Finds and resolves the contacts among all members' particles and, for members that
  /// collide, with `colliders` (may be null) at their end-of-step pose; h (s) is the step.
  /// Updates velocities and positions in place. Scratch buffers are kept between calls (no
  /// per-step allocation once they have grown). Afterwards the working arrays (x, v, x_before,
  /// contacts' indices and the rest) are in working order (cell order when the grid sorted the
  /// particles): flat_index() and member_particle() map an entry to its particle.
  void run(const std::vector<ParticleGroupMember>& members, double contact_speed, double h,
           const std::vector<Collider>* colliders);

  /// The member (flat) index of working index q, the index `contacts` and the other working
  /// arrays use after run() (cell order when the grid sorted the particles).
  [[nodiscard]] std::uint32_t flat_index(std::uint32_t q) const { return q < perm_.size() ? perm_[q] : q; }
  /// A particle of run()'s members: members[member].store, index `index` there.
  struct MemberParticle {
    std::size_t member, index;
  };
  /// The particle of working index q after run().
  [[nodiscard]] MemberParticle member_particle(std::uint32_t q) const;
  /// What fill_working() reads of one particle, packed by run()'s first pass (which reads the
  /// stores in order): one cache line a particle for the gather in cell order, where the stores'
  /// columns were six (position, velocity, mass, radius, age, key) and the gather was bound by
  /// the lines in flight. The same floats as the stores', so the same bits.
  struct alignas(64) FlatParticle {
    float x[3], v[3];
    float mass, radius, age;
    std::uint8_t asleep;  ///< asleep all this step (the member lets it sleep, §3.6.3)
    std::uint64_t key;    ///< key_flat_'s
  };
  static_assert(sizeof(FlatParticle) == 64, "a cache line a particle");

  // Flat working arrays, public for the solver test (set x, v, inv_mass, radius, e, mu, then
  // find_contacts() and solve()).
  std::vector<Vec3> x, v;
  std::vector<Vec3> x_before;  ///< positions before the overlap correction (run() fills it)
  std::vector<double> inv_mass, radius, restitution, friction;
  std::vector<std::uint64_t> key;  ///< (system << 40) | id, for the warm start (run() fills it)
  std::vector<std::uint8_t> collides;  ///< the particle collides with colliders
  /// The particle sleeps (ParticleStore::rest): inv_mass is 0 (it does not move), pairs of two
  /// sleeping particles and its collider contacts are left out; an impact of an awake particle
  /// (overlapping, approaching faster than the contact speed) wakes it before the solve.
  std::vector<std::uint8_t> asleep;
  static constexpr std::uint32_t kCollider = 0xffffffffu;  ///< Contact::i of a collider contact
  /// 104 bytes: every pass over the contacts reads them (a collider contact's surface velocity
  /// is in wall_vc, not here, which pairs would carry for nothing).
  struct Contact {
    std::uint32_t i, j;  ///< particles; i == kCollider: j against collider `collider`
    std::uint32_t collider = 0;
    Vec3 n;             ///< unit, from i to j (from the collider's surface to j)
    double m_eff;       ///< 1 / (1/m_i + 1/m_j); m_j against a collider
    double target;      ///< wanted separating normal speed after the solve
    double depth;       ///< overlap (m); negative: gap to a collider
    double mu;
    double pn = 0.0;    ///< accumulated normal impulse (N s), >= 0; solve() starts from it
                        ///< (the warm start: the previous step's impulse, else 0)
    Vec3 pt = Vec3::Zero();  ///< accumulated friction impulse, likewise
  };
  std::vector<Contact> contacts;
  /// (m/s) velocity of the collider's surface point of each collider contact: they are the last
  /// wall_vc.size() of `contacts`, in the same order (find_collider_contacts() appends both).
  std::vector<Vec3> wall_vc;
  /// Fills `contacts` from x/radius with a uniform grid (§2.3.1). Cell size: 2 x the mean
  /// diameter, or the largest diameter if that is bigger, so the 27 neighbouring cells hold
  /// every contact; particles are sorted by cell and each pair is tested once, from the earlier
  /// cell (half stencil). When the largest would need cells over 4 x those, a hashed multi-level
  /// grid (Coutinho §2.3.2): cells doubling per level, each particle in the finest level that
  /// holds its reach, pairs across levels searched from the smaller particle in the larger
  /// one's level. Contacts come in a fixed order (deterministic), not by particle index.
  /// With h > 0 (s, the step), pairs up to pair_margin_fraction x the smaller radius apart and
  /// not approaching faster than contact_speed are speculative resting contacts (target
  /// -gap / h); with h = 0 only overlaps count.
  void find_contacts(double contact_speed, double h = 0.0);
  /// Appends the collider contacts (closest features within the margin) of particles with
  /// `collides` set (all when it is empty), h (s) the step.
  void find_collider_contacts(const std::vector<Collider>& colliders, double h,
                              double contact_speed);
  /// Sequential impulses over `contacts` for `iterations` sweeps, starting from (and applying)
  /// the impulses the contacts hold: the warm start, zero as find_contacts() leaves them.
  void solve();
  /// Moves positions to remove position_fraction of each overlap beyond the slop (velocities
  /// untouched): a contact found at depth d > 0 ends at no more than d - position_fraction x
  /// (d - slop) (pairs; colliders: (1 - position_fraction) d), one found apart (speculative) at
  /// no more than 0: it may close its gap but not overlap. Colliders do not move, their
  /// contacts' depths are measured from x_before (set to x if it is not filled). Nonlinear
  /// Gauss–Seidel over the contacts, as Box2D v2's position correction.
  void project_positions();
  /// project_positions() over the contacts in the order of the last solve()'s sweeps when
  /// work_order, its runs of one wave in SIMD lanes (the same bits, faster; only while the
  /// contacts are those that solve() had).
  void project_positions(bool work_order);
  double cell_size = 0.0;  ///< (m) of the last find_contacts(), at its finest level
  int levels = 1;          ///< grid levels of the last find_contacts() (1: uniform grid)

  static constexpr std::uint32_t kRemoved = 0xffffffffu;  ///< remap_colliders: gone
  /// The world's collider array changed (a body and its shapes were removed): warm-start entries
  /// against collider k now name new_index[k], or are dropped when it is kRemoved.
  void remap_colliders(const std::vector<std::uint32_t>& new_index);
  /// A system was removed: its group's cache is dropped (entries of its particles in other
  /// groups' caches never match again: serials are not reused).
  void forget_system(std::uint32_t serial);
  /// The warm-start caches (the previous step's resting impulses of every group), the only
  /// state kept from one step to the next, for World::save_state / load_state.
  void save_warm(StateWriter& out) const;
  void load_warm(StateReader& in);

 private:
  /// Previous step's resting impulses of one group (keyed by its first system). Two forms of
  /// the same entries. In key order (ki ascending, ties in contact order) a particle's entries
  /// are found by its key whatever became of the store; the saved state holds this form. In
  /// contact order (`owner` filled) they are as that step's contacts left them, which costs the
  /// store a sequential copy instead of a scatter into key order, and lets the next step find a
  /// particle's entries through its working index while the stores' particles stay where they
  /// were, births after them allowed (a particle's working index moves little from one step to
  /// the next, so the lookups stay near each other in memory). key_order() turns the second form
  /// into the first.
  struct WarmCache {
    std::uint32_t group = 0;
    std::vector<std::uint64_t> ki, kj;  ///< kj: particle key, or collider index for walls
    std::vector<Vec3> n, pt;
    std::vector<double> pn;
    /// ki, kj, n, pt and pn to m entries.
    void resize_entries(std::size_t m) {
      ki.resize(m);
      kj.resize(m);
      n.resize(m);
      pt.resize(m);
      pn.resize(m);
    }
    // Contact order only (owner empty in key order):
    std::vector<std::uint32_t> owner;  ///< each entry's particle, that step's working index
    std::vector<std::uint32_t> perm;   ///< that step's perm_ (working -> flat index)
    std::vector<std::uint64_t> keys;   ///< that step's key_flat_
    /// Per working index k, n + 1 of each: the first particle-pair entry (pair_first) and the
    /// first collider entry (wall_first) of a particle at k or later, so that particle k's are
    /// [first[k], first[k + 1]); empty when there are none of that kind.
    std::vector<std::uint32_t> pair_first, wall_first;
    /// The ranges hold: each kind's owners ascend (false in the hashed grid's contact order, and
    /// key order is then the only way in).
    bool by_place = false;
  };
  std::vector<WarmCache> caches_;
  WarmCache key_order_tmp_;  ///< key_order()'s destination, swapped in (no allocation a step)
  std::vector<std::uint32_t> prev_working_;  ///< load_warm_start(): flat index -> the cache's working index
  void load_warm_start(WarmCache& c);
  void store_warm_start(WarmCache& c);
  /// Puts a contact-order cache into key order (no-op for one already so); `parts` threads.
  static void key_order(WarmCache& c, int parts, CountingSortScratch& scratch, WarmCache& tmp);

  // Uniform grid (one level): particles sorted by cell (x-major linear cell index, then particle
  // index) with a counting sort over the cells of the particles' bounding box (a comparison sort
  // of the same keys when that box has far more cells than particles), read as contiguous cell
  // ranges (Green 2010). run() reorders its working arrays into this order, so the pair search,
  // the solve and the projection read memory in order.
  /// Picks cell_size and levels for the current radii (h > 0: with the speculative margin).
  void choose_cells(double h);
  double max_radius_ = 0.0;  ///< (m) the largest radius at the last choose_cells()
  /// Sorts the particles into cells of cell_size (order_, cell_key_/cell_first_, sx_..sr_);
  /// false when the particles span more than 2^21 cells on an axis (the hashed grid then).
  /// With `sorted_copies` false, sx_..sr_ are left to the caller (run(): fill_working()).
  bool build_grid(bool sorted_copies = true);
  /// Pairs over the sorted grid, half stencil, in (cell, particle, neighbour cell, particle)
  /// order of the sorted positions; contacts name particles by index (order_).
  void find_pairs(double contact_speed, double h);
  /// The hashed grid of Coutinho §2.3.1–2.3.2 (multi-level, or a uniform grid too wide to sort).
  void find_contacts_hashed(double contact_speed, double h);
  /// Appends to `out` the contact of i and j, d2 (m²) apart within reach, unless they are apart
  /// and approaching faster than contact_speed (see find_contacts()).
  void try_pair(std::uint32_t i, std::uint32_t j, double d2, double contact_speed, double h,
                std::vector<Contact>& out) {
    try_pair(i, j, d2, x[j] - x[i], contact_speed, h, out);
  }
  /// The same with d = x[j] - x[i] (m) given: the pair search has the sorted copies of both
  /// positions at hand (the same doubles), where x[j] of a neighbouring plane's particle is a
  /// cache miss.
  void try_pair(std::uint32_t i, std::uint32_t j, double d2, const Vec3& d, double contact_speed,
                double h, std::vector<Contact>& out);
  /// One pair search's scratch: a cell's candidates (sorted position, x, y, z, radius; 8 spare
  /// entries for gather_in_box()) and their squared distances within reach (0: out of reach);
  /// the same of its awake candidates (index into cand_s).
  struct PairSearch {
    std::vector<std::uint32_t> cand_s, hit_u;
    std::vector<double> cand_x, cand_y, cand_z, cand_r, cand_d2;
    std::vector<std::uint32_t> awake_s;
    std::vector<double> awake_x, awake_y, awake_z, awake_r, awake_d2;
  };
  std::vector<PairSearch> search_;  ///< one per thread of find_pairs()
  std::vector<std::size_t> cell_cut_;  ///< find_pairs(): each chunk's first cell, + cells (scratch)
  std::vector<std::vector<Contact>> chunk_out_;  ///< find_pairs(): a chunk's contacts
  std::vector<ClaimRun> pair_runs_;              ///< find_pairs(): each thread's run of chunks
  /// find_pairs() from the awake particles alone (see awake_search_share): each pair within
  /// reach with an awake one, as (lower, higher sorted position, d2), sorted, then try_pair().
  void find_pairs_of_awake(double contact_speed, double h);
  struct ReachPair {
    std::uint32_t lo, hi;
    double d2;
  };
  std::vector<ReachPair> awake_pairs_;  ///< find_pairs_of_awake()'s scratch
  std::vector<double> awake_d2_;        ///< likewise: a run's squared distances within reach
  /// find_pairs() over the occupied cells [cell_begin, cell_end), appending to `out`.
  void find_pairs_in(std::size_t cell_begin, std::size_t cell_end, double contact_speed, double h,
                     PairSearch& ps, std::vector<Contact>& out);
  std::vector<std::uint32_t> order_;       ///< sorted position -> particle index
  std::vector<std::uint32_t> perm_;        ///< run(): working index -> flat (member) index
  std::vector<std::uint64_t> cell_key_;    ///< (particles) linear cell key, then occupied cells'
  std::vector<std::uint32_t> cell_first_;  ///< occupied cell -> first sorted position, + n
  std::vector<std::uint64_t> occupied_;    ///< occupied cells' keys, increasing
  std::vector<double> sx_, sy_, sz_, sr_;  ///< x, y, z, radius in sorted order
  /// run() (fill_working() with the grid's order): the working arrays are in sorted order, so
  /// the sorted radii are `radius` and sr_ is not filled.
  bool sorted_radius_is_radius_ = false;
  [[nodiscard]] const double* sorted_radius() const {
    return sorted_radius_is_radius_ ? radius.data() : sr_.data();
  }
  /// run(): its members' restitution, friction and `collide`, when they are alike (uniform);
  /// the per-particle arrays are then not filled. Reset when run() returns.
  struct UniformSurface {
    bool uniform = false;
    double restitution = 0.0, friction = 0.0;
    bool collide = true;
  };
  UniformSurface surface_;
  std::uint64_t stride_y_ = 0, stride_x_ = 0;  ///< linear key = cx stride_x + cy stride_y + cz
  std::uint64_t cells_x_ = 0;              ///< cells along x (the key's major axis)
  /// Contacts of run() in slabs of grid columns along x: band b holds the pairs whose first
  /// particle lies in its columns (the second lies there or one column on) and the collider
  /// contacts of its particles, so bands two apart share no particle and the solve sweeps the
  /// even bands, then the odd ones, each band in contact order, any number at a time. The bands
  /// depend on the geometry only, so the result is the same at any thread count. Empty: one
  /// sweep in contact order (find_contacts() used directly).
  struct Band {
    std::uint32_t pair_begin, pair_end, wall_begin, wall_end;
    /// (work_ positions, set by schedule()) where the band's lone pairs and lone collider
    /// contacts start: [pair_lone, pair_end) and [wall_lone, wall_end) (see `lone_contacts`).
    std::uint32_t pair_lone = 0, wall_lone = 0;
  };
  std::vector<Band> bands_;
  std::vector<std::uint32_t> band_first_;  ///< band -> its first sorted position, + n
  /// A split of the bands over `parts` threads, about even in contacts: thread t takes the bands
  /// [cut[t], cut[t + 1]) (cut has parts + 1 entries).
  void cut_bands(int parts, std::vector<std::size_t>& cut) const;
  std::vector<std::size_t> band_cut_;
  std::vector<ClaimRun> run_;  ///< sweep_bands(): each thread's run of bands per sweep and phase
  /// Applies each contact's impulse (pn n + pt) to its particles' rows of body_ in contact
  /// order, as one pass in contact order would to the bit: with bands over `parts` threads, each
  /// thread owning the particles of its bands (the pairs of the band before its first reach into
  /// it).
  void apply_impulses(int parts);
  /// solve() without its last pass: the velocities after the sweeps are left in body_, and v
  /// keeps the velocities before the solve (run() takes both in one pass).
  void solve_rows();
  CountingSortScratch sort_scratch_;  ///< store_warm_start()'s and build_grid()'s
  /// Fills work_ with the contacts in wavefront order (sched_: work_ position -> contact):
  /// within each band's pairs and walls (the whole list without bands), windows of contacts
  /// sorted by wave, where no two contacts of a wave share a particle and each particle's
  /// contacts keep their order. A Gauss–Seidel sweep over work_ gives the same bits as one over
  /// `contacts` (each update reads and writes only its own two particles), but neighbouring
  /// updates no longer wait on each other, so the processor overlaps them. Each range's lone
  /// contacts (`lone_contacts`) go after its coupled ones, pairs then collider contacts, in runs
  /// for the SIMD lanes; Band::pair_lone and wall_lone (lone_begin_ without bands) mark them.
  void schedule();
  /// `sweeps` passes of over(begin, end) over the contacts: in contact order, or for bands the
  /// even bands' pairs, the odd bands' pairs, then every band's collider contacts, each phase
  /// split over the threads for a large system (the same order at any thread count).
  template <class F>
  /// skip_lone: the sweeps after the first leave out each range's lone contacts (the solve's
  /// work_ positions; the projection, over `contacts` itself, visits them all).
  void sweep_bands(int sweeps, const F& over, bool skip_lone);
  /// What a sweep reads of the contacts, one column per field in wavefront order (88 bytes a
  /// contact against Contact's 128: the large solves are bound by memory). A run of one wave's
  /// contacts is then a run of each column, so the SIMD updates load and store a field for all
  /// their lanes at once instead of assembling it lane by lane. A collider contact's surface
  /// velocity is in work_vc_.
  struct SolverColumns {  // (every column written whole by schedule() before a read)
    RawVector<std::uint32_t> i, j;
    RawVector<double> n[3];
    RawVector<double> m_eff, target, mu, pn;
    RawVector<double> pt[3];
    void resize(std::size_t m);
  };
  SolverColumns work_;
  std::vector<Vec3> work_vc_;
  RawVector<double> work_depth_;  ///< Contact::depth in work order (the projection's)
  RawVector<SolveBody> body_;  ///< solve(): v and inv_mass of each particle during the sweeps
  std::vector<std::uint32_t> sched_, wave_;
  /// schedule(): per thread, each particle's latest wave in the current window, and a window's
  /// contacts per wave
  struct WaveScratch {
    std::vector<std::uint32_t> last_wave, wave_count;
    std::vector<std::uint32_t> coupled, lone;  ///< a range's contacts, lone ones apart
  };
  /// schedule(): each particle's contacts, counted up to 2 (1: any contact of it is lone)
  std::vector<std::uint8_t> degree_;
  std::uint32_t lone_begin_ = 0;  ///< without bands: the work_ position of the first lone contact
  std::vector<WaveScratch> wave_scratch_;
  /// (work_ position) the run of one wave's contacts that starts there, solved together in SIMD
  /// lanes: 3: eight (two groups of four, AVX2), 2: four (AVX2), 1: two (SSE2), 0: this one
  /// alone. schedule() marks only runs that the CPU and max_lanes allow.
  std::vector<std::uint8_t> pair_next_;
  /// Fills bands_ from the contacts of find_pairs() and find_collider_contacts() on sorted
  /// positions (pairs, then walls, each in ascending band order).
  void make_bands(std::size_t pair_count);
  // run(): values in flat (member) order kept across the reordering.
  std::vector<std::uint64_t> key_flat_;
  std::vector<FlatParticle> flat_;
  std::vector<std::uint32_t> warm_first_;  ///< (flat particle) first cache entry with its key
  RawVector<double> half_dt_;              ///< (sorted) min(age, h) / 2
  std::vector<std::size_t> member_base_;  ///< run(): flat index of each member's first particle
  /// run(): every working array in the order perm_ gives, each entry read from its member's
  /// particle (x and radius again: the grid read them in flat order); with `grid`, also the
  /// sorted grid's copies sx_..sr_ (build_grid(false) left them).
  void fill_working(const std::vector<ParticleGroupMember>& members, double h, int par, bool grid);
  std::vector<std::uint8_t> tmp_byte_;
  std::vector<double> inv_mass_awake_;  ///< 1 / mass, for a sleeping particle woken
  bool any_asleep_ = false;  ///< some particle of this run() sleeps
  bool grid_sorted_ = false;  ///< this run() found its pairs on the sorted grid (find_pairs())
  /// Wakes the sleeping particles an awake one hits (see `asleep`), adds the contacts of each
  /// woken one with its sleeping neighbours (from sleeper_pairs_, where the pair search would
  /// have found them) and updates the pairs' m_eff.
  void wake_on_impact(double contact_speed, double h);
  /// Pairs of two sleeping particles within reach, left out of `contacts` by try_pair(): `before`
  /// is the number of contacts found before it.
  struct SleeperPair {
    std::uint32_t i, j, before;
    double d2;
  };
  std::vector<SleeperPair> sleeper_pairs_;
  bool record_sleeper_pairs_ = false;  ///< try_pair() keeps them (the hashed grid's search)
  std::vector<Contact> tmp_contacts_;
  std::vector<std::uint32_t> woken_;
  /// The sorted grid's pairs of the `woken` (ascending) with particles asleep at the pair search,
  /// into sleeper_pairs_ (find_pairs() skipped them).
  void find_sleeping_neighbours(const std::vector<std::uint32_t>& woken, double h);

  /// After the solve: the members' times at rest, and those that fall asleep (flat order).
  void update_rest(const std::vector<ParticleGroupMember>& members, double h, int par);

  std::vector<std::uint32_t> bucket_start_, cursor_, sorted_, cell_hash_;
  std::vector<std::int64_t> cell_xyz_;
  std::vector<std::uint8_t> level_;
};

}  // namespace simreel::sim::detail
