// Collisions with spheres, cylinders and triangle meshes (Coutinho §2.2 AABB tree, §3.4 swept
// spheres, §3.4.2 removal, §3.6.1 response with static/dynamic friction, §3.6.3 resting contact,
// §3.7 first contact with a face, edge or vertex) and hit actions.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <memory>
#include <numbers>

#include "collision/bvh.hpp"
#include "collision/collider_impl.hpp"
#include "collision/mesh_grid.hpp"
#include "collision/narrow_phase.hpp"
#include "sim_test_util.hpp"
#include "simreel/sim/random.hpp"
#include "simreel/sim/world.hpp"

namespace simreel::sim {
namespace {

using test::position_of;
using test::velocity_of;

constexpr double kR = 0.01;  // particle radius (m)
constexpr double kPi = std::numbers::pi;

Material mat(double e, double mu, double mu_s = -1.0) {
  Material m;
  m.restitution = e;
  m.friction = mu;
  m.static_friction = mu_s;
  return m;
}

/// A square of side 2 L in the local xy plane (two triangles, normal +z).
MeshDef quad(double L, const Material& m, const Transform& t = {}) {
  MeshDef d;
  d.vertices = {Vec3(-L, -L, 0), Vec3(L, -L, 0), Vec3(L, L, 0), Vec3(-L, L, 0)};
  d.triangles = {{0, 1, 2}, {0, 2, 3}};
  d.transform = t;
  d.material = m;
  return d;
}

/// Closed box mesh (12 triangles, outward normals) with half extents he.
MeshDef box_mesh(const Vec3& he, const Material& m) {
  MeshDef d;
  for (int k = 0; k < 8; ++k)
    d.vertices.emplace_back((k & 1 ? 1 : -1) * he.x(), (k & 2 ? 1 : -1) * he.y(),
                            (k & 4 ? 1 : -1) * he.z());
  d.triangles = {{0, 2, 3}, {0, 3, 1}, {4, 5, 7}, {4, 7, 6}, {0, 1, 5}, {0, 5, 4},
                 {2, 6, 7}, {2, 7, 3}, {0, 4, 6}, {0, 6, 2}, {1, 3, 7}, {1, 7, 5}};
  d.material = m;
  return d;
}

/// Hemispherical bowl shell of radius R centred at the origin (open at z = 0, lowest at -R).
MeshDef bowl(double R, int rings, int sectors, const Material& m) {
  MeshDef d;
  d.vertices.emplace_back(0, 0, -R);
  for (int i = 1; i <= rings; ++i) {
    const double th = 0.5 * kPi * i / rings;  // from the bottom
    for (int j = 0; j < sectors; ++j) {
      const double ph = 2 * kPi * j / sectors;
      d.vertices.emplace_back(R * std::sin(th) * std::cos(ph), R * std::sin(th) * std::sin(ph),
                              -R * std::cos(th));
    }
  }
  auto at = [&](int i, int j) { return std::uint32_t(1 + (i - 1) * sectors + (j % sectors)); };
  for (int j = 0; j < sectors; ++j) d.triangles.push_back({0, at(1, j), at(1, j + 1)});
  for (int i = 1; i < rings; ++i)
    for (int j = 0; j < sectors; ++j) {
      d.triangles.push_back({at(i, j), at(i + 1, j), at(i + 1, j + 1)});
      d.triangles.push_back({at(i, j), at(i + 1, j + 1), at(i, j + 1)});
    }
  d.material = m;
  return d;
}

ParticleSystemDef probes(bool gravity = true) {
  ParticleSystemDef def = test::spawn_only_system();
  if (!gravity) def.gravity = Vec3::Zero();
  def.emitter.max_particles = 20000;
  return def;
}

// ---------------------------------------------------------------------------------------------
// AABB tree and narrow phase

/// `count` triangles with corners within `size` (m) of centres uniform in [-1, 1]^3.
std::vector<detail::Triangle> random_triangles(Rng& rng, int count, double size) {
  std::vector<detail::Triangle> tris;
  const auto corner = [&](const Vec3& c) {
    return Vec3(c + Vec3(rng.uniform(-size, size), rng.uniform(-size, size), rng.uniform(-size, size)));
  };
  for (int t = 0; t < count; ++t) {
    const Vec3 c(rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1));
    detail::Triangle x{corner(c), corner(c), corner(c), Vec3::Zero()};  // braces: in order
    x.normal = (x.b - x.a).cross(x.c - x.a).normalized();
    tris.push_back(x);
  }
  return tris;
}

TEST(SimCollisionMesh, BvhQueryEqualsBruteForceOnRandomSegments) {
  Rng rng(7, 1);
  const std::vector<detail::Triangle> tris = random_triangles(rng, 400, 0.1);
  const detail::Bvh bvh(tris);
  EXPECT_LE(bvh.depth(), 10);  // median split: ceil(log2(400 / 4)) + 1 = 8
  int hits = 0;
  for (int q = 0; q < 2000; ++q) {
    const Vec3 a(rng.uniform(-1.5, 1.5), rng.uniform(-1.5, 1.5), rng.uniform(-1.5, 1.5));
    const Vec3 d = Vec3(rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1)) *
                   rng.uniform(0.0, 1.0);
    const double r = rng.uniform(0.001, 0.05);
    detail::SweepHit brute, tree;
    for (const auto& t : tris) detail::sweep_triangle(t, a, d, r, brute);
    const Vec3 b = a + d, g = Vec3::Constant(r);
    bvh.query(a.cwiseMin(b) - g, a.cwiseMax(b) + g,
              [&](std::uint32_t t) { detail::sweep_triangle(tris[t], a, d, r, tree); });
    ASSERT_EQ(brute.s, tree.s) << q;
    if (std::isfinite(brute.s)) {
      ++hits;
      EXPECT_EQ(brute.normal, tree.normal);
      EXPECT_EQ(brute.point, tree.point);
    }
  }
  EXPECT_GT(hits, 100);  // the test exercises hits, not only misses (168 with this seed)
}

// The inside test of closed meshes (§3.4.2) casts a long oblique ray (issue 19: pour spent 38 %
// of its time there, visiting every leaf in the box the ray spans). Its tree traversal must meet
// every triangle the ray crosses (the parity is then a brute force's), along any direction, and
// visit far fewer than the segment's box does.
TEST(SimCollisionMesh, BvhRayQueryMeetsEveryCrossedTriangleAndFewOthers) {
  Rng rng(11, 1);
  const std::vector<detail::Triangle> tris = random_triangles(rng, 2000, 0.08);
  const detail::Bvh bvh(tris);
  std::size_t crossed = 0, by_ray = 0, by_box = 0;
  for (int q = 0; q < 3000; ++q) {
    const Vec3 p(rng.uniform(-1.2, 1.2), rng.uniform(-1.2, 1.2), rng.uniform(-1.2, 1.2));
    Vec3 dir(rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1));
    if (q % 4 == 1) dir[q % 3] = 0.0;                       // in a coordinate plane
    if (q % 4 == 2) dir = Vec3::Unit(q % 3) * (q % 8 < 4 ? 1.0 : -1.0);  // along an axis
    dir.normalize();
    const double len = rng.uniform(0.1, 4.0);
    std::vector<std::uint32_t> brute, ray;
    for (std::uint32_t t = 0; t < tris.size(); ++t)
      if (detail::ray_crosses(tris[t], p, dir, len)) brute.push_back(t);
    bvh.ray_query(p, dir, len, 1e-9 * len, [&](std::uint32_t t) {
      ++by_ray;
      if (detail::ray_crosses(tris[t], p, dir, len)) ray.push_back(t);
    });
    std::sort(ray.begin(), ray.end());
    ASSERT_EQ(brute, ray) << "segment " << q;
    crossed += brute.size();
    const Vec3 e = p + len * dir;
    bvh.query(p.cwiseMin(e), p.cwiseMax(e), [&](std::uint32_t) { ++by_box; });
  }
  EXPECT_GT(crossed, 500u);  // hits exercised, not only misses (852 crossings with this seed)
  EXPECT_LT(3 * by_ray, by_box) << by_ray << " triangles visited along the rays, " << by_box
                                << " in their boxes";
}

/// A closed thick hemispherical bowl: outer radius ro, inner ri, rim annulus at z = 0, in the
/// form MeshShape takes (triangles, tree, local box) without the world around it.
detail::MeshShape thick_bowl(double ro, double ri, int rings, int sectors) {
  std::vector<Vec3> v;
  const auto shell = [&](double R) {
    const std::uint32_t base = std::uint32_t(v.size());
    v.emplace_back(0, 0, -R);
    for (int i = 1; i <= rings; ++i)
      for (int j = 0; j < sectors; ++j) {
        const double th = 0.5 * kPi * i / rings, ph = 2 * kPi * j / sectors;
        v.emplace_back(R * std::sin(th) * std::cos(ph), R * std::sin(th) * std::sin(ph),
                       -R * std::cos(th));
      }
    return base;
  };
  const std::uint32_t o = shell(ro), in = shell(ri);
  const auto at = [&](std::uint32_t base, int i, int j) {
    return base + std::uint32_t(1 + (i - 1) * sectors + (j % sectors));
  };
  std::vector<std::array<std::uint32_t, 3>> f;
  for (std::uint32_t base : {o, in}) {
    const bool flip = base == in;  // the inner shell faces the bowl's hollow
    const auto add = [&](std::uint32_t a, std::uint32_t b, std::uint32_t c) {
      f.push_back(flip ? std::array{a, c, b} : std::array{a, b, c});
    };
    for (int j = 0; j < sectors; ++j) add(base, at(base, 1, j + 1), at(base, 1, j));
    for (int i = 1; i < rings; ++i)
      for (int j = 0; j < sectors; ++j) {
        add(at(base, i, j), at(base, i + 1, j + 1), at(base, i + 1, j));
        add(at(base, i, j), at(base, i, j + 1), at(base, i + 1, j + 1));
      }
  }
  for (int j = 0; j < sectors; ++j) {  // the rim joins the two shells
    f.push_back({at(o, rings, j), at(o, rings, j + 1), at(in, rings, j + 1)});
    f.push_back({at(o, rings, j), at(in, rings, j + 1), at(in, rings, j)});
  }
  detail::MeshShape m;
  detail::Aabb box;
  for (const auto& t : f) {
    detail::Triangle x{v[t[0]], v[t[1]], v[t[2]], Vec3::Zero()};
    x.normal = (x.b - x.a).cross(x.c - x.a).normalized();
    m.triangles.push_back(x);
    box.grow(detail::triangle_box(x));
  }
  m.bvh = detail::Bvh(m.triangles);
  m.closed = true;
  m.local_center = 0.5 * (box.lo + box.hi);
  m.local_half = 0.5 * (box.hi - box.lo);
  return m;
}

