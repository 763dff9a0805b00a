// Quickhull in 3-D (Barber, Dobkin & Huhdanpaa 1996) with a distance tolerance, then an
// optional pass that merges coplanar triangles into polygons (Coutinho §2.2.4 for the hull).
#include "rigid/convex_hull.hpp"

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <utility>

#include "rigid/mass_properties.hpp"

namespace simreel::sim::detail {
namespace {

using Tri = std::array<std::uint32_t, 3>;

/// A hull triangle during construction. Edge k runs v[k] -> v[k+1]; adj[k] is the face across it.
struct Face {
  Tri v{};
  std::array<std::int32_t, 3> adj{-1, -1, -1};
  Vec3 normal = Vec3::Zero();  ///< unit outward normal (zero for a sliver without a direction)
  double offset = 0.0;         ///< plane: normal · x = offset
  std::vector<std::uint32_t> outside;  ///< points strictly in front (beyond the tolerance)
  std::uint32_t farthest = 0;          ///< the outside point farthest from the plane
  double farthest_distance = -1.0;
  std::uint32_t stamp = 0;  ///< visibility pass that last looked at this face
  bool visible = false;     ///< result of that pass
  bool alive = true;
};

class Builder {
 public:
  Builder(std::span<const Vec3> points, double eps) : p_(points), eps_(eps) {}

  std::vector<Face> faces;

  double distance(const Face& f, std::uint32_t i) const { return f.normal.dot(p_[i]) - f.offset; }

  std::int32_t add_face(std::uint32_t a, std::uint32_t b, std::uint32_t c) {
    Face f;
    f.v = {a, b, c};
    const Vec3 n = (p_[b] - p_[a]).cross(p_[c] - p_[a]);
    const double length = n.norm();
    if (length > 0.0) {
      f.normal = n / length;
      // The plane through the centroid rather than one corner: less sensitive to which corner.
      f.offset = f.normal.dot((p_[a] + p_[b] + p_[c]) / 3.0);
    }
    faces.push_back(std::move(f));
    return std::int32_t(faces.size() - 1);
  }

  /// Puts point i into the outside set of the first face in [first, last) it is in front of;
  /// a point in front of none is inside the hull (or on it) and is dropped for good.
  void assign(std::uint32_t i, std::size_t first, std::size_t last) {
    for (std::size_t k = first; k < last; ++k) {
      Face& f = faces[k];
      const double d = distance(f, i);
      if (d > eps_) {
        f.outside.push_back(i);
        if (d > f.farthest_distance) {
          f.farthest_distance = d;
          f.farthest = i;
        }
        return;
      }
    }
  }

  void initial_simplex(std::array<std::uint32_t, 4> s) {
    const auto [a, b, c, d] = s;
    // Base (a, b, c) wound so that d is behind it; the sides reverse each base edge.
    const bool flip = (p_[d] - p_[a]).dot((p_[b] - p_[a]).cross(p_[c] - p_[a])) > 0.0;
    const std::uint32_t b2 = flip ? c : b, c2 = flip ? b : c;
    add_face(a, b2, c2);
    add_face(b2, a, d);
    add_face(c2, b2, d);
    add_face(a, c2, d);
    for (std::size_t f = 0; f < 4; ++f)
      for (int k = 0; k < 3; ++k)
        for (std::size_t g = 0; g < 4; ++g)
          for (int j = 0; j < 3; ++j)
            if (faces[g].v[j] == faces[f].v[(k + 1) % 3] &&
                faces[g].v[(j + 1) % 3] == faces[f].v[k])
              faces[f].adj[k] = std::int32_t(g);
    for (std::uint32_t i = 0; i < p_.size(); ++i)
      if (i != a && i != b && i != c && i != d) assign(i, 0, 4);
  }

