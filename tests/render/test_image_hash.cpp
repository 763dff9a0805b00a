// Perceptual hashes: stable under noise and small shifts, far apart for different pictures.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "simreel/render/image_hash.hpp"

namespace simreel::render {
namespace {

std::uint8_t clamp8(double v) { return std::uint8_t(std::clamp(std::lround(v), 0L, 255L)); }

/// A smooth synthetic "scene": a sky-to-ground gradient with a few soft blobs.
/// (Renders dominated by a sky flat along x, or symmetric left to right, make weaker test
/// images: their near-zero dHash differences and odd-frequency DCT terms flip under a
/// one-pixel shift. That is a property of the hashes, not of the renderer.)
Image scene(int w = 160, int h = 120, int shift = 0) {
  Image img(w, h);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      const double u = double(x - shift) / w;
      const double v = double(y) / h;
      // Gradients along both axes: dHash bits of a region flat along x are decided by noise.
      double r = 70 + 60 * v + 70 * u;
      double g = 120 + 50 * v - 40 * u;
      double b = 220 - 90 * v + 20 * u;
      const double blob1 = std::exp(-(std::pow(u - 0.3, 2) + std::pow(v - 0.6, 2)) / 0.01);
      const double blob2 = std::exp(-(std::pow(u - 0.72, 2) + std::pow(v - 0.35, 2)) / 0.02);
      r += 150 * blob1 - 40 * blob2;
      g += 60 * blob1 + 80 * blob2;
      b += -120 * blob1 + 20 * blob2;
      std::uint8_t* p = img.pixel(x, y);
      p[0] = clamp8(r);
      p[1] = clamp8(g);
      p[2] = clamp8(b);
      p[3] = 255;
    }
  }
  return img;
}

Image with_noise(Image img, int amplitude, unsigned seed) {
  unsigned state = seed;
  for (std::size_t i = 0; i < img.rgba.size(); ++i) {
    if (i % 4 == 3) continue;
    // Sum of two uniforms: a triangular, roughly gaussian, distribution in [-amp, amp].
    state = state * 1664525u + 1013904223u;
    const int a = int(state >> 24) % (amplitude + 1);
    state = state * 1664525u + 1013904223u;
    const int b = int(state >> 24) % (amplitude + 1);
    img.rgba[i] = clamp8(double(img.rgba[i]) + a - b);
  }
  return img;
}

Image checkerboard(int w = 160, int h = 120, int cell = 10) {
  Image img(w, h);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      const std::uint8_t v = ((x / cell + y / cell) % 2) != 0 ? 230 : 25;
      std::uint8_t* p = img.pixel(x, y);
      p[0] = p[1] = p[2] = v;
      p[3] = 255;
    }
  }
  return img;
}

Image mirrored(const Image& img) {
  Image out(img.width, img.height);
  for (int y = 0; y < img.height; ++y) {
    for (int x = 0; x < img.width; ++x) {
      std::copy_n(img.pixel(img.width - 1 - x, y), 4, out.pixel(x, y));
    }
  }
  return out;
}

TEST(RenderHash, IdenticalImagesHashEqual) {
  const Image a = scene();
  const Image b = scene();
  EXPECT_EQ(hamming(phash(a), phash(b)), 0);
  EXPECT_EQ(hamming(dhash(a), dhash(b)), 0);
}

TEST(RenderHash, KnownValues) {
  Image flat(40, 30);
  std::fill(flat.rgba.begin(), flat.rgba.end(), std::uint8_t(128));
  // Only the DC coefficient is above the median of an all-zero AC block.
  EXPECT_EQ(phash(flat), 0x8000000000000000ull);
  EXPECT_EQ(dhash(flat), 0ull);
  Image falling(90, 40);  // brighter on the left: every dHash comparison is true
  for (int y = 0; y < falling.height; ++y) {
    for (int x = 0; x < falling.width; ++x) {
      std::uint8_t* p = falling.pixel(x, y);
      p[0] = p[1] = p[2] = std::uint8_t(250 - 2 * x);
      p[3] = 255;
    }
  }
  EXPECT_EQ(dhash(falling), ~0ull);
}

TEST(RenderHash, SmallNoiseAndOnePixelShiftStayClose) {
  const Image a = scene();
  const Image shifted = scene(160, 120, 1);
  for (const unsigned seed : {1u, 2u, 3u}) {
    const Image noisy = with_noise(a, 4, seed);
    ASSERT_NE(noisy.rgba, a.rgba);
    EXPECT_LE(hamming(phash(a), phash(noisy)), 6) << seed;
    EXPECT_LE(hamming(dhash(a), dhash(noisy)), 6) << seed;
  }
  EXPECT_LE(hamming(phash(a), phash(shifted)), 6);
  EXPECT_LE(hamming(dhash(a), dhash(shifted)), 6);
}

TEST(RenderHash, DifferentImagesAreFarApart) {
  const Image a = scene();
  EXPECT_GE(hamming(phash(a), phash(checkerboard())), 20);
  EXPECT_GE(hamming(dhash(a), dhash(checkerboard())), 20);
  EXPECT_GE(hamming(phash(a), phash(mirrored(a))), 20);
  EXPECT_GE(hamming(dhash(a), dhash(mirrored(a))), 20);
}

TEST(RenderHash, WorksForImagesSmallerThanTheGrid) {
  const Image tiny = scene(7, 5);
  EXPECT_EQ(phash(tiny), phash(scene(7, 5)));
  EXPECT_THROW((void)phash(Image{}), std::invalid_argument);
}

TEST(RenderHash, HexRoundTrip) {
  for (const std::uint64_t h : {0ull, 1ull, 0x8000000000000000ull, 0x0123456789abcdefull, ~0ull}) {
    const std::string hex = hash_to_hex(h);
    EXPECT_EQ(hex.size(), 16u);
    EXPECT_EQ(parse_hash(hex), h) << hex;
  }
  EXPECT_EQ(hash_to_hex(0x0123456789abcdefull), "0123456789abcdef");
  EXPECT_EQ(hamming(0x0ull, 0xffull), 8);
}

TEST(RenderHash, ParseRejectsBadStrings) {
  for (const char* bad : {"", "0", "0123456789abcde", "0123456789abcdef0", "0x23456789abcdef",
                          "0123456789abcdeg", " 123456789abcdef", "0123456789abcde-"}) {
    EXPECT_THROW(parse_hash(bad), std::invalid_argument) << '"' << bad << '"';
  }
}

}  // namespace
}  // namespace simreel::render