// Points in the box of a closed thick bowl (the pour demo's): inside the solid exactly where the
// geometry says, in the wall as in the hollow and below it, away from the facets' chord error.
TEST(SimCollisionMesh, ClosedMeshContainsTheSolidOfAThickBowl) {
  const double ro = 0.3, ri = 0.27;
  const int rings = 24, sectors = 64;
  const detail::MeshShape bowl = thick_bowl(ro, ri, rings, sectors);
  // A facet lies inside its sphere by R (1 - cos(half the angle its diagonal spans)), 0.5 mm
  // here: points nearer a sphere than 2 mm are left out.
  const double chord = 2e-3;
  Rng rng(5, 1);
  int in_wall = 0, tested = 0;
  for (int q = 0; q < 20000; ++q) {
    const Vec3 p(rng.uniform(-0.31, 0.31), rng.uniform(-0.31, 0.31), rng.uniform(-0.31, 0.01));
    const double r = p.norm();
    if (std::abs(r - ro) < chord || std::abs(r - ri) < chord || std::abs(p.z()) < 1e-3) continue;
    const bool solid = p.z() < 0.0 && r > ri && r < ro;
    ASSERT_EQ(bowl.contains(p), solid) << p.transpose();
    in_wall += solid;
    ++tested;
  }
  EXPECT_GT(in_wall, 300);  // points in the 3 cm wall were tested, not only the hollow and air
  EXPECT_GT(tested, 15000);
}

// The cloth contacts' tree (issue 14/16: tablecloth): its traversal against itself gives every
// pair of overlapping boxes exactly once, and after the boxes move, a refitted tree's queries
// and pairs are the brute-force ones again (only its shape is the old one's).
TEST(SimCollisionMesh, BvhSelfPairsAndRefitEqualBruteForce) {
  Rng rng(23, 2);
  auto random_boxes = [&](std::vector<detail::Triangle>& tris, double spread) {
    for (auto& t : tris) {
      const Vec3 c(rng.uniform(-1, 1), rng.uniform(-1, 1), spread * rng.uniform(-1, 1));
      const Vec3 e(rng.uniform(0, .08), rng.uniform(0, .08), rng.uniform(0, .08));
      t = detail::Triangle{c - e, c + e, c - e, Vec3::Zero()};
    }
  };
  auto meet = [](const detail::Triangle& a, const detail::Triangle& b) {
    return (a.a.array() <= b.b.array()).all() && (b.a.array() <= a.b.array()).all();
  };
  auto brute_pairs = [&](const std::vector<detail::Triangle>& tris) {
    std::vector<std::pair<std::uint32_t, std::uint32_t>> out;
    for (std::uint32_t i = 0; i < tris.size(); ++i)
      for (std::uint32_t j = i + 1; j < tris.size(); ++j)
        if (meet(tris[i], tris[j])) out.emplace_back(i, j);
    return out;
  };
  auto tree_pairs = [&](const detail::Bvh& bvh, const std::vector<detail::Triangle>& tris) {
    std::vector<std::pair<std::uint32_t, std::uint32_t>> out;
    bvh.self_pairs([&](std::uint32_t i, std::uint32_t j) {
      if (meet(tris[i], tris[j])) out.emplace_back(std::min(i, j), std::max(i, j));
    });
    std::sort(out.begin(), out.end());  // duplicates stay: each pair must come once
    return out;
  };
  std::vector<detail::Triangle> tris(700);
  random_boxes(tris, 0.1);  // a sheet-like layer: many overlaps
  detail::Bvh bvh(tris);
  const auto first = brute_pairs(tris);
  EXPECT_GT(first.size(), 500u);  // 837 with this seed
  EXPECT_EQ(tree_pairs(bvh, tris), first);
  // Every box moved (another random layer, tilted): the refitted tree is still exact.
  random_boxes(tris, 1.0);
  bvh.refit(tris);
  const auto second = brute_pairs(tris);
  EXPECT_NE(second, first);
  EXPECT_EQ(tree_pairs(bvh, tris), second);
  for (int q = 0; q < 300; ++q) {
    const Vec3 c(rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1));
    const Vec3 lo = c - Vec3::Constant(0.1), hi = c + Vec3::Constant(0.1);
    std::vector<std::uint32_t> brute, tree;
    const detail::Triangle box{lo, hi, lo, Vec3::Zero()};
    for (std::uint32_t t = 0; t < tris.size(); ++t)
      if (meet(tris[t], box)) brute.push_back(t);
    bvh.query(lo, hi, [&](std::uint32_t t) {
      if (meet(tris[t], box)) tree.push_back(t);
    });
    std::sort(tree.begin(), tree.end());
    ASSERT_EQ(tree, brute) << q;
  }
}

TEST(SimCollisionMesh, CulledTriangleSweepEqualsEveryFeatureTested) {
  // sweep_triangle skips the features a segment cannot come within r of; it must give the bits
  // of testing them all. Segments aimed at the hard places: lying on the face (the resting
  // drop), grazing an edge's or a vertex's reach within 1e-3 .. 1e-12 of r on either side, and
  // random ones; near the origin and 1 km from it; with and without an earlier hit known.
  Rng rng(19, 3);
  int hits = 0, culled_cases = 0;
  for (int q = 0; q < 40000; ++q) {
    const double far = q % 4 == 3 ? 1000.0 : 0.0;
    const Vec3 c = Vec3(rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1)) + Vec3::Constant(far);
    const double size = rng.uniform(0.05, 0.5);
    detail::Triangle t{c + size * Vec3(rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1)),
                       c + size * Vec3(rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1)),
                       c + size * Vec3(rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1)),
                       Vec3::Zero()};
    t.normal = (t.b - t.a).cross(t.c - t.a).normalized();
    const double r = rng.uniform(0.002, 0.05);
    const Vec3* v[3] = {&t.a, &t.b, &t.c};
    const int k = int(rng.uniform() * 3.0) % 3;
    const Vec3 e = *v[(k + 1) % 3] - *v[k];
    const Vec3 in = t.normal.cross(e).normalized();  // in-plane, pointing into the triangle
    const double eps[] = {1e-3, 1e-7, 1e-10, 1e-12, 0.0, -1e-12, -1e-10, -1e-7, -1e-3};
    const double rel = eps[int(rng.uniform() * 9.0) % 9];
    Vec3 a, d;
    switch (q % 3) {
      case 0: {  // lying on the face, sliding and pressed in a little
        const double u = rng.uniform(0, 1), w = rng.uniform(0, 1 - u);
        a = t.a + u * (t.b - t.a) + w * (t.c - t.a) + r * (1.0 + rel) * t.normal;
        d = 0.01 * Vec3(rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1)) -
            rng.uniform(0, 1e-4) * t.normal;
        break;
      }
      case 1: {  // grazing edge k's reach from either side, or its vertex's
        const double u = rng.uniform(-0.2, 1.2);
        const double side = rng.uniform() < 0.5 ? -1.0 : 1.0;
        a = *v[k] + u * e + side * r * (1.0 + rel) * in + rng.uniform(-1, 1) * r * t.normal;
        d = 0.02 * Vec3(rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1));
        d -= d.dot(in) * in;  // along the edge's reach: the distance to its line stays put
        break;
      }
      default:
        a = c + Vec3(rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1)) * (size + 0.1);
        d = Vec3(rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1)) * rng.uniform(0, 0.5);
    }
    detail::SweepHit all, culled;
    if (rng.uniform() < 0.2) all.s = culled.s = rng.uniform() < 0.3 ? 0.0 : rng.uniform(0, 1);
    detail::sweep_triangle_all(t, a, d, r, all);
    detail::sweep_triangle(t, a, d, r, culled);
    ASSERT_EQ(all.s, culled.s) << q;
    ASSERT_EQ(all.normal, culled.normal) << q;
    ASSERT_EQ(all.point, culled.point) << q;
    if (std::isfinite(all.s)) ++hits;
    culled_cases += q % 3 == 1 && !std::isfinite(all.s);
  }
  EXPECT_GT(hits, 8000);         // hits of every kind are compared, not only misses
  EXPECT_GT(culled_cases, 2000);  // and misses at the edge of an edge's reach
}

/// True when triangle t and the box [lo, hi] are not separated by more than 1e-12 m along any of
/// the separating-axis theorem's 13 axes (the box's three, the triangle's normal, the nine
/// edge-axis cross products; Akenine-Möller 2001): they touch or overlap, or nearly.
bool triangle_meets_box(const detail::Triangle& t, const Vec3& lo, const Vec3& hi) {
  const Vec3 c = 0.5 * (lo + hi), e = 0.5 * (hi - lo);
  const Vec3 v[3] = {t.a - c, t.b - c, t.c - c};
  const auto separated = [&](const Vec3& axis) {
    const double p0 = axis.dot(v[0]), p1 = axis.dot(v[1]), p2 = axis.dot(v[2]);
    const double r = e.dot(axis.cwiseAbs());
    const double tol = 1e-12 * (1.0 + axis.norm());
    return std::min({p0, p1, p2}) > r + tol || std::max({p0, p1, p2}) < -r - tol;
  };
  const Vec3 edges[3] = {v[1] - v[0], v[2] - v[1], v[0] - v[2]};
  for (int k = 0; k < 3; ++k)
    if (separated(Vec3::Unit(k))) return false;
  if (separated(edges[0].cross(edges[1]))) return false;
  for (const Vec3& f : edges)
    for (int k = 0; k < 3; ++k)
      if (separated(Vec3::Unit(k).cross(f))) return false;
  return true;
}

