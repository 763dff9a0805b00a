// The pair lists of the pair forces' dense grid (pair_forces.cpp): the candidates of one cell
// within the cut-off appended in a fixed order, one at a time or eight (AVX-512VL) or four (AVX2)
// at a time with the kept ones compressed to the front; every form gives the same pairs in the
// same order, so the same bits in the forces (Coutinho §3.3.4).
#pragma once

#include <cstddef>
#include <cstdint>

namespace simreel::sim::detail {

/// Appends (si, cs[u], r2[u]) for each u < len with r2[u] < cut2 (false for NaN) to the pair
/// arrays (pi, pj, pr2) from place p, in candidate order; returns the new count. May write up
/// to 8 entries past the result (the caller's slack).
using AppendWithin = std::size_t (*)(std::uint32_t si, const std::uint32_t* cs, const double* r2,
                                     std::size_t len, double cut2, std::uint32_t* pi,
                                     std::uint32_t* pj, double* pr2, std::size_t p);

/// The pairs of one dense-grid cell's particles si in [first, last), read in place from the
/// sorted positions (sx, sy, sz; m): for each si in turn, the candidates of runs 0..4 (run 0
/// from si + 1, the runs [rb[r], re[r]) otherwise) with |x_si - x_s|² < cut2 (m²), appended from
/// place p in ascending s; returns the new count. May write up to 8 entries past it, and may
/// read (not use) up to 3 doubles past the end of each of sx, sy and sz: they must be readable
/// (pair forces' sorted_ holds sx, sy, sz, q, m in a row, then kCopyBlock doubles of slack).
using CellPairs = std::size_t (*)(const double* sx, const double* sy, const double* sz,
                                  std::uint32_t first, std::uint32_t last, const std::uint32_t* rb,
                                  const std::uint32_t* re, double cut2, std::uint32_t* pi,
                                  std::uint32_t* pj, double* pr2, std::size_t p);

/// The AppendWithin form of `lanes` (8, 4 or 1; at most compress_width()).
AppendWithin append_within(int lanes);

/// The in-place CellPairs form of `lanes` (8 or 4; at most compress_width()), or null for 1 (the
/// caller then copies the runs into one candidate list and uses append_within()).
CellPairs cell_pairs(int lanes);

}  // namespace simreel::sim::detail