  void run() {
    std::vector<std::int32_t> work;
    for (std::int32_t f = 0; f < 4; ++f)
      if (!faces[f].outside.empty()) work.push_back(f);
    std::vector<std::int32_t> start_of(p_.size(), -1);  // new face whose horizon edge starts here
    std::uint32_t stamp = 0;
    std::vector<std::int32_t> visible, stack;
    struct Horizon {
      std::uint32_t a, b;
      std::int32_t behind;  // the face that stays, across a -> b
    };
    std::vector<Horizon> horizon;
    while (!work.empty()) {
      const std::int32_t seed = work.back();
      work.pop_back();
      if (!faces[seed].alive || faces[seed].outside.empty()) continue;
      const std::uint32_t eye = faces[seed].farthest;
      const Vec3& e = p_[eye];

      // Faces the eye sees (in front beyond the tolerance), grown from the seed through
      // neighbours so the region is connected; its boundary edges form the horizon.
      ++stamp;
      visible.clear();
      horizon.clear();
      stack.assign(1, seed);
      faces[seed].stamp = stamp;
      faces[seed].visible = true;
      while (!stack.empty()) {
        const std::int32_t g = stack.back();
        stack.pop_back();
        visible.push_back(g);
        for (int k = 0; k < 3; ++k) {
          Face& h = faces[faces[g].adj[k]];
          if (h.stamp != stamp) {
            h.stamp = stamp;
            h.visible = h.normal.dot(e) - h.offset > eps_;
            if (h.visible) stack.push_back(faces[g].adj[k]);
          }
          if (!h.visible)
            horizon.push_back({faces[g].v[k], faces[g].v[(k + 1) % 3], faces[g].adj[k]});
        }
      }

      // A cone of new faces (a, b, eye) over the horizon, each wound like the face it replaces.
      const std::size_t first_new = faces.size();
      for (const Horizon& h : horizon) {
        if (start_of[h.a] != -1)
          throw std::runtime_error("convex_hull: the horizon is not a simple loop (rounding)");
        const std::int32_t f = add_face(h.a, h.b, eye);
        start_of[h.a] = f;
        faces[f].adj[0] = h.behind;
        Face& behind = faces[h.behind];
        for (int j = 0; j < 3; ++j)
          if (behind.v[j] == h.b && behind.v[(j + 1) % 3] == h.a) behind.adj[j] = f;
      }
      for (std::size_t f = first_new; f < faces.size(); ++f) {
        // Edge b -> eye of (a, b, eye) borders the new face whose horizon edge starts at b.
        const std::int32_t next = start_of[faces[f].v[1]];
        if (next == -1)
          throw std::runtime_error("convex_hull: the horizon is not a closed loop (rounding)");
        faces[f].adj[1] = next;
        faces[next].adj[2] = std::int32_t(f);
      }
      for (const Horizon& h : horizon) start_of[h.a] = -1;

      // The points the removed faces held go to the new faces or are inside now.
      for (const std::int32_t g : visible) {
        faces[g].alive = false;
        std::vector<std::uint32_t> held = std::move(faces[g].outside);
        faces[g].outside = {};
        for (const std::uint32_t i : held)
          if (i != eye) assign(i, first_new, faces.size());
      }
      for (std::size_t f = first_new; f < faces.size(); ++f)
        if (!faces[f].outside.empty()) work.push_back(std::int32_t(f));
    }
  }