TEST(SimCollisionMesh, MeshGridColumnsClearOnlyBoxesThatNoTriangleMeets) {
  // collide() drops a particle near an open mesh's AABB when the grid's columns show that no
  // triangle has a point in its swept box (MeshGrid::clear_of): its sweep would meet nothing.
  // So clear_of() may say true only where no triangle meets the box (a separating-axis test,
  // here), and no sweep of a sphere whose grown segment lies in the box hits anything. A height
  // field with a few large tilted triangles over it; boxes above, below and through it, just
  // above the surface under them, and boxes whose bottom is exactly a triangle's top or one ulp
  // above.
  const auto height = [](double x, double y) { return 0.3 * std::sin(1.7 * x) * std::cos(1.1 * y); };
  std::vector<detail::Triangle> tris;
  const int n = 40;
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const double x0 = -2.0 + 4.0 * i / n, x1 = -2.0 + 4.0 * (i + 1) / n;
      const double y0 = -2.0 + 4.0 * j / n, y1 = -2.0 + 4.0 * (j + 1) / n;
      const Vec3 a(x0, y0, height(x0, y0)), b(x1, y0, height(x1, y0)), c(x1, y1, height(x1, y1)),
          d(x0, y1, height(x0, y1));
      tris.push_back({a, b, c, Vec3::Zero()});
      tris.push_back({a, c, d, Vec3::Zero()});
    }
  Rng rng(17, 3);
  for (int t = 0; t < 12; ++t) {
    const Vec3 c(rng.uniform(-1.5, 1.5), rng.uniform(-1.5, 1.5), rng.uniform(0.4, 0.8));
    tris.push_back({c, c + Vec3(0.5, 0.1, 0.2), c + Vec3(0.05, 0.4, -0.3), Vec3::Zero()});
  }
  for (auto& t : tris) t.normal = (t.b - t.a).cross(t.c - t.a).normalized();
  const auto box_of = [](const detail::Triangle& t) {
    detail::Aabb b;
    b.grow(t.a);
    b.grow(t.b);
    b.grow(t.c);
    return b;
  };
  const detail::Bvh bvh(tris);
  const detail::MeshGrid grid(tris, bvh.visit_order());
  // (the height field's largest height over the square [x - w, x + w] x [y - w, y + w]: its
  // triangles are planar between grid points, so the largest corner value of the grid squares
  // the square spans)
  const auto surface_max = [&](double x, double y, double w) {
    double m = -1e300;
    const int i0 = std::max(0, int(std::floor((x - w + 2.0) * n / 4.0))),
              i1 = std::min(n, int(std::ceil((x + w + 2.0) * n / 4.0)));
    const int j0 = std::max(0, int(std::floor((y - w + 2.0) * n / 4.0))),
              j1 = std::min(n, int(std::ceil((y + w + 2.0) * n / 4.0)));
    for (int j = j0; j <= j1; ++j)
      for (int i = i0; i <= i1; ++i)
        m = std::max(m, height(-2.0 + 4.0 * i / n, -2.0 + 4.0 * j / n));
    return m;
  };
  int clear = 0, well_above = 0, well_above_clear = 0, touching = 0, just_above = 0,
      just_above_clear = 0, cleared_in_boxes = 0;
  for (int q = 0; q < 20000; ++q) {
    const double x = rng.uniform(-2.5, 2.5), y = rng.uniform(-2.5, 2.5);
    const Vec3 half(rng.uniform(0.0, q % 7 == 0 ? 0.6 : 0.04), rng.uniform(0.0, q % 7 == 0 ? 0.6 : 0.04),
                    rng.uniform(0.0, 0.05));
    Vec3 lo(x - half.x(), y - half.y(), 0.0), hi(x + half.x(), y + half.y(), 0.0);
    const int kind = q % 6;
    if (kind <= 1) {  // bottom exactly on a triangle's top, or one ulp above it
      const detail::Aabb t = box_of(tris[std::size_t(rng.uniform(0, double(tris.size()) - 0.01))]);
      lo.head<2>() = t.lo.head<2>();
      hi.head<2>() = t.lo.head<2>() + 2.0 * half.head<2>();
      lo.z() = kind == 0 ? t.hi.z() : std::nextafter(t.hi.z(), 1.0);
      touching += kind == 0;
    } else if (kind == 5) {  // 1 to 4 cm above the highest surface under it (a drop about to land)
      lo.z() = surface_max(x, y, std::max(half.x(), half.y())) + rng.uniform(0.01, 0.04);
    } else {  // above, below or through the surface
      lo.z() = height(x, y) + rng.uniform(-0.6, 0.6);
    }
    hi.z() = lo.z() + 2.0 * half.z();
    const bool inside = std::abs(x) < 1.9 && std::abs(y) < 1.9;
    const bool above = kind >= 2 && kind <= 4 && lo.z() > height(x, y) + 0.35 && inside;
    const bool cl = grid.clear_of(lo, hi);
    if (above) {
      ++well_above;
      well_above_clear += cl;
    }
    if (kind == 5 && inside) {
      ++just_above;
      just_above_clear += cl;
    }
    if (!cl) continue;
    ++clear;
    // The triangles whose boxes reach into the box (no other can meet it or a sweep inside it).
    // Where there are some, columns made of the triangles' boxes (before stop 54) would not have
    // cleared the box: the sweep would be handed them and miss.
    std::vector<const detail::Triangle*> reach;
    for (const auto& t : tris)
      if (box_of(t).overlaps(lo, hi)) reach.push_back(&t);
    cleared_in_boxes += !reach.empty();
    for (const detail::Triangle* t : reach) ASSERT_FALSE(triangle_meets_box(*t, lo, hi)) << q;
    // Spheres swept along the box's four diagonals, grown to its smallest half side: no hit.
    const double r = std::min({half.x(), half.y(), half.z()});
    for (int d = 0; d < 4; ++d) {
      const Vec3 a(d & 1 ? hi.x() - r : lo.x() + r, d & 2 ? hi.y() - r : lo.y() + r, lo.z() + r);
      const Vec3 b(d & 1 ? lo.x() + r : hi.x() - r, d & 2 ? lo.y() + r : hi.y() - r, hi.z() - r);
      detail::SweepHit h;
      for (const detail::Triangle* t : reach) detail::sweep_triangle(*t, a, b - a, r, h);
      ASSERT_FALSE(h.s <= 1.0) << q << " " << d;
    }
  }
  EXPECT_GT(touching, 2500);
  EXPECT_GT(clear, 4000);
  // Most boxes well above the terrain are told from the columns (the tilted triangles hang over
  // some of it).
  EXPECT_GT(well_above_clear, well_above / 2) << well_above;
  // Boxes 1 to 4 cm above the highest surface under them (drops about to land): most are
  // cleared. And boxes that a triangle's box reaches into are cleared too (the columns are the
  // triangles clipped to each column, not the triangles' boxes): the sweeps they are spared.
  EXPECT_GT(just_above, 1000);
  EXPECT_GT(just_above_clear, just_above / 2) << just_above;  // (67 % here)
  EXPECT_GT(cleared_in_boxes, 400) << clear;  // (833 here; none with columns of the boxes)
}

TEST(SimCollisionMesh, RainOnAnOpenTerrainLandsOnItAtAnyThreadCount) {
  // 17,000 drops (past the two-thread threshold) rain onto an open height field that does not
  // move, so collide() takes its Z-order pass with the mesh prefetch and rejects drops above
  // the terrain by the grid's columns. Every drop lands and none goes through, with and without
  // drag (both rejection paths), and one and two threads give the same state.
  const auto height = [](double x, double y) { return 0.25 * std::sin(1.3 * x) * std::cos(0.9 * y); };
  constexpr double kR = 0.01;
  const auto run = [&](int threads, double drag, std::vector<float>& z_out, std::vector<float>& ground) {
    World w(WorldDef{1.0 / 240, 1, 0.05, threads});
    MeshDef md;
    test::fill_height_field(md, 64, 3.0, height);
    md.material = Material(0.2, 0.5);
    w.add_mesh(md);
    ParticleSystemDef def;
    def.emitter.rate = 0.0;
    def.emitter.max_particles = 17000;
    def.drag = drag;
    const auto ps = w.add_particle_system(def);
    Rng rng(8);
    for (int i = 0; i < 17000; ++i) {
      const double x = rng.uniform(-2.8, 2.8), y = rng.uniform(-2.8, 2.8);
      w.spawn_particle(ps, Vec3(x, y, height(x, y) + rng.uniform(0.05, 1.2)), Vec3(0, 0, -rng.uniform(0, 4)),
                       1e-3, kR, 100.0);
    }
    for (int k = 0; k < 240; ++k) w.advance(1.0 / 240);
    const ParticleView v = w.particles(ps);
    z_out.clear();
    ground.clear();
    for (std::size_t i = 0; i < v.count; ++i) {
      z_out.push_back(v.position[3 * i + 2]);
      ground.push_back(float(height(v.position[3 * i], v.position[3 * i + 1])));
    }
    return w.state_hash();
  };
  for (const double drag : {0.0, 2e-4}) {
    std::vector<float> z, g;
    const std::uint64_t one = run(1, drag, z, g);
    ASSERT_EQ(z.size(), 17000u);
    int landed = 0;
    for (std::size_t i = 0; i < z.size(); ++i) {
      // The facets lie within 3 mm of the sine they sample (curvature x cell² / 8).
      ASSERT_GT(z[i] - g[i], kR - 3e-3) << i << " drag " << drag;
      landed += z[i] - g[i] < kR + 3e-3;
    }
    EXPECT_GT(landed, 16000) << "drag " << drag;
    if (drag == 0.0) {
      std::vector<float> z2, g2;
      EXPECT_EQ(run(2, drag, z2, g2), one);
    }
  }
}

TEST(SimCollisionMesh, MeshGridPrefetchNamesOnlyCellsOfTheGrid) {
  // collide() walks the particles near a mesh ahead of their sweeps and asks the grid for the
  // memory each will read (MeshGrid::cell_of, then prefetch() stage by stage). A hint, so no
  // result can show it; what can go wrong is an index past the grid. Points inside, on every
  // face and corner of the bounds, just outside, far away and not finite: a cell of the grid
  // exactly when inside the bounds, and each stage reads only the grid's own arrays (the
  // sanitizer build runs this).
  std::vector<detail::Triangle> tris;
  Rng rng(5, 1);
  for (int t = 0; t < 400; ++t) {
    const Vec3 c(rng.uniform(-2, 2), rng.uniform(-2, 2), rng.uniform(-0.3, 0.3));
    detail::Triangle x{c, c + Vec3(0.2, 0, 0.05), c + Vec3(0, 0.2, -0.05), Vec3::Zero()};
    x.normal = (x.b - x.a).cross(x.c - x.a).normalized();
    tris.push_back(x);
  }
  const detail::Bvh bvh(tris);
  const detail::MeshGrid grid(tris, bvh.visit_order());
  ASSERT_GT(grid.cell_count(), 8u);
  Vec3 lo = tris[0].a, hi = tris[0].a;
  for (const auto& t : tris)
    for (const Vec3* v : {&t.a, &t.b, &t.c}) {
      lo = lo.cwiseMin(*v);
      hi = hi.cwiseMax(*v);
    }
  const double nan = std::numeric_limits<double>::quiet_NaN(), inf = std::numeric_limits<double>::infinity();
  int inside = 0;
  for (int q = 0; q < 3000; ++q) {
    Vec3 p;
    for (int k = 0; k < 3; ++k) {
      const double u = rng.uniform();
      p[k] = u < 0.3 ? lo[k] : u < 0.6 ? hi[k] : u < 0.65 ? std::nextafter(hi[k], inf)
           : u < 0.7 ? std::nextafter(lo[k], -inf) : rng.uniform(lo[k] - 1, hi[k] + 1);
    }
    if (q % 50 == 0) p[q / 50 % 3] = q % 100 == 0 ? nan : -inf;
    const bool in = (p.array() >= lo.array()).all() && (p.array() <= hi.array()).all();
    const std::int64_t cell = grid.cell_of(p);
    if (in) {
      ++inside;
      ASSERT_GE(cell, 0) << q;
      ASSERT_LT(std::size_t(cell), grid.cell_count()) << q;
    } else {
      ASSERT_EQ(cell, -1) << q;
    }
    for (int stage = 0; stage < 3; ++stage) grid.prefetch(cell, stage, p);
  }
  EXPECT_GT(inside, 500);
}

/// Asks the grid and the tree about [lo, hi]: true when the grid answered (false: it declined, a
/// large box). The grid must hand out every triangle whose own box overlaps the query, in the
/// order the tree visits them (so a first-hit sweep over either gives the same bits); it may add a
/// triangle whose box misses the query by float rounding (it tests boxes in floats), which the
/// exact sweep then rejects. `found`: the triangles it handed out.
bool grid_answers_like_the_tree(const std::vector<detail::Triangle>& tris, const detail::Bvh& bvh,
                                const detail::MeshGrid& grid, const Vec3& lo, const Vec3& hi, int& found) {
  const auto box_of = [&](std::uint32_t t) {
    detail::Aabb b;
    b.grow(tris[t].a);
    b.grow(tris[t].b);
    b.grow(tris[t].c);
    return b;
  };
  std::vector<std::uint32_t> from_tree, from_grid;
  bvh.query(lo, hi, [&](std::uint32_t t) {
    if (box_of(t).overlaps(lo, hi)) from_tree.push_back(t);
  });
  if (!grid.query(lo, hi, [&](const detail::SweepTriangle& x, std::uint32_t t) {
        EXPECT_EQ(x.t.a, tris[t].a);  // the grid's copy of the triangle
        EXPECT_EQ(x.t.normal, tris[t].normal);
        if (box_of(t).overlaps(lo, hi)) {
          from_grid.push_back(t);
        } else {  // one more within float rounding of the box
          const Vec3 tol = Vec3::Constant(1e-6);  // float rounding of coordinates below 10 m
          EXPECT_TRUE(box_of(t).overlaps(lo - tol, hi + tol)) << t;
        }
      }))
    return false;
  found += int(from_grid.size());
  EXPECT_EQ(from_grid, from_tree) << lo.transpose() << " .. " << hi.transpose();
  return true;
}

