#pragma once
// Contact manifold of any two convex shapes (support.hpp kinds), built on collide()'s single
// contact (GJK/EPA, Coutinho §4.7):
//   - box–box: the 15-axis SAT of box_box.hpp;
//   - a polytope (box, or hull with its faces) against anything with a flat feature: the face of
//     either shape most aligned with collide()'s normal becomes the reference face when its own
//     separation is within the face bias of the true one (so it really is the contact plane,
//     not an edge–edge or corner contact seen at an angle), and the other shape's incident face
//     (polytope), core segment (capsule) or cap/side line (cylinder) is clipped against it
//     (clip.hpp): up to 4 points;
//   - two side-by-side capsules: two points, the ends of the overlap of their axes;
//   - everything else (a sphere, an edge–edge or corner contact, a tilted cylinder rim, two
//     cylinders): collide()'s one point.
// Limits: a cylinder cap is approximated by the inscribed square of four rim points (support
// area 2/pi of the disc); a cylinder never serves as the reference face (its flat cap against
// another cylinder gives one point); a hull without HullFaces, or with a face of more than
// kMaxClipVertices / 2 vertices, gives one point. Private.
//
// Conventions as in manifold.hpp: normal unit from A to B, separation (m) < 0 is penetration.

#include "collision/convex_contact.hpp"
#include "collision/manifold.hpp"
#include "collision/polytope_faces.hpp"

namespace simreel::sim::detail {

/// Manifold of A and B. faces_a / faces_b: the planar faces of a hull shape (built once by
/// make_hull_faces on the same vertex array the shape's span shows); ignored for other kinds.
/// Empty (count 0) when the shapes are farther apart than options.margin. Deterministic; no heap.
[[nodiscard]] Manifold collide_manifold(const PosedShape& A, const PosedShape& B,
                                        const ManifoldOptions& options = {},
                                        const HullFaces* faces_a = nullptr,
                                        const HullFaces* faces_b = nullptr);

/// collide()'s contact as a one-point manifold (id: shape, shape); empty when not touching.
[[nodiscard]] Manifold manifold_from_contact(const ConvexContact& c);

}  // namespace simreel::sim::detail
