#pragma once
/// @file image_hash.hpp
/// 64-bit perceptual image hashes (two on luminance, one on colour), compared by Hamming distance.

#include <cstdint>
#include <string>

#include "simreel/render/image.hpp"

namespace simreel::render {

/// DCT pHash: luminance (Rec. 709) box-resampled to 32x32, 2-D DCT-II, the 8x8 lowest
/// frequencies (DC included) compared with their median -> 64 bits, row-major from (0,0).
/// Bit 63 (the most significant, first hex digit) is (0,0); rows are vertical frequencies.
/// Luminance is taken from the 8-bit (sRGB-encoded) values; the box resample is exact, so flat
/// areas hash deterministically. @throws std::invalid_argument for an empty image.
std::uint64_t phash(const Image& image);
/// dHash: luminance box-resampled to 9x8, bit = left pixel brighter than its right neighbour.
/// Bit 63 is row 0, column 0. Regions flat along x give 0 bits that noise can flip.
std::uint64_t dhash(const Image& image);
/// Colour layout hash, for what the luminance hashes cannot see (a hue change at equal
/// luminance, e.g. a changed colour ramp). The image is split into the opponent channels
/// red-green (R - G) and yellow-blue ((R + G)/2 - B) of the 8-bit values, box-averaged over a
/// 4x4 grid; each of the 32 cell means is quantised against fixed thresholds +-24/510 of the
/// channel's full range (about 5%) into three levels, thermometer-coded in two bits
/// (00 below -T, 10 within, 11 above), so Hamming distance counts level steps. Bits 63..32:
/// red-green cells row-major from the top-left, 2 bits each; bits 31..0: yellow-blue.
/// Absolute thresholds rather than a median make a uniform hue shift visible, at the price of
/// a flip when a cell mean sits at a threshold; averaging over a sixteenth of the image makes
/// pixel noise negligible there. Idea after colour-layout descriptors (MPEG-7 CLD).
/// @throws std::invalid_argument for an empty image.
std::uint64_t chash(const Image& image);
/// Number of differing bits.
int hamming(std::uint64_t a, std::uint64_t b);
/// 16 lowercase hex digits. `parse_hash` accepts the same (throws std::invalid_argument).
std::string hash_to_hex(std::uint64_t h);
std::uint64_t parse_hash(const std::string& hex);

}  // namespace simreel::render