TEST(SimCollisionMesh, MeshGridGivesTheTreesTrianglesInTheTreesOrder) {
  // grid_answers_like_the_tree(), or the grid declines (a large box). Triangles of mixed sizes;
  // small and large query boxes, and boxes that touch a triangle's box or miss it by 1e-9 m.
  Rng rng(11, 2);
  std::vector<detail::Triangle> tris;
  for (int t = 0; t < 3000; ++t) {
    const Vec3 c(rng.uniform(-5, 5), rng.uniform(-5, 5), rng.uniform(-1, 1));
    const double e = t % 50 == 0 ? 1.5 : 0.15;
    detail::Triangle x{c + e * Vec3(rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1)),
                       c + e * Vec3(rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1)),
                       c + e * Vec3(rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1)),
                       Vec3::Zero()};
    x.normal = (x.b - x.a).cross(x.c - x.a).normalized();
    tris.push_back(x);
  }
  const detail::Bvh bvh(tris);
  const detail::MeshGrid grid(tris, bvh.visit_order());
  int answered = 0, declined = 0, found = 0;
  for (int q = 0; q < 4000; ++q) {
    const Vec3 c(rng.uniform(-6, 6), rng.uniform(-6, 6), rng.uniform(-1.5, 1.5));
    const Vec3 h = Vec3::Constant(q % 10 == 0 ? rng.uniform(0.5, 3.0) : rng.uniform(0.0, 0.1));
    Vec3 lo = c - h, hi = c + h;
    if (q % 4 == 1) {  // starting at a triangle's box, or just beyond it, on one axis
      const detail::Triangle& t = tris[std::size_t(rng.uniform(0, 2999.99))];
      const int k = q / 4 % 3;
      lo[k] = std::max({t.a[k], t.b[k], t.c[k]}) + (q % 8 == 1 ? 0.0 : 1e-9);
      hi[k] = lo[k] + 0.05;
    }
    if (grid_answers_like_the_tree(tris, bvh, grid, lo, hi, found)) {
      ++answered;
    } else {
      ++declined;
    }
    if (HasFailure()) return;
  }
  EXPECT_GT(answered, 3000);  // small boxes are answered by the grid
  EXPECT_GT(declined, 100);   // large ones go to the tree
  EXPECT_GT(found, 2000);     // and the answers are not empty
}

TEST(SimCollisionMesh, MeshGridHaloListsAnswerBoxesAcrossCellSidesLikeTheTree) {
  // A particle's box near the bowl's shell spans two to eight of the grid's cells most of the
  // time; the grid answers it from one cell's halo list (the triangles whose boxes overlap the
  // cell grown by MeshGrid::kHaloCells of its side) when the box lies within that halo. Boxes
  // about the shell from a tenth of the halo to twice it (the larger ones span more than a
  // halo: the cells' own lists answer them), many of them reaching just to a cell's halo or
  // just past it: every answer is the tree's.
  const MeshDef b = bowl(0.3, 16, 48, mat(0.3, 0.5));
  std::vector<detail::Triangle> tris;
  for (const auto& t : b.triangles) {
    detail::Triangle x{b.vertices[t[0]], b.vertices[t[1]], b.vertices[t[2]], Vec3::Zero()};
    x.normal = (x.b - x.a).cross(x.c - x.a).normalized();
    tris.push_back(x);
  }
  const detail::Bvh bvh(tris);
  const detail::MeshGrid grid(tris, bvh.visit_order());
  ASSERT_GT(grid.halo(), 0.0);  // the bowl's halo lists are within their budget
  const double halo = grid.halo(), cell = halo / detail::MeshGrid::kHaloCells;
  Rng rng(29, 1);
  int answered = 0, found = 0;
  for (int q = 0; q < 20000; ++q) {
    Vec3 d(rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 0.05));
    d.normalize();
    const Vec3 p = (0.3 + rng.uniform(-0.03, 0.01)) * d;
    const double h = halo * rng.uniform(0.1, 2.0);
    Vec3 lo = p - Vec3::Constant(h), hi = p + Vec3::Constant(h);
    if (q % 3 == 0) {  // on one axis, reaching from about the middle of a cell to its halo's side
      const int k = q / 3 % 3;
      const double side = grid.cell_side(lo[k] + h, k) + (q % 2 == 0 ? cell + halo : -halo);
      const double nudge = q % 6 < 2 ? 0.0 : q % 6 < 4 ? 1e-9 : -1e-9;
      (q % 2 == 0 ? hi[k] : lo[k]) = side + nudge;
    }
    if (grid_answers_like_the_tree(tris, bvh, grid, lo, hi, found)) ++answered;
    if (HasFailure()) return;
  }
  EXPECT_GT(answered, 15000);  // the largest boxes span more than kMaxCells cells: the tree
  EXPECT_GT(found, 20000);
}

TEST(SimCollisionMesh, SweptSphereHitsFaceEdgeAndVertexWithTheirNormals) {
  const detail::Triangle t{Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3::UnitZ()};
  const double r = 0.1;
  {  // face, from below (two-sided): contact when the centre is r under the plane
    detail::SweepHit h;
    detail::sweep_triangle(t, Vec3(0.2, 0.2, -1), Vec3(0, 0, 2), r, h);
    EXPECT_NEAR(h.s, 0.45, 1e-12);
    EXPECT_TRUE(h.normal.isApprox(-Vec3::UnitZ()));
  }
  {  // edge y = 0 from -y, moving horizontally at the plane's height
    detail::SweepHit h;
    detail::sweep_triangle(t, Vec3(0.5, -1, 0), Vec3(0, 2, 0), r, h);
    EXPECT_NEAR(h.s, 0.45, 1e-12);
    EXPECT_TRUE(h.normal.isApprox(-Vec3::UnitY()));
  }
  {  // vertex (1, 0, 0) along +x from beyond it
    detail::SweepHit h;
    detail::sweep_triangle(t, Vec3(2, 0, 0), Vec3(-2, 0, 0), r, h);
    EXPECT_NEAR(h.s, 0.45, 1e-12);
    EXPECT_TRUE(h.normal.isApprox(Vec3::UnitX()));
  }
  {  // misses by more than r
    detail::SweepHit h;
    detail::sweep_triangle(t, Vec3(2, 2, 0.05), Vec3(0, 0, -1), r, h);
    EXPECT_FALSE(std::isfinite(h.s));
  }
}

// ---------------------------------------------------------------------------------------------
// No tunnelling at 500 m/s (one 1/240 s step moves 2 m, 100 times the particle's diameter)

TEST(SimCollisionMesh, NoTunnellingThroughTriangleWallThinMeshSphereAndCylinder) {
  for (int kind = 0; kind < 4; ++kind) {
    World world;
    switch (kind) {
      case 0: {  // a single triangle in the plane x = 0
        MeshDef d;
        d.vertices = {Vec3(0, -5, -5), Vec3(0, 5, -5), Vec3(0, 0, 5)};
        d.triangles = {{0, 1, 2}};
        d.material = mat(0.5, 0.0);
        world.add_mesh(d);
        break;
      }
      case 1: {  // a closed slab 1 mm thick
        MeshDef d = box_mesh(Vec3(0.0005, 2, 2), mat(0.5, 0.0));
        world.add_mesh(d);
        break;
      }
      case 2: {
        SphereDef s;
        s.radius = 0.05;
        s.material = mat(0.5, 0.0);
        world.add_sphere(s);
        break;
      }
      case 3: {
        CylinderDef c;
        c.radius = 0.02;
        c.half_height = 1.0;
        c.material = mat(0.5, 0.0);
        world.add_cylinder(c);
        break;
      }
    }
    const auto ps = world.add_particle_system(probes(false));
    for (int k = 0; k < 7; ++k)  // start offsets along the step, so contacts fall anywhere in it
      world.spawn_particle(ps, Vec3(-3.0 - 0.29 * k, 0, 0.001 * k), Vec3(500, 0, 0), 0.01, kR, 100);
    for (int f = 0; f < 6; ++f) world.advance(1.0 / 60);
    const ParticleView v = world.particles(ps);
    ASSERT_EQ(v.count, 7u) << kind;
    for (std::size_t i = 0; i < v.count; ++i) {
      EXPECT_LT(v.position[3 * i], -kR) << "kind " << kind << " particle " << i;
      if (kind != 2) {
        EXPECT_NEAR(v.velocity[3 * i], -250.0, 1e-3) << kind;  // e = 0.5
      }
      EXPECT_LT(v.velocity[3 * i], -200.0) << kind;
    }
  }
}

// ---------------------------------------------------------------------------------------------
// Response on meshes

TEST(SimCollisionMesh, SuccessiveBounceApexesFollowRestitutionPowers) {
  // On a mesh floor: apex n = e^{2n} h (Coutinho §3.6.1 with an immovable body).
  const double e = 0.8, h = 1.0;
  World world(WorldDef{1.0 / 2000, 0, 0.05});
  world.add_mesh(quad(2.0, mat(e, 0.0)));
  const auto ps = world.add_particle_system(probes());
  world.spawn_particle(ps, Vec3(0.1, 0.2, h + kR), Vec3::Zero(), 0.01, kR, 100);
  std::vector<double> apex;
  double top = -1, prev_vz = 0;
  for (int i = 0; i < 2000 * 4 && apex.size() < 3; ++i) {
    world.advance(1.0 / 2000);
    const ParticleView v = world.particles(ps);
    ASSERT_GE(v.position[2], kR - 1e-6);
    const double vz = v.velocity[2];
    if (prev_vz > 0 && vz <= 0) apex.push_back(top - kR);
    top = std::max(vz > 0 && prev_vz <= 0 ? 0.0 : top, double(v.position[2]));
    prev_vz = vz;
  }
  ASSERT_EQ(apex.size(), 3u);
  for (int n = 1; n <= 3; ++n)
    EXPECT_NEAR(apex[std::size_t(n - 1)], std::pow(e, 2 * n) * h, 0.01 * std::pow(e, 2 * n) * h) << n;
}

TEST(SimCollisionMesh, CriticalFrictionStopsSlidingExactly) {
  // Impact (3, 0, -4) m/s, e = 0.5: critical mu* = |v_t| / ((1 + e) |v_n|) = 0.5 (eqs. 3.56–3.57).
  const Vec3 v(3, 0, -4), n = Vec3::UnitZ();
  for (double mu : {0.2, 0.4, 0.5, 0.8}) {
    const Vec3 out = detail::respond(v, Vec3::Zero(), n, mat(0.5, mu), 0.05, Vec3::Zero());
    EXPECT_DOUBLE_EQ(out.z(), 2.0);
    EXPECT_NEAR(out.x(), std::max(0.0, 3.0 - mu * 1.5 * 4.0), 1e-12) << mu;
  }
  // The same impact on a mesh in a world without gravity.
  for (double mu : {0.25, 0.6}) {
    World world;
    world.add_mesh(quad(5.0, mat(0.5, mu)));
    const auto ps = world.add_particle_system(probes(false));
    world.spawn_particle(ps, Vec3(0, 0, kR + 0.01), v, 0.01, kR, 100);
    world.advance(1.0 / 60);
    const Vec3 out = velocity_of(world.particles(ps), 0);
    EXPECT_NEAR(out.z(), 2.0, 1e-5);
    EXPECT_NEAR(out.x(), std::max(0.0, 3.0 - mu * 6.0), 1e-5) << mu;
  }
}

