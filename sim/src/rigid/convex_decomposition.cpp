// Convex decomposition by recursive plane cuts through reflex edges (Coutinho App. F; see the
// header for where this departs from the book).
#include "simreel/sim/convex_decomposition.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <numbers>
#include <numeric>
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>

#include "rigid/convex_hull.hpp"
#include "rigid/mass_properties.hpp"

namespace simreel::sim {
namespace {

using Tri = std::array<std::uint32_t, 3>;

struct Part {
  std::vector<Vec3> v;
  std::vector<Tri> t;
};

double volume(const Part& p) {
  double six_v = 0.0;
  for (const Tri& t : p.t) six_v += p.v[t[0]].dot(p.v[t[1]].cross(p.v[t[2]]));
  return six_v / 6.0;
}

/// The part's hull as outward planes (n, offset: n·x <= offset inside) and its volume; empty for a
/// flat or degenerate point set.
struct Hull {
  std::vector<std::pair<Vec3, double>> planes;
  double volume = 0.0;
};

Hull hull_of(std::span<const Vec3> points) {
  Hull h;
  try {
    detail::ConvexHullOptions raw;  // planes and volume only: the coplanar merge is not needed
    raw.merge_coplanar = false;
    const detail::ConvexHull ch = detail::convex_hull(points, raw);
    Part p{ch.vertices, ch.triangles};
    h.volume = volume(p);
    for (const Tri& t : ch.triangles) {
      Vec3 n = (ch.vertices[t[1]] - ch.vertices[t[0]]).cross(ch.vertices[t[2]] - ch.vertices[t[0]]);
      const double len = n.norm();
      if (len == 0.0) continue;
      n /= len;
      h.planes.emplace_back(n, n.dot(ch.vertices[t[0]]));
    }
  } catch (const std::exception&) {  // flat, or too close to flat to build
    h = {};
  }
  return h;
}

/// How far `x` lies inside the hull (m; 0 on its surface).
double depth(const Hull& h, const Vec3& x) {
  double d = INFINITY;
  for (const auto& [n, off] : h.planes) d = std::min(d, off - n.dot(x));
  return h.planes.empty() ? 0.0 : std::max(d, 0.0);
}

struct ReflexEdge {
  std::uint32_t a, b;  // vertex indices, the edge a→b of face n1
  Vec3 n1, n2;         // unit outward normals of the two faces
  double depth;        // deepest of a, b and the midpoint inside the hull (m)
};

/// Reflex edges of a closed part, deepest first (ties by vertex indices, for determinism).
std::vector<ReflexEdge> reflex_edges(const Part& p, const Hull& hull, double tol) {
  std::map<std::pair<std::uint32_t, std::uint32_t>, std::uint32_t> face_of;  // directed edge → face
  for (std::uint32_t f = 0; f < p.t.size(); ++f)
    for (int k = 0; k < 3; ++k) face_of[{p.t[f][std::size_t(k)], p.t[f][std::size_t((k + 1) % 3)]}] = f;
  const auto normal = [&](std::uint32_t f) {
    const Tri& t = p.t[f];
    const Vec3 n = (p.v[t[1]] - p.v[t[0]]).cross(p.v[t[2]] - p.v[t[0]]);
    const double len = n.norm();
    return len > 0.0 ? Vec3(n / len) : Vec3::Zero();
  };
  std::vector<ReflexEdge> out;
  for (std::uint32_t f = 0; f < p.t.size(); ++f)
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t a = p.t[f][std::size_t(k)], b = p.t[f][std::size_t((k + 1) % 3)];
      if (a > b) continue;  // each undirected edge once
      const auto it = face_of.find({b, a});
      if (it == face_of.end()) continue;
      const std::uint32_t g = it->second;
      const Vec3 n1 = normal(f), n2 = normal(g);
      if (n1.isZero() || n2.isZero()) continue;  // a sliver from a cap's collinear corners
      // The other face's far corner above this face's plane: the solid bends outwards here.
      std::uint32_t d = p.t[g][0];
      for (std::uint32_t c : p.t[g])
        if (c != a && c != b) d = c;
      if (n1.dot(p.v[d] - p.v[a]) <= tol) continue;
      const double dep =
          std::max({depth(hull, p.v[a]), depth(hull, p.v[b]), depth(hull, 0.5 * (p.v[a] + p.v[b]))});
      out.push_back({a, b, n1, n2, dep});
    }
  std::stable_sort(out.begin(), out.end(), [](const ReflexEdge& x, const ReflexEdge& y) { return x.depth > y.depth; });
  return out;
}

/// Ear clipping of a simple polygon, counter-clockwise in (x, y); appends triangles of indices
/// into `ids`. False if no ear is found (a self-touching polygon).
bool ear_clip(std::vector<Eigen::Vector2d> q, std::vector<std::uint32_t> ids, std::vector<Tri>& out) {
  const auto cross = [](const Eigen::Vector2d& o, const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
    return (a.x() - o.x()) * (b.y() - o.y()) - (a.y() - o.y()) * (b.x() - o.x());
  };
  // Cut points interpolated along a straight face edge are straight only to rounding.
  Eigen::Vector2d lo = q[0], hi = q[0];
  for (const auto& x : q) {
    lo = lo.cwiseMin(x);
    hi = hi.cwiseMax(x);
  }
  const double tol = 1e-12 * (hi - lo).squaredNorm();
  while (q.size() > 3) {
    const std::size_t n = q.size();
    bool clipped = false;
    for (int pass = 0; pass < 2 && !clipped; ++pass)
      for (std::size_t i = 0; i < n && !clipped; ++i) {
        const std::size_t ip = (i + n - 1) % n, in = (i + 1) % n;
        const double c = cross(q[ip], q[i], q[in]);
        // Pass 0: strictly convex corners; pass 1: a straight corner (a cut point on an edge)
        // may go as a sliver so the cap keeps every boundary vertex (no T-junctions).
        if (pass == 0 ? c <= tol : c < -tol) continue;
        bool empty = true;
        for (std::size_t j = 0; j < n && empty; ++j) {
          if (j == ip || j == i || j == in) continue;
          if (q[j] == q[ip] || q[j] == q[i] || q[j] == q[in]) continue;
          if (cross(q[ip], q[i], q[j]) >= -tol && cross(q[i], q[in], q[j]) >= -tol && cross(q[in], q[ip], q[j]) >= -tol)
            empty = false;
        }
        if (!empty) continue;
        out.push_back({ids[ip], ids[i], ids[in]});
        q.erase(q.begin() + std::ptrdiff_t(i));
        ids.erase(ids.begin() + std::ptrdiff_t(i));
        clipped = true;
      }
    if (!clipped) return false;
  }
  out.push_back({ids[0], ids[1], ids[2]});
  return true;
}

/// Disjoint sets over 0..n-1; a set is named by its smallest member, so groupings come out in a
/// fixed order.
struct DisjointSets {
  std::vector<std::uint32_t> parent;
  explicit DisjointSets(std::size_t n) : parent(n) { std::iota(parent.begin(), parent.end(), 0u); }
  std::uint32_t find(std::uint32_t x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  }
  void join(std::uint32_t a, std::uint32_t b) {
    a = find(a);
    b = find(b);
    if (a != b) parent[std::max(a, b)] = std::min(a, b);
  }
};

/// Connected pieces of a closed triangle soup (its triangles grouped). Triangles join across an edge only
/// when exactly two hold it: two solids touching along an edge or at a corner (a cut through a
/// reflex edge can leave such) are two pieces, each closed.
std::vector<std::vector<Tri>> components(const std::vector<Tri>& t) {
  DisjointSets sets(t.size());
  std::map<std::pair<std::uint32_t, std::uint32_t>, std::vector<std::uint32_t>> faces_at;
  for (std::uint32_t f = 0; f < t.size(); ++f)
    for (int k = 0; k < 3; ++k)
      faces_at[std::minmax(t[f][std::size_t(k)], t[f][std::size_t((k + 1) % 3)])].push_back(f);
  for (const auto& [e, fs] : faces_at)
    if (fs.size() == 2) {
      sets.join(fs[0], fs[1]);
    }
  std::map<std::uint32_t, std::size_t> group_of;
  std::vector<std::vector<Tri>> groups;
  for (std::uint32_t f = 0; f < t.size(); ++f) {
    const auto [it, fresh] = group_of.emplace(sets.find(f), groups.size());
    if (fresh) groups.emplace_back();
    groups[it->second].push_back(t[f]);
  }
  return groups;
}

/// The triangles as a part of their own (vertices renumbered in order of first use).
Part compact(const std::vector<Vec3>& v, const std::vector<Tri>& t) {
  Part p;
  std::map<std::uint32_t, std::uint32_t> remap;
  for (const Tri& tri : t) {
    Tri local;
    for (int k = 0; k < 3; ++k) {
      const auto [m, added] = remap.emplace(tri[std::size_t(k)], std::uint32_t(p.v.size()));
      if (added) p.v.push_back(v[tri[std::size_t(k)]]);
      local[std::size_t(k)] = m->second;
    }
    p.t.push_back(local);
  }
  return p;
}

/// The part cut by the plane n·x = off along the cut face through vertex `through` (the reflex
/// edge's; App. F cuts only that face, so other crossings of the plane stay joined), as closed
/// parts; nothing when that cut face is not a simple polygon (a hole, App. F condition 15; a
/// pinch) or it comes out degenerate.
std::optional<std::vector<Part>> cut(const Part& p, const Vec3& n, double off, std::uint32_t through, double eps) {
  std::vector<Vec3> v = p.v;
  std::vector<int> side(v.size());
  for (std::size_t i = 0; i < v.size(); ++i) {
    const double d = n.dot(v[i]) - off;
    side[i] = d > eps ? 1 : d < -eps ? -1 : 0;
  }
  std::map<std::pair<std::uint32_t, std::uint32_t>, std::uint32_t> cut_point;
  const auto crossing = [&](std::uint32_t a, std::uint32_t b) {
    const auto key = std::minmax(a, b);
    const auto it = cut_point.find(key);
    if (it != cut_point.end()) return it->second;
    const double da = n.dot(v[key.first]) - off, db = n.dot(v[key.second]) - off;
    v.push_back(v[key.first] + (da / (da - db)) * (v[key.second] - v[key.first]));
    side.push_back(0);
    const auto id = std::uint32_t(v.size() - 1);
    cut_point.emplace(key, id);
    return id;
  };
  std::array<std::vector<Tri>, 2> tris;  // [0] below (n·x < off), [1] above
  const auto fan = [&](const std::vector<std::uint32_t>& poly, int s) {
    for (std::size_t k = 1; k + 1 < poly.size(); ++k) tris[std::size_t(s)].push_back({poly[0], poly[k], poly[k + 1]});
  };
  for (const Tri& t : p.t) {
    const int s0 = side[t[0]], s1 = side[t[1]], s2 = side[t[2]];
    const bool any_above = s0 > 0 || s1 > 0 || s2 > 0, any_below = s0 < 0 || s1 < 0 || s2 < 0;
    if (!any_above && !any_below) {
      // In the plane: part of the cut face (App. F, Fig. F.7), which the caps below rebuild;
      // kept, it would leave a hole in the cap of one side and a flap on the other.
      continue;
    } else if (!any_below) {
      tris[1].push_back(t);
    } else if (!any_above) {
      tris[0].push_back(t);
    } else {
      std::vector<std::uint32_t> below, above;
      for (int k = 0; k < 3; ++k) {
        const std::uint32_t a = t[std::size_t(k)], b = t[std::size_t((k + 1) % 3)];
        if (side[a] <= 0) below.push_back(a);
        if (side[a] >= 0) above.push_back(a);
        if (side[a] * side[b] < 0) {
          const std::uint32_t c = crossing(a, b);
          below.push_back(c);
          above.push_back(c);
        }
      }
      fan(below, 0);
      fan(above, 1);
    }
  }
  if (tris[0].empty() || tris[1].empty()) return std::nullopt;
  // Basis of the plane, u × w = n.
  const Vec3 u = (std::abs(n.x()) < 0.9 ? Vec3::UnitX() : Vec3::UnitY()).cross(n).normalized();
  const Vec3 w = n.cross(u);
  // Loops of boundary half-edges (no twin on their side) lie in the plane. On each side, the loop
  // through `through` is the cut face's outline and gets a cap; the others are left open on both
  // sides, which glues the two sides back together there.
  std::vector<char> open_vertex(v.size(), 0), cap_vertex(v.size(), 0);
  std::array<std::vector<std::vector<Eigen::Vector2d>>, 2> open_loops;
  std::array<std::vector<Eigen::Vector2d>, 2> face;
  for (int s = 0; s < 2; ++s) {
    const std::vector<Tri>& ts = tris[std::size_t(s)];
    std::map<std::pair<std::uint32_t, std::uint32_t>, int> count;
    for (const Tri& t : ts)
      for (int k = 0; k < 3; ++k) ++count[{t[std::size_t(k)], t[std::size_t((k + 1) % 3)]}];
    std::map<std::uint32_t, std::uint32_t> next;
    for (const auto& [e, c] : count) {
      if (c != 1) return std::nullopt;  // a non-manifold edge
      if (count.count({e.second, e.first})) continue;
      if (!next.emplace(e.first, e.second).second) return std::nullopt;  // a pinch
    }
    // The cap of the part below faces +n, above −n; its winding is the loop's reversed.
    const double facing = s == 0 ? 1.0 : -1.0;
    bool capped = false;
    while (!next.empty()) {
      std::vector<std::uint32_t> loop;
      std::uint32_t at = next.begin()->first;
      while (true) {
        const auto it = next.find(at);
        if (it == next.end()) break;
        loop.push_back(at);
        at = it->second;
        next.erase(it);
      }
      if (loop.size() < 3 || at != loop.front()) return std::nullopt;
      std::reverse(loop.begin(), loop.end());
      std::vector<Eigen::Vector2d> q;
      for (std::uint32_t id : loop) q.emplace_back(v[id].dot(u), facing * v[id].dot(w));
      if (std::find(loop.begin(), loop.end(), through) == loop.end()) {
        for (std::uint32_t id : loop) open_vertex[id] = 1;
        open_loops[std::size_t(s)].push_back(std::move(q));
        continue;
      }
      if (capped) return std::nullopt;  // the reflex vertex on two loops: a pinch
      capped = true;
      double area2 = 0.0;
      for (std::size_t k = 0; k < q.size(); ++k) {
        const auto& a = q[k];
        const auto& b = q[(k + 1) % q.size()];
        area2 += a.x() * b.y() - a.y() * b.x();
      }
      if (area2 <= 0.0) return std::nullopt;  // the cut face is a hole's outline
      face[std::size_t(s)] = q;
      for (std::uint32_t id : loop) cap_vertex[id] = 1;
      if (!ear_clip(std::move(q), loop, tris[std::size_t(s)])) return std::nullopt;
    }
    if (!capped) return std::nullopt;
  }
  // The cut face's outline seen from one side must be the whole of it seen from the other.
  for (std::size_t id = 0; id < v.size(); ++id)
    if (open_vertex[id] && cap_vertex[id]) return std::nullopt;
  // A hole in the cut face: another loop inside it (App. F condition 15).
  for (int s = 0; s < 2; ++s)
    for (const auto& q : open_loops[std::size_t(s)]) {
      const Eigen::Vector2d& x = q.front();
      const auto& f = face[std::size_t(s)];
      bool inside = false;
      for (std::size_t k = 0, j = f.size() - 1; k < f.size(); j = k++)
        if ((f[k].y() > x.y()) != (f[j].y() > x.y()) &&
            x.x() < (f[j].x() - f[k].x()) * (x.y() - f[k].y()) / (f[j].y() - f[k].y()) + f[k].x())
          inside = !inside;
      if (inside) return std::nullopt;
    }
  // The cut face's corners, twice: a cut that does not separate the part (the first cut through
  // a ring) leaves it one part whose two caps touch, and each cap needs its own corners to stay a
  // closed, manifold surface (App. F's "double-occurring face", Fig. F.3).
  {
    std::map<std::uint32_t, std::uint32_t> twin;
    for (Tri& t : tris[1])
      for (std::uint32_t& id : t) {
        if (side[id] != 0 || open_vertex[id]) continue;
        const auto [it, fresh] = twin.emplace(id, std::uint32_t(v.size()));
        if (fresh) v.push_back(v[id]);
        id = it->second;
      }
  }
  // Each side's pieces; those sharing a loop left open are one part again.
  std::vector<std::vector<Tri>> groups = components(tris[0]);
  for (auto& g : components(tris[1])) groups.push_back(std::move(g));
  DisjointSets sets(groups.size());
  std::map<std::uint32_t, std::uint32_t> group_at;  // an open-loop vertex → the first group using it
  for (std::uint32_t g = 0; g < groups.size(); ++g)
    for (const Tri& t : groups[g])
      for (std::uint32_t id : t) {
        if (id >= open_vertex.size() || !open_vertex[id]) continue;  // a cut face's twin corner is never open
        const auto [it, fresh] = group_at.emplace(id, g);
        if (!fresh) sets.join(it->second, g);
      }
  std::map<std::uint32_t, std::size_t> part_of;
  std::vector<std::vector<Tri>> merged;
  for (std::uint32_t g = 0; g < groups.size(); ++g) {
    const auto [it, fresh] = part_of.emplace(sets.find(g), merged.size());
    if (fresh) merged.emplace_back();
    merged[it->second].insert(merged[it->second].end(), groups[g].begin(), groups[g].end());
  }
  std::vector<Part> out;
  for (const auto& m : merged) {
    out.push_back(compact(v, m));
    if (!detail::closed_oriented_error(out.back().t).empty()) return std::nullopt;
  }
  return out;
}

struct Piece {
  Part part;
  Hull hull;
  double volume;
};

Piece make_piece(Part part) {
  Piece p{std::move(part), {}, 0.0};
  p.hull = hull_of(p.part.v);
  p.volume = volume(p.part);
  return p;
}

}  // namespace

