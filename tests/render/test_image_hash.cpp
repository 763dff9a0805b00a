// Perceptual hashes: stable under noise and small shifts, far apart for different pictures.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <stdexcept>
#include <vector>

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

/// JPEG's lossy steps without the entropy coding: YCbCr (JFIF), chroma averaged over 2x2
/// (4:2:0), 8x8 block DCT of every plane quantised with the JPEG Annex K tables at quality 75.
Image jpeg_like(const Image& img) {
  static constexpr std::array<int, 64> kLuma = {16, 11, 10, 16, 24,  40,  51,  61,  12, 12, 14, 19, 26,  58,  60,  55,
                                                14, 13, 16, 24, 40,  57,  69,  56,  14, 17, 22, 29, 51,  87,  80,  62,
                                                18, 22, 37, 56, 68,  109, 103, 77,  24, 35, 55, 64, 81,  104, 113, 92,
                                                49, 64, 78, 87, 103, 121, 120, 101, 72, 92, 95, 98, 112, 100, 103, 99};
  static constexpr std::array<int, 64> kChroma = {17, 18, 24, 47, 99, 99, 99, 99, 18, 21, 26, 66, 99, 99, 99, 99,
                                                  24, 26, 56, 99, 99, 99, 99, 99, 47, 66, 99, 99, 99, 99, 99, 99,
                                                  99, 99, 99, 99, 99, 99, 99, 99, 99, 99, 99, 99, 99, 99, 99, 99,
                                                  99, 99, 99, 99, 99, 99, 99, 99, 99, 99, 99, 99, 99, 99, 99, 99};
  const double q75 = 0.5;  // libjpeg scaling: quality 75 -> tables x 50%
  const int w = img.width, h = img.height;
  std::vector<double> plane[3];
  for (auto& p : plane) p.assign(std::size_t(w) * h, 0.0);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      // Chroma from the 2x2 block mean (4:2:0), luma per pixel.
      double cb = 0, cr = 0;
      int n = 0;
      for (int dy = 0; dy < 2; ++dy) {
        for (int dx = 0; dx < 2; ++dx) {
          const int xx = std::min(w - 1, (x & ~1) + dx), yy = std::min(h - 1, (y & ~1) + dy);
          const std::uint8_t* q = img.pixel(xx, yy);
          cb += -0.168736 * q[0] - 0.331264 * q[1] + 0.5 * q[2];
          cr += 0.5 * q[0] - 0.418688 * q[1] - 0.081312 * q[2];
          ++n;
        }
      }
      const std::uint8_t* p = img.pixel(x, y);
      plane[0][std::size_t(y) * w + x] = 0.299 * p[0] + 0.587 * p[1] + 0.114 * p[2] - 128;
      plane[1][std::size_t(y) * w + x] = cb / n;
      plane[2][std::size_t(y) * w + x] = cr / n;
    }
  }
  auto c = [](int k) { return k == 0 ? std::sqrt(0.125) : 0.5; };
  for (int ch = 0; ch < 3; ++ch) {
    const auto& table = ch == 0 ? kLuma : kChroma;
    for (int by = 0; by + 8 <= h; by += 8) {
      for (int bx = 0; bx + 8 <= w; bx += 8) {
        double coef[64];
        for (int v = 0; v < 8; ++v) {
          for (int u = 0; u < 8; ++u) {
            double sum = 0;
            for (int y = 0; y < 8; ++y)
              for (int x = 0; x < 8; ++x)
                sum += plane[ch][std::size_t(by + y) * w + bx + x] *
                       std::cos((2 * x + 1) * u * std::numbers::pi / 16) * std::cos((2 * y + 1) * v * std::numbers::pi / 16);
            const double step = std::max(1.0, table[std::size_t(v * 8 + u)] * q75);
            coef[v * 8 + u] = std::round(c(u) * c(v) * sum / step) * step;
          }
        }
        for (int y = 0; y < 8; ++y) {
          for (int x = 0; x < 8; ++x) {
            double sum = 0;
            for (int v = 0; v < 8; ++v)
              for (int u = 0; u < 8; ++u)
                sum += c(u) * c(v) * coef[v * 8 + u] * std::cos((2 * x + 1) * u * std::numbers::pi / 16) *
                       std::cos((2 * y + 1) * v * std::numbers::pi / 16);
            plane[ch][std::size_t(by + y) * w + bx + x] = sum;
          }
        }
      }
    }
  }
  Image out(w, h);
  for (int i = 0; i < w * h; ++i) {
    const double Y = plane[0][std::size_t(i)] + 128, cb = plane[1][std::size_t(i)], cr = plane[2][std::size_t(i)];
    std::uint8_t* p = &out.rgba[std::size_t(i) * 4];
    p[0] = clamp8(Y + 1.402 * cr);
    p[1] = clamp8(Y - 0.344136 * cb - 0.714136 * cr);
    p[2] = clamp8(Y + 1.772 * cb);
    p[3] = 255;
  }
  return out;
}