TEST(SimCollisionMesh, InclineHoldsWhenStaticMuExceedsTanThetaElseSlides) {
  // Static mu_s = 0.5, dynamic mu_d = 0.3. At 20 deg (tan = 0.364): mu_d alone would slide, mu_s
  // holds. At 35 deg (tan = 0.700 > mu_s): slides with a = g (sin - mu_d cos). On a tilted mesh
  // and on a tilted plane.
  const double g = 9.81, mu_s = 0.5, mu_d = 0.3;
  for (int on_mesh = 0; on_mesh < 2; ++on_mesh)
    for (double deg : {20.0, 35.0}) {
      const double th = deg * kPi / 180;
      const Vec3 n(-std::sin(th), 0, std::cos(th));
      World world;
      if (on_mesh) {
        Transform t;
        t.rotation = Quat(Eigen::AngleAxisd(-th, Vec3::UnitY()));  // local +z -> n
        world.add_mesh(quad(20.0, mat(0.0, mu_d, mu_s), t));
      } else {
        PlaneDef p;
        p.normal = n;
        p.material = mat(0.0, mu_d, mu_s);
        world.add_plane(p);
      }
      const auto ps = world.add_particle_system(probes());
      world.spawn_particle(ps, kR * n, Vec3::Zero(), 0.01, kR, 100);
      world.advance(1.0);
      const ParticleView v = world.particles(ps);
      const Vec3 x = position_of(v, 0);
      EXPECT_NEAR(n.dot(x), kR, 1e-5) << deg;  // on the surface
      const double speed = velocity_of(v, 0).norm();
      if (std::tan(th) <= mu_s) {
        EXPECT_EQ(speed, 0.0) << deg << " mesh " << on_mesh;
        EXPECT_LT((x - kR * n).norm(), 1e-6);
      } else {
        const double a = g * (std::sin(th) - mu_d * std::cos(th));
        EXPECT_NEAR(speed, a * 1.0, 0.01 * a) << deg << " mesh " << on_mesh;
      }
    }
}

TEST(SimCollisionMesh, KinematicMeshCarriesARestingParticle) {
  World world;
  MeshDef d = quad(1.0, mat(0.0, 0.5));
  d.path.smooth = false;
  d.path.keys = {Keyframe{0.0, Vec3(0, 0, 0), Quat::Identity()},
                 Keyframe{1.0, Vec3(0, 0, 0.5), Quat::Identity()}};
  world.add_mesh(d);
  const auto ps = world.add_particle_system(probes());
  world.spawn_particle(ps, Vec3(0.2, 0, kR), Vec3::Zero(), 0.01, kR, 100);
  world.advance(1.0);
  const Vec3 x = position_of(world.particles(ps), 0);
  EXPECT_NEAR(x.z(), 0.5 + kR, 2e-3);  // lifted with the mesh (within one step's lag)
  EXPECT_NEAR(x.x(), 0.2, 1e-5);
}

// ---------------------------------------------------------------------------------------------
// Removal (§3.4.2) and hit actions

TEST(SimCollisionMesh, ParticleInsideASolidIsRemovedAndCounted) {
  World world;
  SphereDef s;
  s.radius = 0.5;
  world.add_sphere(s);
  MeshDef cube = box_mesh(Vec3(0.3, 0.3, 0.3), Material{});
  cube.transform.translation = Vec3(3, 0, 0);
  world.add_mesh(cube);
  CylinderDef c;
  c.transform.translation = Vec3(-3, 0, 0);
  world.add_cylinder(c);
  const auto ps = world.add_particle_system(probes(false));
  world.spawn_particle(ps, Vec3(0.1, 0, 0), Vec3::Zero(), 0.01, kR, 100);    // in the sphere
  world.spawn_particle(ps, Vec3(3.1, 0.1, 0), Vec3::Zero(), 0.01, kR, 100);  // in the cube
  world.spawn_particle(ps, Vec3(-3, 0.2, 0.1), Vec3::Zero(), 0.01, kR, 100); // in the cylinder
  world.spawn_particle(ps, Vec3(3.5, 0, 0), Vec3::Zero(), 0.01, kR, 100);    // outside all
  world.advance(1.0 / 60);
  EXPECT_EQ(world.particles(ps).count, 1u);
  EXPECT_EQ(world.removed_inside_count(ps), 3u);
  EXPECT_NEAR(world.particles(ps).position[0], 3.5, 1e-6);
}

TEST(SimCollisionMesh, MissesAmongOpenMeshesOnlyKeepTheirStateExactly) {
  // Among open meshes only, a drop whose first sweep hits nothing leaves the slow path at once
  // (CollisionContext::bare_misses: nothing to push it out of or find it inside). A plane far
  // below everything turns that shortcut off and touches no drop, so both worlds must agree to
  // the bit: drops falling past the bowl, into it, bouncing and resting in it, 6,000 of them
  // (over the Z-ordered pass's threshold) and 1,000 (index order).
  auto run = [](bool far_plane, int n) {
    World world(WorldDef{1.0 / 240, 1, 0.05, 1});
    world.add_mesh(bowl(2.0, 12, 24, mat(0.3, 0.4)));
    if (far_plane) {
      PlaneDef p;
      p.point = Vec3(0, 0, -100);
      world.add_plane(p);
    }
    const auto ps = world.add_particle_system(probes());
    Rng rng(11);
    for (int i = 0; i < n; ++i)
      world.spawn_particle(ps, Vec3(rng.uniform(-2.5, 2.5), rng.uniform(-2.5, 2.5), rng.uniform(-1.8, 1.0)),
                           Vec3(0, 0, -rng.uniform(0.5, 3.0)), 1e-3, 0.01, 100);
    for (int k = 0; k < 120; ++k) world.advance(1.0 / 240);
    const ParticleView v = world.particles(ps);
    std::vector<float> state(v.position, v.position + 3 * v.count);
    state.insert(state.end(), v.velocity, v.velocity + 3 * v.count);
    return state;
  };
  for (const int n : {6000, 1000}) {
    const auto bare = run(false, n), with_plane = run(true, n);
    ASSERT_EQ(bare.size(), 6u * std::size_t(n));
    EXPECT_TRUE(bare == with_plane) << n << " drops";
    // Both kinds were there: drops held in the bowl (slow, inside its rim) and drops that missed it.
    std::size_t held = 0, missed = 0;
    for (std::size_t i = 0; i < std::size_t(n); ++i) {
      const double x = bare[3 * i], y = bare[3 * i + 1], z = bare[3 * i + 2];
      const double speed = Vec3(bare[3 * (n + i)], bare[3 * (n + i) + 1], bare[3 * (n + i) + 2]).norm();
      if (x * x + y * y < 1.9 * 1.9 && z > -2.0 && z < 0.0 && speed < 1.0) ++held;
      if (z < -2.5) ++missed;
    }
    EXPECT_GT(held, std::size_t(n) / 40) << n << " drops";
    EXPECT_GT(missed, std::size_t(n) / 10) << n << " drops";
  }
}

TEST(SimCollisionMesh, LargeRainOnMeshesIsBitIdenticalAtAnyThreadCount) {
  // 20,000 drops (above the parallel threshold) on a bowl and a closed box, some born inside the
  // box: bounce only, no bodies, so the pass splits over the threads. State and removal count
  // must not depend on the count.
  // The drops may also come as 10 systems of 2,000: a pass that small visits its particles in
  // index order, a large one in spatial order (Z-order over the meshes), which must not change
  // a bit either.
  auto run = [](int threads, int systems = 1) {
    World world(WorldDef{1.0 / 240, 1, 0.05, threads});
    world.add_mesh(bowl(2.0, 12, 24, mat(0.3, 0.4)));
    MeshDef box = box_mesh(Vec3(0.4, 0.4, 0.4), mat(0.5, 0.2));
    box.transform.translation = Vec3(0.0, 0.0, -1.2);
    world.add_mesh(box);
    ParticleSystemDef def = probes();
    def.emitter.max_particles = 20000;
    std::vector<ParticleSystemHandle> ids;
    for (int k = 0; k < systems; ++k) ids.push_back(world.add_particle_system(def));
    Rng rng(7);
    for (int i = 0; i < 20000; ++i)
      world.spawn_particle(ids[std::size_t(i / (20000 / systems))],
                           Vec3(rng.uniform(-1.5, 1.5), rng.uniform(-1.5, 1.5), rng.uniform(-1.6, 0.5)),
                           Vec3(0, 0, -rng.uniform(1, 4)), 1e-3, 0.01, 100);
    for (int k = 0; k < 48; ++k) world.advance(1.0 / 240);
    std::vector<float> state;
    std::uint64_t removed = 0;
    for (const auto ps : ids) {
      const ParticleView v = world.particles(ps);
      state.insert(state.end(), v.position, v.position + 3 * v.count);
      removed += world.removed_inside_count(ps);
    }
    for (const auto ps : ids) {
      const ParticleView v = world.particles(ps);
      state.insert(state.end(), v.velocity, v.velocity + 3 * v.count);
    }
    return std::make_pair(state, removed);
  };
  const auto one = run(1);
  EXPECT_GT(one.second, 0u) << "some drops were born inside the box";
  EXPECT_GT(one.first.size(), 3u * 2u * 15000u);
  for (const int t : {2, 3}) {
    const auto many = run(t);
    EXPECT_EQ(many.second, one.second) << t << " threads";
    EXPECT_TRUE(many.first == one.first) << t << " threads";
  }
  const auto small = run(1, 10);
  EXPECT_EQ(small.second, one.second);
  EXPECT_TRUE(small.first == one.first) << "spatial order changed the results";
}