std::vector<ConvexPiece> convex_decomposition(std::span<const Vec3> vertices, std::span<const Tri> triangles,
                                              const ConvexDecompositionOptions& options) {
  Part whole{{vertices.begin(), vertices.end()}, {triangles.begin(), triangles.end()}};
  for (const Tri& t : whole.t)
    for (std::uint32_t i : t)
      if (i >= whole.v.size())
        throw std::invalid_argument("convex_decomposition: a triangle indexes vertex " + std::to_string(i) + " of " +
                                    std::to_string(whole.v.size()));
  if (const std::string e = detail::closed_oriented_error(whole.t); !e.empty())
    throw std::invalid_argument("convex_decomposition: " + e);
  Vec3 lo = Vec3::Constant(INFINITY), hi = Vec3::Constant(-INFINITY);
  for (const Vec3& x : whole.v) {
    lo = lo.cwiseMin(x);
    hi = hi.cwiseMax(x);
  }
  const double size = (hi - lo).norm();
  const double total = volume(whole);
  if (!(size > 0.0) || !(total > 1e-12 * size * size * size))
    throw std::invalid_argument("convex_decomposition: the mesh bounds no volume (outward winding expected)");
  const double concavity = options.max_concavity > 0.0 ? options.max_concavity : 0.01 * size;
  // Vertices this close to a cut plane count as on it: a cut point is then never closer than
  // this to a corner, which keeps the pieces' hulls (quickhull, tolerance 1e-10 of the size)
  // well conditioned.
  const double eps = 1e-6 * size;
  const std::size_t max_pieces = std::size_t(std::max(options.max_convex_hulls, 1));

  std::vector<Piece> todo{make_piece(whole)};
  std::vector<Piece> done;
  // Depth-first over a stack kept in order, so the pieces come out in a fixed order.
  while (!todo.empty()) {
    Piece piece = std::move(todo.back());
    todo.pop_back();
    const std::vector<ReflexEdge> reflex = reflex_edges(piece.part, piece.hull, eps);
    // Deep reflex edges, or a hull that over-fills the part (reflex edges on the hull's surface:
    // two lobes joined by a thin neck), mean a cut is due.
    const double excess_allowed = concavity * std::cbrt(piece.hull.volume) * std::cbrt(piece.hull.volume);
    const bool shallow = reflex.empty() || reflex.front().depth <= concavity;
    const bool convex = reflex.empty() || (shallow && piece.hull.volume - piece.volume <= excess_allowed);
    if (convex || done.size() + todo.size() + 2 > max_pieces) {
      done.push_back(std::move(piece));
      continue;
    }
    std::optional<std::vector<Piece>> best;
    double best_cost = INFINITY;
    // The deepest reflex edges first; the first one with a valid cut is resolved.
    for (std::size_t e = 0; e < reflex.size() && e < 8 && !best; ++e) {
      const ReflexEdge& r = reflex[e];
      if (r.depth <= concavity && !shallow) break;
      // The interior wedge at the edge runs from face 1's direction t1 the long way round to
      // face 2's t2 (the short way, under π, is outside). Its bisectors are planes through the
      // edge and t1 turned into the solid by a fraction of the interior angle.
      const Vec3& pa = piece.part.v[r.a];
      const Vec3 dir = (piece.part.v[r.b] - pa).normalized();
      const Vec3 t1 = r.n1.cross(dir).normalized(), t2 = dir.cross(r.n2).normalized();
      const double exterior = std::atan2(dir.dot(t1.cross(t2)), t1.dot(t2));  // signed, about e
      const double interior = exterior >= 0 ? exterior - 2.0 * std::numbers::pi : exterior + 2.0 * std::numbers::pi;
      const auto turned = [&](double frac) {
        const Eigen::AngleAxisd rot(frac * interior, dir);
        return dir.cross(rot * t1);
      };
      const Vec3 candidates[] = {r.n1, r.n2, turned(0.5), turned(0.25), turned(0.75)};
      for (const Vec3& c : candidates) {
        if (c.norm() < 1e-9) continue;
        const Vec3 m = c.normalized();
        const std::optional<std::vector<Part>> parts = cut(piece.part, m, m.dot(piece.part.v[r.a]), r.a, eps);
        if (!parts) continue;
        std::vector<Piece> ps;
        double cost = 0.0;
        bool ok = true;
        for (const Part& q : *parts) {
          ps.push_back(make_piece(q));
          if (!(ps.back().volume > 1e-9 * total) || ps.back().hull.planes.empty()) ok = false;
          cost += ps.back().hull.volume - ps.back().volume;
        }
        // Fewer parts win a tie (costs equal to rounding: a plane along a face versus a bisector).
        cost += 1e-9 * total * double(ps.size());
        if (ok && cost < best_cost - 1e-12 * total) {
          best_cost = cost;
          best = std::move(ps);
        }
      }
    }
    if (!best) {
      done.push_back(std::move(piece));  // nothing resolves: keep its hull
      continue;
    }
    for (auto it = best->rbegin(); it != best->rend(); ++it) todo.push_back(std::move(*it));
  }
  if (done.size() == 1) return {ConvexPiece(vertices.begin(), vertices.end())};

  // Merge neighbours whose union is still convex within the tolerance: the whole-part cuts split
  // more than App. F's cut faces would.
  std::vector<std::vector<Vec3>> points;
  std::vector<double> vol;
  for (const Piece& p : done) {
    points.push_back(p.part.v);
    vol.push_back(p.volume);
  }
  for (bool merged = true; merged;) {
    merged = false;
    for (std::size_t i = 0; i < points.size() && !merged; ++i)
      for (std::size_t j = i + 1; j < points.size() && !merged; ++j) {
        std::vector<Vec3> both = points[i];
        both.insert(both.end(), points[j].begin(), points[j].end());
        const Hull h = hull_of(both);
        // Tolerance: the concavity allowed, spread over the union's hull surface is about
        // concavity × area; use the volume form V_hull − V ≤ concavity × V^(2/3) as its scale.
        const double v = vol[i] + vol[j];
        if (h.volume - v > concavity * std::cbrt(v) * std::cbrt(v)) continue;
        // Only neighbours: a shared corner (the cut points are the same numbers on both sides).
        bool touch = false;
        for (const Vec3& a : points[i])
          for (const Vec3& b : points[j])
            if (a == b) touch = true;
        if (!touch) continue;
        points[i] = std::move(both);
        vol[i] = v;
        points.erase(points.begin() + std::ptrdiff_t(j));
        vol.erase(vol.begin() + std::ptrdiff_t(j));
        merged = true;
      }
  }
  for (auto& ps : points) {  // shared cut corners appear once per piece
    std::vector<Vec3> unique;
    for (const Vec3& x : ps)
      if (std::find(unique.begin(), unique.end(), x) == unique.end()) unique.push_back(x);
    ps = std::move(unique);
  }
  return points;
}

}  // namespace simreel::sim