/// A colour ramp from left to right over the luminance of scene() (grey, with its blobs: a
/// smooth gradient alone leaves pHash's AC terms near zero and their bits to rounding), each
/// pixel's Rec. 709 luma kept equal whatever `hue_sign`: the chroma added,
/// s * (0.7152, -0.2126 + 0.0722, -0.7152), has zero luma. hue_sign +1 gives a red/yellow
/// ramp, -1 a cyan/blue one.
Image iso_luminant_ramp(int hue_sign, int w = 160, int h = 120) {
  const Image base = scene(w, h);
  Image img(w, h);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      const std::uint8_t* b = base.pixel(x, y);
      const double grey = 20 + 0.8 * (0.2126 * b[0] + 0.7152 * b[1] + 0.0722 * b[2]);
      const double s = hue_sign * 80.0 * x / w;  // the ramp: saturation grows left to right
      std::uint8_t* p = img.pixel(x, y);
      p[0] = clamp8(grey + s * 0.7152);
      p[1] = clamp8(grey - s * 0.2126 + s * 0.0722);
      p[2] = clamp8(grey - s * 0.7152);
      p[3] = 255;
    }
  }
  return img;
}

/// scene() with its bright blob moved by (dx, dy) of the image size.
Image moved_blob(double dx, double dy, int w = 160, int h = 120) {
  Image img = scene(w, h);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      const double u = double(x) / w, v = double(y) / h;
      const double old_blob = std::exp(-(std::pow(u - 0.3, 2) + std::pow(v - 0.6, 2)) / 0.01);
      const double new_blob = std::exp(-(std::pow(u - 0.3 - dx, 2) + std::pow(v - 0.6 - dy, 2)) / 0.01);
      std::uint8_t* p = img.pixel(x, y);
      p[0] = clamp8(p[0] + 150 * (new_blob - old_blob));
      p[1] = clamp8(p[1] + 60 * (new_blob - old_blob));
      p[2] = clamp8(p[2] - 120 * (new_blob - old_blob));
    }
  }
  return img;
}

TEST(RenderHash, IdenticalImagesHashEqual) {
  const Image a = scene();
  const Image b = scene();
  EXPECT_EQ(hamming(phash(a), phash(b)), 0);
  EXPECT_EQ(hamming(dhash(a), dhash(b)), 0);
  EXPECT_EQ(hamming(chash(a), chash(b)), 0);
}

TEST(RenderHash, ColourHashKnownValues) {
  Image grey(40, 30);
  std::fill(grey.rgba.begin(), grey.rgba.end(), std::uint8_t(128));
  // Every cell of both channels within +-T: thermometer code 10 in all 32 places.
  EXPECT_EQ(chash(grey), 0xaaaaaaaaaaaaaaaaull);
  Image blue(40, 30);
  for (int i = 0; i < 40 * 30; ++i) {
    blue.rgba[std::size_t(i) * 4 + 0] = 20;
    blue.rgba[std::size_t(i) * 4 + 1] = 20;
    blue.rgba[std::size_t(i) * 4 + 2] = 220;
    blue.rgba[std::size_t(i) * 4 + 3] = 255;
  }
  // R = G: red-green neutral (10...); strongly blue: yellow-blue below -T (00...).
  EXPECT_EQ(chash(blue), 0xaaaaaaaa00000000ull);
  EXPECT_THROW((void)chash(Image{}), std::invalid_argument);
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
  EXPECT_LE(hamming(chash(a), chash(with_noise(a, 4, 1))), 2);
  EXPECT_LE(hamming(chash(a), chash(shifted)), 2);
}

TEST(RenderHash, JpegLikeQuantisationStaysClose) {
  const Image a = scene();
  const Image j = jpeg_like(a);
  int changed = 0;
  for (std::size_t i = 0; i < a.rgba.size(); ++i) changed += a.rgba[i] != j.rgba[i] ? 1 : 0;
  ASSERT_GT(changed, int(a.rgba.size() / 8)) << "the quantisation must actually change the image";
  EXPECT_LE(hamming(phash(a), phash(j)), 6);
  EXPECT_LE(hamming(dhash(a), dhash(j)), 6);
  EXPECT_LE(hamming(chash(a), chash(j)), 2);
}

TEST(RenderHash, MovedObjectIsFarApart) {
  const Image a = scene();
  const Image moved = moved_blob(0.35, -0.3);
  EXPECT_GE(hamming(phash(a), phash(moved)), 12);
  // dHash bits compare neighbouring cells, so only those the blob leaves and enters change.
  EXPECT_GE(hamming(dhash(a), dhash(moved)), 8);
}

TEST(RenderHash, ChangedColourRampAtEqualLuminanceIsSeenOnlyByTheColourHash) {
  const Image warm = iso_luminant_ramp(+1);
  const Image cold = iso_luminant_ramp(-1);
  // Same luminance up to 8-bit rounding: the luminance hashes cannot tell them apart...
  EXPECT_LE(hamming(phash(warm), phash(cold)), 2);
  EXPECT_LE(hamming(dhash(warm), dhash(cold)), 2);
  // ...the colour hash sees the ramp reversed in both opponent channels.
  EXPECT_GE(hamming(chash(warm), chash(cold)), 20);
}

TEST(RenderHash, DifferentImagesAreFarApart) {
  const Image a = scene();
  EXPECT_GE(hamming(phash(a), phash(checkerboard())), 20);
  EXPECT_GE(hamming(dhash(a), dhash(checkerboard())), 20);
  EXPECT_GE(hamming(phash(a), phash(mirrored(a))), 20);
  EXPECT_GE(hamming(dhash(a), dhash(mirrored(a))), 20);
  EXPECT_GE(hamming(chash(a), chash(checkerboard())), 16);
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
