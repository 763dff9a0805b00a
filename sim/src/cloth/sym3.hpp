#pragma once
// A symmetric 3x3 block for the cloth's implicit solver (private to cloth/).

#include <cstddef>

#include "simreel/sim/types.hpp"

namespace simreel::sim::detail {

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
  /// Reads the 6 numbers from p[0], p[stride], ... p[5 stride] (xx xy xz yy yz zz): the inverse
  /// of store().
  static Sym3 load(const double* p, std::size_t stride) {
    return {p[0], p[stride], p[2 * stride], p[3 * stride], p[4 * stride], p[5 * stride]};
  }
  /// Writes the 6 numbers to p[0], p[stride], ... p[5 stride] (xx xy xz yy yz zz): one entry of
  /// a structure of arrays (the implicit solver's layout, spring_stencil.hpp).
  void store(double* p, std::size_t stride) const {
    p[0] = xx;
    p[stride] = xy;
    p[2 * stride] = xz;
    p[3 * stride] = yy;
    p[4 * stride] = yz;
    p[5 * stride] = zz;
  }
};

}  // namespace simreel::sim::detail