 private:
  std::span<const Vec3> p_;
  double eps_;
};

/// Lexicographically smallest / largest point in the axis order (k, k+1, k+2): always a vertex
/// of the hull, even when many points tie on a bounding-box face (a grid on a cube's face).
std::pair<std::uint32_t, std::uint32_t> lexicographic_extremes(std::span<const Vec3> p, int k) {
  const auto less = [&](std::uint32_t i, std::uint32_t j) {
    for (int a = 0; a < 3; ++a) {
      const int axis = (k + a) % 3;
      if (p[i][axis] != p[j][axis]) return p[i][axis] < p[j][axis];
    }
    return false;
  };
  std::uint32_t lo = 0, hi = 0;
  for (std::uint32_t i = 1; i < p.size(); ++i) {
    if (less(i, lo)) lo = i;
    if (less(hi, i)) hi = i;
  }
  return {lo, hi};
}

std::array<std::uint32_t, 4> initial_points(std::span<const Vec3> p, double eps) {
  std::uint32_t a = 0, b = 0;
  double best = -1.0;
  for (int k = 0; k < 3; ++k) {
    const auto [lo, hi] = lexicographic_extremes(p, k);
    const double d = (p[hi] - p[lo]).squaredNorm();
    if (d > best) {
      best = d;
      a = lo;
      b = hi;
    }
  }
  if (std::sqrt(best) <= eps)
    throw std::invalid_argument("convex_hull: all points coincide (within the tolerance)");
  const Vec3 axis = (p[b] - p[a]).normalized();
  std::uint32_t c = a;
  best = -1.0;
  for (std::uint32_t i = 0; i < p.size(); ++i) {
    const double d = (p[i] - p[a]).cross(axis).squaredNorm();
    if (d > best) {
      best = d;
      c = i;
    }
  }
  if (std::sqrt(best) <= eps)
    throw std::invalid_argument("convex_hull: all points are collinear (within the tolerance)");
  const Vec3 normal = (p[b] - p[a]).cross(p[c] - p[a]).normalized();
  std::uint32_t d = a;
  best = -1.0;
  for (std::uint32_t i = 0; i < p.size(); ++i) {
    const double h = std::abs(normal.dot(p[i] - p[a]));
    if (h > best) {
      best = h;
      d = i;
    }
  }
  if (best <= eps)
    throw std::invalid_argument("convex_hull: all points are coplanar (within the tolerance)");
  return {a, b, c, d};
}

/// Polygons over input indices: the groups of coplanar triangles, each walked along its boundary;
/// a group whose boundary is not one loop stays as its separate triangles.
std::vector<std::vector<std::uint32_t>> merge_coplanar(const std::vector<Face>& faces,
                                                       std::span<const Vec3> p, double eps) {
  std::vector<std::int32_t> group(faces.size(), -1);
  std::vector<std::vector<std::uint32_t>> polygons;
  std::vector<std::int32_t> members, stack;
  std::vector<std::pair<std::uint32_t, std::uint32_t>> boundary;
  std::int32_t next_group = 0;
  for (std::size_t s = 0; s < faces.size(); ++s) {
    if (!faces[s].alive || group[s] != -1) continue;
    const Face& seed = faces[s];
    const std::int32_t id = next_group++;
    members.clear();
    stack.assign(1, std::int32_t(s));
    group[s] = id;
    // Grown against the seed's plane, not pairwise, so a gently curved surface cannot drift
    // into one "planar" face.
    while (!stack.empty()) {
      const std::int32_t g = stack.back();
      stack.pop_back();
      members.push_back(g);
      for (const std::int32_t h : faces[g].adj) {
        if (group[h] != -1 || faces[h].normal.dot(seed.normal) <= 0.0) continue;
        bool coplanar = true;
        for (const std::uint32_t v : faces[h].v)
          coplanar = coplanar && std::abs(seed.normal.dot(p[v]) - seed.offset) <= eps;
        if (coplanar) {
          group[h] = id;
          stack.push_back(h);
        }
      }
    }
    boundary.clear();
    for (const std::int32_t g : members)
      for (int k = 0; k < 3; ++k)
        if (group[faces[g].adj[k]] != id)
          boundary.emplace_back(faces[g].v[k], faces[g].v[(k + 1) % 3]);
    std::sort(boundary.begin(), boundary.end());
    bool simple = std::adjacent_find(boundary.begin(), boundary.end(), [](auto x, auto y) {
                    return x.first == y.first;
                  }) == boundary.end();
    std::vector<std::uint32_t> loop;
    if (simple) {
      std::uint32_t v = boundary.front().first;
      do {
        loop.push_back(v);
        const auto it = std::lower_bound(boundary.begin(), boundary.end(),
                                         std::pair<std::uint32_t, std::uint32_t>(v, 0));
        if (it == boundary.end() || it->first != v || loop.size() > boundary.size()) {
          simple = false;
          break;
        }
        v = it->second;
      } while (v != loop.front());
      simple = simple && loop.size() == boundary.size();
    }
    if (simple) {
      polygons.push_back(std::move(loop));
    } else {
      for (const std::int32_t g : members)
        polygons.push_back({faces[g].v[0], faces[g].v[1], faces[g].v[2]});
    }
  }
  return polygons;
}

/// Distance of b from the line through a and c.
double off_line(const Vec3& a, const Vec3& b, const Vec3& c) {
  const Vec3 axis = c - a;
  const double length = axis.norm();
  return length > 0.0 ? (b - a).cross(axis).norm() / length : (b - a).norm();
}

}  // namespace

ConvexHull convex_hull(std::span<const Vec3> points, const ConvexHullOptions& options) {
  if (points.size() < 4)
    throw std::invalid_argument("convex_hull: need at least 4 points, got " +
                                std::to_string(points.size()));
  if (points.size() >= std::numeric_limits<std::int32_t>::max())
    throw std::invalid_argument("convex_hull: too many points");
  Vec3 lo = Vec3::Constant(INFINITY), hi = Vec3::Constant(-INFINITY);
  double largest = 0.0;
  for (std::size_t i = 0; i < points.size(); ++i) {
    if (!points[i].allFinite())
      throw std::invalid_argument("convex_hull: point " + std::to_string(i) + " is not finite");
    lo = lo.cwiseMin(points[i]);
    hi = hi.cwiseMax(points[i]);
    largest = std::max(largest, points[i].cwiseAbs().maxCoeff());
  }
  const double eps =
      std::max(options.relative_tolerance * (hi - lo).norm(), 16.0 * DBL_EPSILON * largest);

  Builder builder(points, eps);
  builder.initial_simplex(initial_points(points, eps));
  builder.run();
  const std::vector<Face>& faces = builder.faces;

  std::vector<std::vector<std::uint32_t>> polygons;
  if (options.merge_coplanar) {
    polygons = merge_coplanar(faces, points, eps);
    // A vertex stays if it is a corner of at least one polygon; one that is on a straight edge
    // of every polygon around it (a point of a grid on a cube's edge) or inside a face goes.
    std::vector<char> corner(points.size(), 0);
    for (const auto& poly : polygons)
      for (std::size_t k = 0; k < poly.size(); ++k) {
        const std::uint32_t prev = poly[(k + poly.size() - 1) % poly.size()];
        const std::uint32_t next = poly[(k + 1) % poly.size()];
        if (off_line(points[prev], points[poly[k]], points[next]) > eps) corner[poly[k]] = 1;
      }
    for (auto& poly : polygons) std::erase_if(poly, [&](std::uint32_t v) { return !corner[v]; });
    std::erase_if(polygons, [](const auto& poly) { return poly.size() < 3; });
  }
  std::vector<Tri> triangles;
  for (const auto& poly : polygons)
    for (std::size_t k = 1; k + 1 < poly.size(); ++k)
      triangles.push_back({poly[0], poly[k], poly[k + 1]});
  if (!options.merge_coplanar || !closed_oriented_error(triangles).empty()) {
    // Unmerged (asked for, or the merge could not keep the surface closed): the raw triangles.
    polygons.clear();
    triangles.clear();
    for (const Face& f : faces)
      if (f.alive) triangles.push_back(f.v);
  }

  // Vertices in ascending input order; indices remapped.
  ConvexHull hull;
  hull.tolerance = eps;
  std::vector<std::uint32_t> remap(points.size(), 0);
  std::vector<char> used(points.size(), 0);
  for (const Tri& t : triangles)
    for (const std::uint32_t v : t) used[v] = 1;
  for (std::uint32_t i = 0; i < points.size(); ++i)
    if (used[i]) {
      remap[i] = std::uint32_t(hull.vertices.size());
      hull.vertices.push_back(points[i]);
      hull.input_index.push_back(i);
    }
  hull.triangles.reserve(triangles.size());
  for (const Tri& t : triangles) hull.triangles.push_back({remap[t[0]], remap[t[1]], remap[t[2]]});
  for (auto& poly : polygons) {
    for (auto& v : poly) v = remap[v];
    hull.faces.push_back(std::move(poly));
  }
  return hull;
}

}  // namespace simreel::sim::detail