TEST(SimCollisionMesh, LargeSplashingRainIsBitIdenticalAtAnyThreadCount) {
  // The rain demo's case: 20,000 drops with drag (not the vectorised plain test) over a ground
  // that splits them into droplets, a box and a sphere. Splashes share the droplet list and the
  // random generator, so the responses run in index order on one thread; the rejection test
  // before them runs on every thread (issue 19). The drops, the droplets and the removal count
  // must not depend on the count.
  auto run = [](int threads) {
    World world(WorldDef{1.0 / 240, 3, 0.05, threads});
    PlaneDef ground;
    ground.material = mat(0.3, 0.4);
    ground.material.on_hit = HitAction::split;
    ground.material.split.count = 3;
    ground.material.split.min_radius = 0.005;
    world.add_plane(ground);
    BoxDef box;
    box.transform.translation = Vec3(0.5, 0.0, 0.3);
    box.half_extents = Vec3(0.3, 0.3, 0.3);
    box.material = mat(0.5, 0.2);
    world.add_box(box);
    SphereDef ball;
    ball.transform.translation = Vec3(-0.6, 0.2, 0.4);
    ball.radius = 0.4;
    ball.material = mat(0.5, 0.2);
    world.add_sphere(ball);
    ParticleSystemDef def = probes();
    def.drag = 2e-4;
    def.emitter.max_particles = 100000;
    const ParticleSystemHandle ps = world.add_particle_system(def);
    Rng rng(13);
    for (int i = 0; i < 20000; ++i)
      world.spawn_particle(ps, Vec3(rng.uniform(-1.5, 1.5), rng.uniform(-1.5, 1.5), rng.uniform(0.02, 1.2)),
                           Vec3(0.3, 0, -rng.uniform(2, 5)), 1e-4, 0.01, 100);
    for (int k = 0; k < 36; ++k) world.advance(1.0 / 240);
    const ParticleView v = world.particles(ps);
    std::vector<float> state(v.position, v.position + 3 * v.count);
    state.insert(state.end(), v.velocity, v.velocity + 3 * v.count);
    return std::make_pair(state, world.removed_inside_count(ps));
  };
  const auto one = run(1);
  EXPECT_GT(one.first.size(), 6u * 21000u) << "drops splashed into droplets";
  for (const int t : {2, 3}) {
    const auto many = run(t);
    EXPECT_EQ(many.second, one.second) << t << " threads";
    EXPECT_TRUE(many.first == one.first) << t << " threads";
  }
}

TEST(SimCollisionMesh, HitActionsStickKillAndSplit) {
  for (HitAction action : {HitAction::stick, HitAction::kill, HitAction::split}) {
    World world;
    Material m = mat(0.9, 0.0);
    m.on_hit = action;
    m.split.count = 5;
    m.split.min_radius = 0.005;
    m.split.size_fraction = 0.25;
    m.split.speed_fraction = 0.5;
    world.add_mesh(quad(2.0, m));
    const auto ps = world.add_particle_system(probes());
    world.spawn_particle(ps, Vec3(0, 0, 0.2), Vec3(1, 0, -2), 0.01, kR, 100);
    world.advance(0.1);  // hits at about 0.08 s
    const ParticleView v = world.particles(ps);
    if (action == HitAction::stick) {
      ASSERT_EQ(v.count, 1u);
      EXPECT_EQ(velocity_of(v, 0).norm(), 0.0);  // e = 0, unlimited friction, then resting
      EXPECT_NEAR(v.position[2], kR, 1e-6);
    } else if (action == HitAction::kill) {
      EXPECT_EQ(v.count, 0u);
    } else {
      ASSERT_EQ(v.count, 5u);  // the parent is gone, five droplets
      for (std::size_t i = 0; i < v.count; ++i) {
        EXPECT_FLOAT_EQ(v.radius[i], float(0.25 * kR));
        EXPECT_GT(v.position[3 * i + 2], 0.0);
        EXPECT_GT(v.velocity[3 * i + 2], -2.5);  // thrown up from the surface, then falling
      }
      EXPECT_EQ(world.emitted_count(ps), 6u);
      world.advance(1.0);  // droplets (radius 2.5 mm < min_radius) vanish at their next hit
      EXPECT_EQ(world.particles(ps).count, 0u);
    }
  }
}

TEST(SimCollisionMesh, InvalidDefinitionsAreRejectedNamingTheField) {
  World world;
  SphereDef s;
  s.radius = -1;
  EXPECT_THROW(world.add_sphere(s), std::invalid_argument);
  CylinderDef c;
  c.half_height = 0;
  EXPECT_THROW(world.add_cylinder(c), std::invalid_argument);
  MeshDef m;
  EXPECT_THROW(world.add_mesh(m), std::invalid_argument);
  m = quad(1, Material{});
  m.triangles.push_back({0, 1, 9});
  try {
    world.add_mesh(m);
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("MeshDef.triangles[2]"), std::string::npos) << e.what();
  }
  m = quad(1, Material{});
  m.material.split.size_fraction = 2.0;
  EXPECT_THROW(world.add_mesh(m), std::invalid_argument);
}

TEST(SimCollisionMesh, SurfaceContactsGiveTheClosestFeatureOfEachShape) {
  // The resting-contact query (closest feature, §3.6.3) against closed forms: gap = distance
  // from the surface to the sphere, normal from the surface to the centre.
  const double r = 0.01, margin = 0.005;
  detail::SurfaceContact out[3];
  auto one = [&](const detail::Collider& c, const Vec3& p, double gap, const Vec3& n) {
    ASSERT_EQ(detail::surface_contacts(c, p, r, margin, out, 3), 1) << p.transpose();
    EXPECT_NEAR(out[0].gap, gap, 1e-12) << p.transpose();
    EXPECT_LT((out[0].normal - n).norm(), 1e-12) << p.transpose();
  };
  // A static shape posed at `at` (identity offset), as World::add_body places it.
  auto posed = [](const ShapeDef& d, const Vec3& at = Vec3::Zero()) {
    detail::Collider c = detail::make_collider(d, "shape");
    c.follow(Transform{at, Quat::Identity()}, Vec3::Zero(), Vec3::Zero());
    return c;
  };
  const detail::Collider box = posed(ShapeDef::box(Vec3(0.1, 0.2, 0.3)), Vec3(1, 0, 0));
  one(box, Vec3(1.05, 0.2 + r + 0.002, 0), 0.002, Vec3::UnitY());              // face
  one(box, Vec3(1.1 + 0.003, 0.2 + 0.004, 0), 0.005 - r, Vec3(0.6, 0.8, 0));   // edge
  one(box, Vec3(1.0, 0.0, 0.3 - 0.001), -0.001 - r, Vec3::UnitZ());            // inside: least deep
  EXPECT_EQ(detail::surface_contacts(box, Vec3(1.05, 0.2 + r + 0.006, 0), r, margin, out, 3), 0);
  const detail::Collider sphere = posed(ShapeDef::sphere(0.5));
  one(sphere, Vec3(0, 0.3, 0.402), std::hypot(0.3, 0.402) - 0.5 - r, Vec3(0, 0.3, 0.402).normalized());
  EXPECT_EQ(detail::surface_contacts(sphere, Vec3(0, 0, 0.2), r, margin, out, 3), 0);  // inside
  const detail::Collider cyl = posed(ShapeDef::cylinder(0.2, 0.1));
  one(cyl, Vec3(0.2 + r + 0.001, 0, 0.05), 0.001, Vec3::UnitX());              // side
  one(cyl, Vec3(0.1, 0, -0.1 - r + 0.002), -0.002, -Vec3::UnitZ());            // cap
  one(cyl, Vec3(0.2 + 0.003, 0, 0.1 + 0.004), 0.005 - r, Vec3(0.6, 0, 0.8));   // rim
  // Capsule (segment |z| <= 0.1 grown by 0.2): side, and the end cap's sphere.
  const detail::Collider cap = posed(ShapeDef::capsule(0.2, 0.1));
  one(cap, Vec3(0.2 + r + 0.001, 0, 0.05), 0.001, Vec3::UnitX());
  one(cap, Vec3(0, 0, 0.1) + (0.2 + r + 0.003) * Vec3(0.6, 0, 0.8), 0.003, Vec3(0.6, 0, 0.8));
  EXPECT_EQ(detail::surface_contacts(cap, Vec3(0.1, 0, 0.25), r, margin, out, 3), 0);  // inside
  // A crease of a mesh (two facets at 90 degrees along x): one contact per facet, nearest first.
  ShapeDef md;
  md.type = ShapeType::mesh;
  md.vertices = {Vec3(-1, 0, 0), Vec3(1, 0, 0), Vec3(1, 1, 0), Vec3(-1, 1, 0), Vec3(1, 0, 1),
                 Vec3(-1, 0, 1)};
  md.triangles = {{0, 1, 2}, {0, 2, 3}, {0, 1, 4}, {0, 4, 5}};
  const detail::Collider crease = posed(md);
  ASSERT_EQ(detail::surface_contacts(crease, Vec3(0.2, r + 0.001, r - 0.001), r, margin, out, 3), 2);
  EXPECT_NEAR(out[0].gap, -0.001, 1e-12);
  EXPECT_LT((out[0].normal - Vec3::UnitZ()).norm(), 1e-12);
  EXPECT_NEAR(out[1].gap, 0.001, 1e-12);
  EXPECT_LT((out[1].normal - Vec3::UnitY()).norm(), 1e-12);
}

TEST(SimCollisionMesh, SurfaceContactsFromTheMeshGridAreTheTreesToTheBit) {
  // surface_contacts() asks a mesh's grid first (§2.3.1) and its AABB tree where the grid
  // declines. Both must give the same features in the same order, to the bit. Reference: the
  // same collider with an empty grid (the tree alone). Points on both sides of the bowl's shell,
  // near its vertices (where several triangles tie) and in its hollow; radii whose boxes span
  // one cell, several, and too many (the grid declines).
  const double R = 0.3;
  const MeshDef b = bowl(R, 16, 48, mat(0.3, 0.5));
  ShapeDef md;
  md.type = ShapeType::mesh;
  md.vertices = b.vertices;
  md.triangles = b.triangles;
  detail::Collider grid = detail::make_collider(md, "bowl");
  grid.follow(Transform{Vec3(0.1, -0.2, 0.05), Quat::Identity()}, Vec3::Zero(), Vec3::Zero());
  ASSERT_GT(grid.mesh->grid.cell_count(), 0u);
  detail::Collider tree = grid;
  auto alone = std::make_shared<detail::MeshShape>(*grid.mesh);
  alone->grid = detail::MeshGrid();
  tree.mesh = alone;
  Rng rng(29, 4);
  int found = 0, several = 0;
  for (int k = 0; k < 30000; ++k) {
    const double r = k % 3 == 0 ? 0.002 : k % 3 == 1 ? 0.008 : 0.06;
    Vec3 p;
    if (k % 4 == 0) {  // near a vertex
      p = b.vertices[std::size_t(rng.uniform(0.0, double(b.vertices.size()) - 1e-9))] +
          Vec3(rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1)) * (1.2 * r);
    } else {  // at a distance from the centre across the shell
      const double ph = rng.uniform(0.0, 2 * kPi), th = rng.uniform(0.0, 0.5 * kPi);
      const Vec3 dir(std::sin(th) * std::cos(ph), std::sin(th) * std::sin(ph), -std::cos(th));
      p = (R + rng.uniform(-2.0 * r, 0.5 * r)) * dir;
    }
    p += Vec3(0.1, -0.2, 0.05);
    const double margin = 0.25 * r;
    detail::SurfaceContact a[3], c[3];
    const int na = detail::surface_contacts(grid, p, r, margin, a, 3);
    const int nc = detail::surface_contacts(tree, p, r, margin, c, 3);
    ASSERT_EQ(na, nc) << p.transpose() << " r " << r;
    for (int q = 0; q < na; ++q) {
      ASSERT_EQ(a[q].gap, c[q].gap) << p.transpose() << " r " << r;
      ASSERT_EQ(a[q].normal, c[q].normal) << p.transpose() << " r " << r;
    }
    found += na;
    several += na > 1 ? 1 : 0;
  }
  EXPECT_GT(found, 10000);
  EXPECT_GT(several, 1000);
}

// ---------------------------------------------------------------------------------------------
// A pile in the bowl (the 5,000-particle, 10 s version is in bench/sim/bench_collisions.cpp)

