// The candidate tests of the particle–particle pair search (particle_pairs.cpp, Coutinho
// §2.3.1): which of a cell's neighbours a pair may reach, one at a time or eight (AVX-512VL) or
// four (AVX2) at a time with the kept ones compressed to the front. Every form performs the
// scalar test's operations in each lane, so the pairs and their order are the same.
#pragma once

#include <cstddef>
#include <cstdint>

namespace simreel::sim::detail {

/// d2[k] = the squared distance (m²) from (xi, yi, zi) to candidate k (cx, cy, cz; m) when it
/// is within reach (ri + r_k + margin min(ri, r_k)) and not coincident, else 0, for k < m;
/// element-wise (the scalar arithmetic in every lane), so each vector clone gives the same bits.
void within_reach(double xi, double yi, double zi, double ri, double margin, const double* cx,
                  const double* cy, const double* cz, const double* cr, std::size_t m, double* d2);

/// A box (m) around a cell's particles: lo, hi per axis, and how far past it a pair still reaches.
struct ReachBox {
  double lx, ly, lz, hx, hy, hz, reach;
};

/// Writes the sorted positions s in the runs [rb[u], re[u]) (u < runs, in order) that are not
/// farther than box.reach past the box along any axis (fl(c - hi) <= reach and fl(lo - c) <=
/// reach on x, y and z) to the candidate arrays (cs: s; cx, cy, cz, cr: its position and
/// radius, from px, py, pz, pr), in order; returns the count. All of a cell's runs in one call.
/// May write up to 8 entries past the result (the callers' slack).
using GatherInBox = std::size_t (*)(const std::uint32_t* rb, const std::uint32_t* re, int runs,
                                    const double* px, const double* py, const double* pz,
                                    const double* pr, const ReachBox& box, std::uint32_t* cs,
                                    double* cx, double* cy, double* cz, double* cr);

/// The candidates [0, m) within reach of particle (xi, yi, zi, ri): within_reach()'s test, the
/// places and squared distances of those within reach written to the front of `hit` and `hd2`,
/// in order; returns the count. May write up to 8 entries past it, and may read (not use) up to
/// 3 entries past the end of cx, cy, cz and cr (the callers' candidate lists have 8 of slack).
/// One pass instead of within_reach() and a scan of its output.
using InReach = std::size_t (*)(double xi, double yi, double zi, double ri, double margin,
                                const double* cx, const double* cy, const double* cz,
                                const double* cr, std::size_t m, std::uint32_t* hit, double* hd2);

/// The GatherInBox form of `lanes` (8, 4 or 1; at most compress_width()).
GatherInBox gather_in_box(int lanes);

/// The InReach form of `lanes` (8 or 4; at most compress_width()), or null for 1 (the caller
/// then runs within_reach() and scans its output).
InReach in_reach(int lanes);

}  // namespace simreel::sim::detail
