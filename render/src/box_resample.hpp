#pragma once
// Private: the one area-average (box filter) resample, in exact integer arithmetic; used by
// resize_box (thumbnails) and the image hashes.

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <utility>
#include <vector>

namespace simreel::render::detail {

/// Integer area weights of a 1-D box resample from `src` to `dst` samples: output i covers
/// [i*src, (i+1)*src) and source j covers [j*dst, (j+1)*dst) in units of 1/dst source pixels,
/// so every overlap is an integer and each output's weights sum to `src`.
inline std::vector<std::vector<std::pair<int, std::int64_t>>> box_weights(int src, int dst) {
  std::vector<std::vector<std::pair<int, std::int64_t>>> weights(static_cast<std::size_t>(dst));
  for (int i = 0; i < dst; ++i) {
    const std::int64_t a = std::int64_t(i) * src;
    const std::int64_t b = std::int64_t(i + 1) * src;
    for (int j = int(a / dst); j < src && std::int64_t(j) * dst < b; ++j) {
      const std::int64_t overlap =
          std::min(b, std::int64_t(j + 1) * dst) - std::max(a, std::int64_t(j) * dst);
      if (overlap > 0) weights[std::size_t(i)].emplace_back(j, overlap);
    }
  }
  return weights;
}

/// Box-resamples `channels` interleaved planes of (sh x sw) samples, row-major, to
/// (dh x dw x channels). Each result is the area mean times sw*sh, exactly (the caller divides,
/// rounding as it needs), so equal areas compare equal: a flat image has no "edges" made of
/// rounding noise. T is any integer type; the sums must fit in int64 (|sample| * sw * sh).
template <class T>
std::vector<std::int64_t> box_resample(const T* src, int sw, int sh, int channels, int dw, int dh) {
  const auto wx = box_weights(sw, dw);
  const auto wy = box_weights(sh, dh);
  const std::size_t c = std::size_t(channels);
  // Horizontal pass into (sh x dw) rows, then the vertical one.
  std::vector<std::int64_t> rows(std::size_t(sh) * std::size_t(dw) * c, 0);
  for (int y = 0; y < sh; ++y) {
    for (int x = 0; x < dw; ++x) {
      std::int64_t* out = &rows[(std::size_t(y) * std::size_t(dw) + std::size_t(x)) * c];
      for (const auto& [j, w] : wx[std::size_t(x)]) {
        const T* p = &src[(std::size_t(y) * std::size_t(sw) + std::size_t(j)) * c];
        for (std::size_t k = 0; k < c; ++k) out[k] += w * std::int64_t(p[k]);
      }
    }
  }
  std::vector<std::int64_t> out(std::size_t(dh) * std::size_t(dw) * c, 0);
  for (int y = 0; y < dh; ++y) {
    for (int x = 0; x < dw; ++x) {
      std::int64_t* o = &out[(std::size_t(y) * std::size_t(dw) + std::size_t(x)) * c];
      for (const auto& [j, w] : wy[std::size_t(y)]) {
        const std::int64_t* r = &rows[(std::size_t(j) * std::size_t(dw) + std::size_t(x)) * c];
        for (std::size_t k = 0; k < c; ++k) o[k] += w * r[k];
      }
    }
  }
  return out;
}

}  // namespace simreel::render::detail