/// 400 beads of radius r poured into the bowl over the first second, colliding with each other.
ParticleSystemDef pile_system(double r) {
  ParticleSystemDef def = probes();
  def.collide_particles = true;
  def.particle_restitution = 0.2;
  def.particle_friction = 0.3;
  def.emitter.rate = 400;
  def.emitter.stop_time = 1.0;
  def.emitter.disk_radius = 0.05;
  def.emitter.transform.translation = Vec3(0, 0, 0.1);
  def.emitter.transform.rotation = Quat(Eigen::AngleAxisd(kPi, Vec3::UnitX()));  // downwards
  def.emitter.start_speed = {0.5, 0.0, 0.0};
  def.emitter.lifetime = {100, 0, 0};
  def.emitter.radius = {r, 0, 1e-6};
  return def;
}

TEST(SimCollisionMesh, PileInBowlComesToRestInsideIt) {
  const double R = 0.3, r = 0.01;
  World world;
  world.add_mesh(bowl(R, 12, 32, mat(0.3, 0.5)));
  const auto ps = world.add_particle_system(pile_system(r));
  world.advance(3.5);
  std::vector<Vec3> before;
  for (std::size_t i = 0; i < world.particles(ps).count; ++i)
    before.push_back(position_of(world.particles(ps), i));
  world.advance(0.5);
  const ParticleView v = world.particles(ps);
  ASSERT_EQ(v.count, 400u);
  double max_speed = 0, mean_speed = 0, max_v = 0;
  for (std::size_t i = 0; i < v.count; ++i) {
    const Vec3 x = position_of(v, i);
    // Inside the shell: the inner facets are chords of the sphere R, so a particle resting on
    // one has |x| <= R - r; 1 mm allows the overlap the contact solver leaves in a pile.
    EXPECT_LT(x.norm(), R - r + 1e-3) << i;
    EXPECT_LT(x.z(), 0.0) << i;  // a pile in the bottom, none flung out
    const double speed = (x - before[i]).norm() / 0.5;  // mean speed over the last 0.5 s
    max_speed = std::max(max_speed, speed);
    mean_speed += speed / double(v.count);
    max_v = std::max(max_v, velocity_of(v, i).norm());
  }
  // At rest (§3.6.3): the collider contacts are in the same solve as the pair contacts, with
  // warm-started resting impulses, so the pile does not creep. Measured: mean 0.29 mm/s, max
  // 1.8 mm/s, stored speeds up to 1.2 cm/s; before, with the bowl's contacts left to the next
  // step's swept pass: mean 2.2 mm/s, max 2.6 cm/s. (Other seeds: surface particles of the
  // pile still slide down now and then at mu = 0.3, up to 4 cm/s; that is friction, not jitter.)
  // Since issue 15 (forces over the rest of a step after a contact, impulses moving the position
  // by h dv / 2) this seed has one surface particle sliding: max 1.7 cm/s, stored 4.4 cm/s.
  EXPECT_LT(mean_speed, 1e-3) << "max " << max_speed;
  EXPECT_LT(max_speed, 2e-2);
  EXPECT_LT(max_v, 5e-2);  // the stored velocity: no jitter either
  EXPECT_EQ(world.removed_inside_count(ps), 0u);
}

// ---------------------------------------------------------------------------------------------
// Sleep of particles at rest (ParticleStore::rest, collision/particle_collisions.hpp)

/// The 400-bead pile of PileInBowlComesToRestInsideIt; `moving_box`: a kinematic box far from
/// the bowl moves all the time (particles must not sleep among moving colliders).
struct SleepyPile {
  World world;
  ParticleSystemHandle ps;
  explicit SleepyPile(bool moving_box = false, int threads = 1, double max_step = 1.0 / 240)
      : world(WorldDef{max_step, 1, 0.05, threads}) {
    world.add_mesh(bowl(0.3, 12, 32, mat(0.3, 0.5)));
    if (moving_box) {
      BoxDef b;
      b.half_extents = Vec3::Constant(0.05);
      b.path.keys = {Keyframe{0.0, Vec3(2, 0, 0), Quat::Identity()},
                     Keyframe{10.0, Vec3(3, 0, 0), Quat::Identity()}};
      world.add_box(b);
    }
    ps = world.add_particle_system(pile_system(0.01));
  }
  std::vector<Vec3> positions() const {
    std::vector<Vec3> x;
    for (std::size_t i = 0; i < world.particles(ps).count; ++i)
      x.push_back(position_of(world.particles(ps), i));
    return x;
  }
  /// Particles whose position has not changed by a single bit since `before` and whose velocity
  /// is exactly zero: asleep (an awake particle's stored velocity is never exactly zero under
  /// gravity).
  std::size_t still(const std::vector<Vec3>& before) const {
    const ParticleView v = world.particles(ps);
    std::size_t n = 0;
    for (std::size_t i = 0; i < before.size() && i < v.count; ++i)
      n += position_of(v, i) == before[i] && velocity_of(v, i) == Vec3::Zero();
    return n;
  }
};

TEST(SimParticleSleep, ASettledPileSleepsAndAnImpactWakesWhatItHits) {
  SleepyPile p;
  p.world.advance(4.0);  // poured over the first second, settled well before 3.5 s
  const std::vector<Vec3> settled = p.positions();
  ASSERT_EQ(settled.size(), 400u);
  p.world.advance(0.5);
  const std::size_t still = p.still(settled);
  // Measured: 367 of 400 (beads slower than 1 cm/s for 0.5 s sleep; on the pile's surface some
  // slide now and then at mu = 0.3). Advanced in steps of 0.5 s the count reads 275 at 2.5 s,
  // 326 at 3 s, 352 at 4 s and 350-358 up to 6 s. Without sleep no stored velocity is exactly 0.
  EXPECT_GE(still, 320u);

  // A bead thrown down onto the pile at 2 m/s: the beads it hits wake and give way, it does
  // not pass through them, and the pile settles and sleeps again.
  const std::vector<Vec3> before = p.positions();
  double top = -1.0;
  std::size_t top_i = 0;
  for (std::size_t i = 0; i < before.size(); ++i)
    if (before[i].z() > top) {
      top = before[i].z();
      top_i = i;
    }
  const Vec3 aim = before[top_i];
  p.world.spawn_particle(p.ps, aim + Vec3(0, 0, 0.05), Vec3(0, 0, -2.0), 0.01 * 0.01 * 0.01 * 4.19 * 1000,
                         0.01, 100);
  p.world.advance(0.25);
  const ParticleView v = p.world.particles(p.ps);
  ASSERT_EQ(v.count, 401u);
  std::size_t moved = 0;
  for (std::size_t i = 0; i < before.size(); ++i) moved += position_of(v, i) != before[i];
  EXPECT_GE(moved, 1u);  // woken by the impact
  const Vec3 thrown = position_of(v, 400);
  EXPECT_GT(thrown.z(), aim.z() - 0.02) << "through the pile";  // rests on top, not inside
  for (std::size_t i = 0; i < before.size(); ++i)
    EXPECT_GT((position_of(v, i) - thrown).norm(), 2 * 0.01 - 2e-3) << i;  // no deep overlap
  p.world.advance(2.0);
  const std::vector<Vec3> again = p.positions();
  p.world.advance(0.5);
  EXPECT_GE(p.still(again), 320u);  // measured 341
  for (const Vec3& x : p.positions()) {
    EXPECT_LT(x.norm(), 0.3 - 0.01 + 1e-3);  // all still in the bowl
    EXPECT_LT(x.z(), 0.0);
  }
}

TEST(SimParticleSleep, BeadsHeldStillInALargePileSleepEvenWithAVelocity) {
  // 2,000 beads of 8 mm poured into the bowl over 2 s (the pile_in_bowl benchmark's bowl and
  // beads, two fifths of its count), then 3 s to settle. A bead whose contacts hold it still must
  // fall asleep: its stored velocity reads its motion. When the overlap projection held each
  // speculative pair contact at the gap it was found with, it put back every step what the solve
  // had let gravity close, and such beads read 1-8 cm/s without moving, awake for ever.
  // Measured at t = 4, 4.5, 5 and 6 s: 15, 11, 10 and 4 beads awake; with the gap held, 123, 98,
  // 93 and 86. Most of those left were beads caged by sleeping neighbours: the solve left each
  // a velocity sliding along two of them, the projection took the step's motion back, and the
  // rest test read the velocity (1-4 cm/s) instead of the motion (none). Resting by velocity,
  // 8 were awake at 5 s (6 of them moved by 5.5 s), 4 at 6 s, and 14 of the benchmark's 5,000
  // at 14.5 s. Resting by motion alone,
  // one bead on the bowl's facets, put back and forth by 50 um a step with a velocity of
  // 1e-20 m/s, stayed awake. Resting by either (update_rest()): none awake at 5 s, and no bead
  // moves from 5 to 5.5 s.
  World world;
  world.add_mesh(bowl(0.3, 16, 48, mat(0.3, 0.5)));
  ParticleSystemDef def = pile_system(0.008);
  def.emitter.rate = 1000;
  def.emitter.stop_time = 2.0;
  def.emitter.disk_radius = 0.08;
  def.emitter.transform.translation = Vec3(0, 0, 0.15);
  const auto ps = world.add_particle_system(def);
  world.advance(5.0);
  const ParticleView v = world.particles(ps);
  ASSERT_EQ(v.count, 2000u);
  std::size_t awake = 0;
  std::vector<Vec3> settled;
  for (std::size_t i = 0; i < v.count; ++i) {
    awake += velocity_of(v, i) != Vec3::Zero();
    settled.push_back(position_of(v, i));
  }
  // Measured 0 and 0 below (the old rest test: 8 and 6). Two are allowed for a build whose
  // rounding gives a different pile (the sanitizer job's clang build).
  EXPECT_LE(awake, 2u);
  world.advance(0.5);
  const ParticleView later = world.particles(ps);
  std::size_t moved = 0;
  for (std::size_t i = 0; i < later.count; ++i) moved += position_of(later, i) != settled[i];
  EXPECT_LE(moved, 2u);
}

class SimParticleSleepGrid : public testing::TestWithParam<bool> {};

TEST_P(SimParticleSleepGrid, AWokenBeadRestsOnItsSleepingNeighboursSoTheWakingStaysNearTheImpact) {
  // A bead woken by an impact must rest on the sleepers under it in the step it wakes: without
  // those contacts it falls for a step, hits them faster than the wake speed and wakes them, and
  // the waking runs down through the pile to the bowl. Param: a 1 mm bead far off makes the
  // radii differ enough for the multi-level hashed grid (§2.3.2) instead of the sorted one.
  SleepyPile p;
  if (GetParam()) p.world.spawn_particle(p.ps, Vec3(0.0, 0.0, 0.5), Vec3::Zero(), 1e-6, 0.001, 100);
  p.world.advance(4.5);
  const std::vector<Vec3> before = p.positions();
  std::vector<double> z;
  for (const Vec3& x : before) z.push_back(x.z());
  std::sort(z.begin(), z.end());
  const double low = z[z.size() / 3];  // the bottom third of the pile lies below
  const std::size_t top_i = std::size_t(std::max_element(before.begin(), before.end(), [](const Vec3& a, const Vec3& b) {
                                           return a.z() < b.z();
                                         }) - before.begin());
  p.world.spawn_particle(p.ps, before[top_i] + Vec3(0, 0, 0.03), Vec3(0, 0, -1.0),
                         0.01 * 0.01 * 0.01 * 4.19 * 1000, 0.01, 100);
  std::size_t deep_moved = 0, moved = 0;
  for (int k = 0; k < 12; ++k) {
    p.world.advance(1.0 / 24);
    const ParticleView v = p.world.particles(p.ps);
    std::size_t d = 0, m = 0;
    for (std::size_t i = 0; i < before.size(); ++i) {
      const bool changed = position_of(v, i) != before[i];
      m += changed;
      d += changed && before[i].z() < low;
    }
    deep_moved = std::max(deep_moved, d);
    moved = std::max(moved, m);
  }
  SCOPED_TRACE(testing::Message() << "moved " << moved << ", in the bottom third " << deep_moved);
  EXPECT_GE(moved, 1u);
  EXPECT_LE(deep_moved, 10u);
}

