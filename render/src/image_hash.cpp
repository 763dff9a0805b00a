#include "simreel/render/image_hash.hpp"

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <numbers>
#include <stdexcept>
#include <utility>
#include <vector>

#include "box_resample.hpp"

namespace simreel::render {
namespace {

/// Rec. 709 luma of the 8-bit (gamma-encoded) values, scaled by 10000 so it is an exact
/// integer; (height x width), row-major.
std::vector<std::int64_t> luma(const Image& image) {
  if (image.width < 1 || image.height < 1 ||
      image.rgba.size() != std::size_t(image.width) * std::size_t(image.height) * 4) {
    throw std::invalid_argument("cannot hash an empty or malformed image");
  }
  std::vector<std::int64_t> y(std::size_t(image.width) * std::size_t(image.height));
  for (std::size_t i = 0; i < y.size(); ++i) {
    const std::uint8_t* p = &image.rgba[i * 4];
    y[i] = 2126 * std::int64_t(p[0]) + 7152 * std::int64_t(p[1]) + 722 * std::int64_t(p[2]);
  }
  return y;
}

}  // namespace

std::uint64_t phash(const Image& image) {
  constexpr int kN = 32;
  constexpr int kK = 8;
  const std::vector<std::int64_t> sums =
      detail::box_resample(luma(image).data(), image.width, image.height, 1, kN, kN);
  const double scale = 1.0 / (10000.0 * double(image.width) * double(image.height));
  std::vector<double> f(sums.size());
  for (std::size_t i = 0; i < f.size(); ++i) f[i] = double(sums[i]) * scale;

  // Orthonormal DCT-II basis, only the kK lowest frequencies are needed.
  std::array<std::array<double, kN>, kK> basis{};
  for (int u = 0; u < kK; ++u) {
    const double alpha = u == 0 ? std::sqrt(1.0 / kN) : std::sqrt(2.0 / kN);
    for (int x = 0; x < kN; ++x) {
      basis[std::size_t(u)][std::size_t(x)] =
          alpha * std::cos(std::numbers::pi * (2 * x + 1) * u / (2.0 * kN));
    }
  }
  // Rows first (horizontal frequency u), then columns (vertical frequency v).
  std::array<std::array<double, kK>, kN> rows{};
  for (int y = 0; y < kN; ++y) {
    for (int u = 0; u < kK; ++u) {
      double sum = 0.0;
      for (int x = 0; x < kN; ++x) sum += basis[std::size_t(u)][std::size_t(x)] * f[std::size_t(y) * kN + x];
      rows[std::size_t(y)][std::size_t(u)] = sum;
    }
  }
  std::array<double, kK * kK> coeffs{};
  for (int v = 0; v < kK; ++v) {
    for (int u = 0; u < kK; ++u) {
      double sum = 0.0;
      for (int y = 0; y < kN; ++y) sum += basis[std::size_t(v)][std::size_t(y)] * rows[std::size_t(y)][std::size_t(u)];
      // Snap to 1e-6 so coefficients that are zero in exact arithmetic are exactly zero here
      // and compare equal to a zero median, instead of by the sign of their rounding error.
      coeffs[std::size_t(v * kK + u)] = std::nearbyint(sum * 1e6) * 1e-6;
    }
  }
  std::array<double, kK * kK> sorted = coeffs;
  std::sort(sorted.begin(), sorted.end());
  const double median = 0.5 * (sorted[31] + sorted[32]);

  std::uint64_t h = 0;
  for (std::size_t k = 0; k < coeffs.size(); ++k) {
    if (coeffs[k] > median) h |= std::uint64_t{1} << (63 - k);
  }
  return h;
}

std::uint64_t dhash(const Image& image) {
  const std::vector<std::int64_t> g =
      detail::box_resample(luma(image).data(), image.width, image.height, 1, 9, 8);
  std::uint64_t h = 0;
  for (int y = 0; y < 8; ++y) {
    for (int x = 0; x < 8; ++x) {
      if (g[std::size_t(y) * 9 + x] > g[std::size_t(y) * 9 + x + 1]) {
        h |= std::uint64_t{1} << (63 - (y * 8 + x));
      }
    }
  }
  return h;
}

std::uint64_t chash(const Image& image) {
  if (image.width < 1 || image.height < 1 ||
      image.rgba.size() != std::size_t(image.width) * std::size_t(image.height) * 4) {
    throw std::invalid_argument("cannot hash an empty or malformed image");
  }
  // Opponent channels of the 8-bit values, kept as exact integers: rg = R - G in [-255, 255],
  // yb = R + G - 2B in [-510, 510] (twice the yellow-blue axis, so both share one scale).
  const std::size_t n = std::size_t(image.width) * std::size_t(image.height);
  std::vector<std::int64_t> rg(n);
  std::vector<std::int64_t> yb(n);
  for (std::size_t i = 0; i < n; ++i) {
    const std::uint8_t* p = &image.rgba[i * 4];
    rg[i] = 2 * (std::int64_t(p[0]) - std::int64_t(p[1]));
    yb[i] = std::int64_t(p[0]) + std::int64_t(p[1]) - 2 * std::int64_t(p[2]);
  }
  constexpr int kGrid = 4;
  const std::vector<std::int64_t> mean_rg =
      detail::box_resample(rg.data(), image.width, image.height, 1, kGrid, kGrid);
  const std::vector<std::int64_t> mean_yb =
      detail::box_resample(yb.data(), image.width, image.height, 1, kGrid, kGrid);
  // Each sum is the cell mean times width*height, on a scale where 510 is full saturation.
  // Levels: below -T, within +-T (grey-ish), above +T, thermometer-coded in two bits so that
  // the Hamming distance counts level steps; T = 24/510 (about 5% of the axis).
  const std::int64_t area = std::int64_t(image.width) * std::int64_t(image.height);
  const std::int64_t threshold = 24 * area;
  std::uint64_t h = 0;
  int bit = 63;
  for (const auto* plane : {&mean_rg, &mean_yb}) {
    for (const std::int64_t v : *plane) {
      if (v > -threshold) h |= std::uint64_t{1} << bit;
      --bit;
      if (v > threshold) h |= std::uint64_t{1} << bit;
      --bit;
    }
  }
  return h;
}

int hamming(std::uint64_t a, std::uint64_t b) { return std::popcount(a ^ b); }

std::string hash_to_hex(std::uint64_t h) {
  static constexpr char kDigits[] = "0123456789abcdef";
  std::string s(16, '0');
  for (int i = 15; i >= 0; --i, h >>= 4) s[std::size_t(i)] = kDigits[h & 0xf];
  return s;
}

std::uint64_t parse_hash(const std::string& hex) {
  if (hex.size() != 16) {
    throw std::invalid_argument("image hash \"" + hex + "\" is not 16 hex digits");
  }
  std::uint64_t h = 0;
  for (const char c : hex) {
    int d = 0;
    if (c >= '0' && c <= '9') {
      d = c - '0';
    } else if (c >= 'a' && c <= 'f') {
      d = c - 'a' + 10;
    } else if (c >= 'A' && c <= 'F') {
      d = c - 'A' + 10;
    } else {
      throw std::invalid_argument("image hash \"" + hex + "\" is not 16 hex digits");
    }
    h = (h << 4) | std::uint64_t(d);
  }
  return h;
}

}  // namespace simreel::render
