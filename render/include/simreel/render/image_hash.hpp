#pragma once
/// @file image_hash.hpp
/// 64-bit perceptual image hashes on luminance, compared by Hamming distance.

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
/// Number of differing bits.
int hamming(std::uint64_t a, std::uint64_t b);
/// 16 lowercase hex digits. `parse_hash` accepts the same (throws std::invalid_argument).
std::string hash_to_hex(std::uint64_t h);
std::uint64_t parse_hash(const std::string& hex);

}  // namespace simreel::render