INSTANTIATE_TEST_SUITE_P(SortedAndHashed, SimParticleSleepGrid, testing::Bool());

TEST(SimParticleSleep, ABeadLaidOnASleepingColumnAtSixtyHertzDoesNotWakeIt) {
  // At 60 Hz a bead resting on a sleeper meets it at g h = 16 cm/s each step, over the contact
  // speed: that is its own weight, not an impact, and must neither wake the sleeper nor bounce.
  const double r = 0.01, h = 1.0 / 60;
  World world(WorldDef{h, 1, 0.05, 1});
  PlaneDef ground;
  ground.material = Material(0.5, 0.5);
  world.add_plane(ground);
  ParticleSystemDef def = pile_system(r);
  def.emitter.rate = 0.0;
  const auto ps = world.add_particle_system(def);
  const double m = 4.19 * r * r * r * 1000;
  for (int k = 0; k < 5; ++k) world.spawn_particle(ps, Vec3(0, 0, r + 2 * r * k), Vec3::Zero(), m, r, 100);
  world.advance(2.0);
  std::vector<Vec3> column;
  for (std::size_t i = 0; i < 5; ++i) column.push_back(position_of(world.particles(ps), i));
  world.advance(0.5);
  for (std::size_t i = 0; i < 5; ++i) {
    ASSERT_EQ(position_of(world.particles(ps), i), column[i]) << "the column sleeps " << i;
    ASSERT_EQ(velocity_of(world.particles(ps), i), Vec3::Zero()) << i;
  }
  // Laid on top, touching, at rest: it settles on the column and falls asleep in turn.
  world.spawn_particle(ps, Vec3(0, 0, r + 2 * r * 5), Vec3::Zero(), m, r, 100);
  double top_speed = 0.0;
  for (int k = 0; k < 60; ++k) {
    world.advance(h);
    top_speed = std::max(top_speed, velocity_of(world.particles(ps), 5).norm());
    for (std::size_t i = 0; i < 5; ++i)
      ASSERT_EQ(position_of(world.particles(ps), i), column[i]) << "woken at step " << k << ": " << i;
  }
  EXPECT_LT(top_speed, 0.01);  // no bounce off the sleeper (e = 0.2 of 16 cm/s would be 3 cm/s)
  EXPECT_EQ(velocity_of(world.particles(ps), 5), Vec3::Zero()) << "asleep after 1 s";
}

TEST(SimParticleSleep, ABeadThatDoesNotCollideWithTheBowlSleepsOnThePileWithoutSinking) {
  // Beads of a second system in the pile's collision group with `collide` false (they meet the
  // pile, never the bowl) poured on the settled pile: asleep, they must stay exactly put (a
  // sleeper the integrator moved and nothing put back would sink into the pile).
  ParticleSystemDef top = pile_system(0.01);
  top.collide = false;
  top.collide_particles = false;
  top.collision_group = "pile";
  top.emitter.rate = 50;
  top.emitter.start_time = 3.0;
  top.emitter.stop_time = 4.0;
  ParticleSystemDef base = pile_system(0.01);
  base.collision_group = "pile";
  World world;
  world.add_mesh(bowl(0.3, 12, 32, mat(0.3, 0.5)));
  world.add_particle_system(base);
  const auto b = world.add_particle_system(top);
  world.advance(7.0);
  ASSERT_EQ(world.particles(b).count, 50u);
  std::vector<Vec3> before;
  for (std::size_t i = 0; i < 50; ++i) before.push_back(position_of(world.particles(b), i));
  world.advance(0.5);
  // Those that rolled off the pile fall through the bowl (they do not collide with it); the
  // ones on the pile lie still, each exactly where it fell asleep.
  std::size_t on_pile = 0, still = 0;
  for (std::size_t i = 0; i < 50; ++i) {
    const Vec3 x = position_of(world.particles(b), i);
    if (!(x.norm() < 0.3)) continue;
    ++on_pile;
    still += x == before[i] && velocity_of(world.particles(b), i) == Vec3::Zero();
  }
  // Measured: 45 on the pile, 38 still; 0 still when only the systems that collide with the
  // colliders had their sleepers put back.
  EXPECT_GE(on_pile, 10u);
  EXPECT_GE(still, on_pile * 8 / 10);
}

TEST(SimParticleSleep, RemovingTheColliderUnderASleepingPileWakesIt) {
  // A sleeper stays put only because what holds it stays: with the bowl removed, the pile falls.
  World world;
  const auto bowl_h = world.add_mesh(bowl(0.3, 12, 32, mat(0.3, 0.5)));
  const auto ps = world.add_particle_system(pile_system(0.01));
  world.advance(4.5);
  world.remove(bowl_h);
  world.advance(0.5);
  const ParticleView v = world.particles(ps);
  ASSERT_EQ(v.count, 400u);
  std::size_t fallen = 0;
  for (std::size_t i = 0; i < v.count; ++i) fallen += position_of(v, i).z() < -0.3 - 0.5;
  EXPECT_EQ(fallen, v.count);  // in free fall g t^2 / 2 = 1.2 m in 0.5 s
}

TEST(SimParticleSleep, AColliderAddedIntoASleepingPileWakesIt) {
  // A sphere set down into the settled pile: the beads it overlaps must be pushed out of it (a
  // sleeper has no collider contacts and is not swept, so it would stay inside the sphere's skin).
  SleepyPile p;
  p.world.advance(4.5);
  const std::vector<Vec3> before = p.positions();
  double top = -1.0;
  for (const Vec3& x : before) top = std::max(top, x.z());
  const double R = 0.06, r = 0.01;
  const Vec3 c(0.0, 0.0, top - 0.02);
  std::size_t overlapped = 0;
  for (const Vec3& x : before) overlapped += (x - c).norm() < R + r && (x - c).norm() > R;
  ASSERT_GE(overlapped, 3u);
  SphereDef sphere;
  sphere.transform.translation = c;
  sphere.radius = R;
  sphere.material = mat(0.3, 0.5);
  p.world.add_sphere(sphere);
  p.world.advance(0.25);
  const ParticleView v = p.world.particles(p.ps);
  std::size_t deep = 0;
  for (std::size_t i = 0; i < v.count; ++i) deep += (position_of(v, i) - c).norm() < R + r - 2e-3;
  EXPECT_EQ(deep, 0u) << "of " << overlapped << " overlapping when it was added";
}

TEST(SimParticleSleep, APileWhoseBottomBeadsDieWakesAndSettles) {
  // Beads live 3.6 s: those poured first (the bottom of the pile) die first, from 3.6 s on,
  // while the pile sleeps. A sleeper that rested on a bead that died must fall, not hover.
  World world;
  world.add_mesh(bowl(0.3, 12, 32, mat(0.3, 0.5)));
  ParticleSystemDef def = pile_system(0.01);
  def.emitter.lifetime = {3.6, 0, 0};
  const auto ps = world.add_particle_system(def);
  world.advance(3.5);
  const auto top = [&] {  // mean height of the 20 highest beads
    std::vector<double> z;
    for (std::size_t i = 0; i < world.particles(ps).count; ++i) z.push_back(position_of(world.particles(ps), i).z());
    std::sort(z.rbegin(), z.rend());
    double m = 0.0;
    for (std::size_t i = 0; i < 20 && i < z.size(); ++i) m += z[i] / 20.0;
    return m;
  };
  const double before = top();
  world.advance(0.4);  // the beads poured in the first 0.3 s are gone
  ASSERT_LT(world.particles(ps).count, 300u);
  EXPECT_LT(top(), before - 0.005) << "the pile's top sank " << before - top() << " m";
}

TEST(SimParticleSleep, NoSleepAmongMovingColliders) {
  // A kinematic box far away moving: a collider that moves could push a sleeping particle
  // without waking it, so none sleeps (the pile itself settles the same way).
  SleepyPile p(true);
  p.world.advance(4.0);
  const std::vector<Vec3> settled = p.positions();
  p.world.advance(0.5);
  EXPECT_LT(p.still(settled), 10u);
}

TEST(SimParticleSleep, SleepingPileIsTheSameBitsAtOneAndTwoThreadsAndAfterARestore) {
  SleepyPile a(false, 1), b(false, 2);
  a.world.advance(3.0);
  b.world.advance(3.0);
  std::string saved;
  a.world.save_state(saved);
  SleepyPile c(false, 1);
  c.world.load_state(saved);
  a.world.advance(1.0);
  b.world.advance(1.0);
  c.world.advance(1.0);
  EXPECT_EQ(a.world.state_hash(), b.world.state_hash());
  EXPECT_EQ(a.world.state_hash(), c.world.state_hash());
  // The restore must carry the sleep: one whose sleepers were woken would move them.
  EXPECT_GE(a.still(c.positions()), 320u);  // measured 369
}

TEST(SimParticleSleep, LargeRestingLayerFallsAsleepTheSameAtOneAndTwoThreads) {
  // Over kParallelMin the sleep bookkeeping (time at rest, the velocity zeroed on falling asleep)
  // is split over the threads like every other per-particle pass: a layer of 130 x 130 beads
  // laid on the ground at rest must fall asleep to the same bits at any thread count.
  const auto run = [](int threads) {
    World world(WorldDef{1.0 / 60, 1, 0.05, threads});
    world.add_plane(PlaneDef{});
    ParticleSystemDef def = probes();
    def.collide_particles = true;
    def.emitter.rate = 0.0;
    def.emitter.max_particles = 130 * 130;
    const auto ps = world.add_particle_system(def);
    for (int i = 0; i < 130; ++i)
      for (int j = 0; j < 130; ++j)
        world.spawn_particle(ps, Vec3(0.021 * i, 0.021 * j, 0.01), Vec3::Zero(), 1e-3, 0.01, 100);
    world.advance(0.75);  // asleep after 0.5 s at rest
    const ParticleView v = world.particles(ps);
    std::size_t still = 0;
    for (std::size_t i = 0; i < v.count; ++i) still += velocity_of(v, i) == Vec3::Zero();
    return std::pair(world.state_hash(), still);
  };
  const auto [hash1, still1] = run(1);
  const auto [hash2, still2] = run(2);
  EXPECT_EQ(hash1, hash2);
  EXPECT_EQ(still1, still2);
  // Every bead sleeps; without sleep, gravity leaves no stored velocity exactly zero.
  EXPECT_EQ(still1, 130u * 130u);
}

}  // namespace
}  // namespace simreel::sim
