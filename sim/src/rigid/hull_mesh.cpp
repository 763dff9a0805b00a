// The public face of the engine's quickhull (rigid/convex_hull.hpp) for the program's drawables.
#include "simreel/sim/hull_mesh.hpp"

#include <string>

#include "rigid/convex_hull.hpp"

namespace simreel::sim {

HullMesh hull_mesh(std::span<const Vec3> points) {
  detail::ConvexHull h = detail::convex_hull(points);
  HullMesh m;
  m.vertices = std::move(h.vertices);
  m.faces = std::move(h.faces);
  m.triangles = std::move(h.triangles);
  return m;
}

}  // namespace simreel::sim
