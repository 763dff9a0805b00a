#include "simreel/render/image.hpp"

#include <stb_image.h>
#include <libdeflate.h>

#include <algorithm>
#include <cerrno>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <new>
#include <stdexcept>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "box_resample.hpp"
#include "simreel/render/atomic_file.hpp"

namespace simreel::render {

namespace fs = std::filesystem;

namespace {

/// The eight bytes every PNG file begins with (PNG specification §5.2).
constexpr std::string_view kPngSignature("\x89PNG\r\n\x1a\n", 8);

/// The Paeth predictor (PNG specification §9.4): of left, above and upper-left, the one closest
/// to left + above - upper-left.
std::uint8_t paeth(int a, int b, int c) {
  const int p = a + b - c;
  const int pa = std::abs(p - a), pb = std::abs(p - b), pc = std::abs(p - c);
  return std::uint8_t(pa <= pb && pa <= pc ? a : pb <= pc ? b : c);
}

/// Row filter `type` (0 None, 1 Sub, 2 Up, 3 Average, 4 Paeth; PNG specification §9.2) of one
/// row of `n` bytes with `bpp` bytes per pixel into `out`; `prev` is the row above (zeros for
/// the first row).
void filter_row(int type, const std::uint8_t* row, const std::uint8_t* prev, std::size_t n, std::size_t bpp,
                std::uint8_t* out) {
  for (std::size_t i = 0; i < n; ++i) {
    const int a = i >= bpp ? row[i - bpp] : 0;
    const int b = prev[i];
    const int c = i >= bpp ? prev[i - bpp] : 0;
    int predictor = 0;
    switch (type) {
      case 1: predictor = a; break;
      case 2: predictor = b; break;
      case 3: predictor = (a + b) / 2; break;
      case 4: predictor = paeth(a, b, c); break;
      default: break;
    }
    out[i] = std::uint8_t(row[i] - predictor);
  }
}

/// The sum of the filtered bytes read as signed: libpng's heuristic for the filter that
/// deflates best.
std::uint64_t filtered_cost(const std::uint8_t* bytes, std::size_t n) {
  std::uint64_t sum = 0;
  for (std::size_t i = 0; i < n; ++i) sum += std::uint64_t(std::abs(int(std::int8_t(bytes[i]))));
  return sum;
}

void put_u32(std::string& out, std::uint32_t v) {
  const char b[4] = {char(v >> 24), char(v >> 16), char(v >> 8), char(v)};
  out.append(b, 4);
}

/// Appends one chunk: length, type, data, CRC-32 of type and data (PNG specification §5.3).
void put_chunk(std::string& out, const char* type, const std::uint8_t* data, std::size_t n) {
  put_u32(out, std::uint32_t(n));
  const std::size_t type_at = out.size();
  out.append(type, 4);
  if (n > 0) out.append(reinterpret_cast<const char*>(data), n);
  put_u32(out, libdeflate_crc32(0, out.data() + type_at, n + 4));
}

/// The whole PNG file of `image` at zlib-like `level` (0-9). Below 6 every row takes the Up
/// filter; from 6 each row takes the filter whose output has the smallest sum of magnitudes (as
/// libpng does). An opaque image is written as RGB: a quarter less to filter and deflate.
/// The IDAT stream is compressed by libdeflate, two to three times faster than zlib at the
/// same level and a fifth smaller (1280x720 demo frames).
std::string encode_png(const Image& image, int level) {
  const std::size_t w = std::size_t(image.width), h = std::size_t(image.height);
  const std::uint8_t* rgba = image.rgba.data();
  std::uint8_t alpha = 255;
  for (std::size_t i = 3; i < image.rgba.size(); i += 4) alpha &= rgba[i];  // no early exit: vectorises
  const bool rgb = alpha == 255;
  const std::size_t bpp = rgb ? 3 : 4;
  const std::size_t stride = w * bpp;
  // The rows as stored (RGB drops every fourth byte), then each filtered behind its filter byte.
  std::vector<std::uint8_t> packed(rgb ? stride * h : 0);
  for (std::size_t p = 0; p < packed.size() / 3; ++p) std::memcpy(&packed[3 * p], rgba + 4 * p, 3);
  const std::uint8_t* rows = rgb ? packed.data() : rgba;
  std::vector<std::uint8_t> filtered((stride + 1) * h);
  const std::vector<std::uint8_t> zeros(stride, 0);
  // From level 6 each filter is tried into `trial`; the best so far is kept in `best_row`.
  std::vector<std::uint8_t> trial(level >= 6 ? stride : 0), best_row(trial.size());
  for (std::size_t y = 0; y < h; ++y) {
    const std::uint8_t* row = &rows[y * stride];
    const std::uint8_t* prev = y > 0 ? row - stride : zeros.data();
    std::uint8_t* out = &filtered[y * (stride + 1)];
    if (level < 6) {
      out[0] = 2;
      filter_row(2, row, prev, stride, bpp, out + 1);
      continue;
    }
    std::uint64_t best_cost = ~std::uint64_t{0};
    for (int type = 0; type < 5; ++type) {
      filter_row(type, row, prev, stride, bpp, trial.data());
      const std::uint64_t cost = filtered_cost(trial.data(), stride);
      if (cost < best_cost) {
        best_cost = cost;
        out[0] = std::uint8_t(type);
        trial.swap(best_row);
      }
    }
    std::memcpy(out + 1, best_row.data(), stride);
  }
  libdeflate_compressor* compressor = libdeflate_alloc_compressor(std::clamp(level, 0, 9));
  if (compressor == nullptr) throw std::bad_alloc();
  std::vector<std::uint8_t> zdata(libdeflate_zlib_compress_bound(compressor, filtered.size()));
  const std::size_t zsize =
      libdeflate_zlib_compress(compressor, filtered.data(), filtered.size(), zdata.data(), zdata.size());
  libdeflate_free_compressor(compressor);
  if (zsize == 0) throw std::runtime_error("PNG: the compressed rows did not fit their bound");

  std::string png(kPngSignature);
  std::uint8_t ihdr[13] = {};
  for (int k = 0; k < 4; ++k) {
    ihdr[k] = std::uint8_t(std::uint32_t(w) >> (24 - 8 * k));
    ihdr[4 + k] = std::uint8_t(std::uint32_t(h) >> (24 - 8 * k));
  }
  ihdr[8] = 8;               // bits per channel
  ihdr[9] = rgb ? 2 : 6;     // colour type: RGB or RGBA; compression, filter, interlace 0
  put_chunk(png, "IHDR", ihdr, sizeof ihdr);
  constexpr std::size_t kIdatBytes = std::size_t{1} << 20;  // far below the 2^31 - 1 a chunk may hold
  for (std::size_t at = 0; at < zsize; at += kIdatBytes) {
    put_chunk(png, "IDAT", zdata.data() + at, std::min(kIdatBytes, zsize - at));
  }
  put_chunk(png, "IEND", nullptr, 0);
  return png;
}

/// The image format a file's first bytes name, by the signatures stb_image tests; "" for none
/// (TGA has no signature).
std::string format_by_signature(const std::string& head) {
  const auto starts = [&](std::string_view magic) { return head.compare(0, magic.size(), magic) == 0; };
  if (starts(kPngSignature)) return "PNG";
  if (starts("\xff\xd8")) return "JPEG";
  if (starts("GIF8")) return "GIF";
  if (starts("BM")) return "BMP";
  if (starts("8BPS")) return "PSD";
  if (starts("#?RADIANCE") || starts("#?RGBE")) return "HDR";
  if (starts("P5") || starts("P6")) return "PNM";
  return "";
}

/// Whether a PNG file ends before its IEND chunk: inside a chunk, or between chunks (PNG
/// specification §5.3: each chunk is a 4-byte length, a 4-byte type, the data and a 4-byte CRC).
/// Only the lengths are read, by seeking past each chunk's data.
bool png_cut_short(const fs::path& path) {
  std::error_code ec;
  const std::uintmax_t size = fs::file_size(path, ec);
  if (ec) return false;
  std::FILE* f = std::fopen(path.c_str(), "rb");
  if (f == nullptr) return false;
  std::uintmax_t at = kPngSignature.size();
  bool cut = true;
  while (at + 8 <= size) {
    unsigned char head[8];
    if (std::fseek(f, long(at), SEEK_SET) != 0 || std::fread(head, 1, 8, f) != 8) break;
    const std::uintmax_t len = std::uintmax_t(head[0]) << 24 | std::uintmax_t(head[1]) << 16 |
                               std::uintmax_t(head[2]) << 8 | std::uintmax_t(head[3]);
    at += 12 + len;
    if (at > size) break;
    if (std::memcmp(head + 4, "IEND", 4) == 0) {
      cut = false;
      break;
    }
  }
  std::fclose(f);
  return cut;
}

/// What a `format` file that stb_image refused with failure `code` is, in words: a PNG whose
/// chunks run past its end (`cut_short`) is named as cut short without stb_image's code, which
/// for a file cut at or near a chunk's start is empty or a fragment of the chunk's type ("IDA");
/// otherwise its terse codes for a file that ends early are named as such.
std::string undecodable(const std::string& format, const char* code, bool cut_short) {
  if (cut_short) return "a " + format + " file cut short: its data ends early";
  const std::string c = code != nullptr && *code != '\0' ? code : "no reason given";
  const bool cut = c == "outofdata" || c == "bad file" || c == "unexpected end" || c == "no IDAT" ||
                   c == "not enough pixels";
  return "a " + format + (cut ? " file cut short: its data ends early" : " file that cannot be decoded") +
         " (stb_image: " + c + ")";
}

/// The width and height a PNG's IHDR chunk declares (PNG specification §11.2.2), if `head`
/// holds it: stb_image refuses a PNG of more than 2^30 bytes of pixels before it reports a size.
bool png_header_size(const std::string& head, std::uint32_t& w, std::uint32_t& h) {
  if (head.size() < 24 || head.compare(12, 4, "IHDR") != 0) return false;
  const auto be32 = [&](std::size_t at) {
    std::uint32_t v = 0;
    for (std::size_t k = 0; k < 4; ++k) v = (v << 8) | std::uint8_t(head[at + k]);
    return v;
  };
  w = be32(16);
  h = be32(20);
  return true;
}

}  // namespace

void write_png(const fs::path& path, const Image& image, int compression) {
  if (image.width < 1 || image.height < 1 ||
      image.rgba.size() != std::size_t(image.width) * std::size_t(image.height) * 4) {
    throw IoError("cannot write " + path.string() + ": image is empty or its size does not match");
  }
  const std::string png = encode_png(image, std::clamp(compression, 0, 9));
  AtomicFile file(path);  // a half-written PNG never appears under the final name
  file.write(png);        // throws IoError naming the path; the temporary is discarded
  file.commit();
}

Image read_image(const fs::path& path) {
  const std::string what = "cannot read image " + path.string() + ": ";
  std::error_code ec;
  const auto status = fs::status(path, ec);
  if (!fs::exists(status)) throw IoError(what + "no such file");
  // A FIFO would block the read (a texture named /dev/stdin), a device might never end.
  if (!fs::is_regular_file(status)) throw IoError(what + "not a regular file (a directory, device or FIFO)");
  std::string head(32, '\0');
  {
    std::FILE* f = std::fopen(path.c_str(), "rb");
    if (f == nullptr) throw IoError(what + "cannot open it (" + std::strerror(errno) + ")");
    head.resize(std::fread(head.data(), 1, head.size(), f));
    std::fclose(f);
  }
  const std::string format = format_by_signature(head);
  const auto size_error = [&](long long w, long long h) {
    return IoError(what + std::to_string(w) + " x " + std::to_string(h) + " pixels, expected 1 to " +
                   std::to_string(kMaxImageSide) + " on each side");
  };
  // stbi_info() tries every format in turn and leaves the last one's reason ("unknown image
  // type" for a PNG it refused), stbi_load() that of the format whose signature matched: the
  // format is named from the signature, and only stbi_load()'s reason is passed on.
  const auto decode_error = [&](bool loading) {
    if (format.empty())
      return IoError(what + "not an image format simreel reads (PNG, JPEG, BMP, GIF, TGA, PSD, HDR, PNM)");
    return IoError(what + (loading ? undecodable(format, stbi_failure_reason(), format == "PNG" && png_cut_short(path))
                                   : "a " + format + " file whose header is cut short or corrupt"));
  };
  std::uint32_t png_w = 0, png_h = 0;
  if (format == "PNG" && png_header_size(head, png_w, png_h) &&
      (png_w < 1 || png_h < 1 || png_w > std::uint32_t(kMaxImageSide) || png_h > std::uint32_t(kMaxImageSide)))
    throw size_error(png_w, png_h);
  int w = 0;
  int h = 0;
  int channels = 0;
  // The size from the header first: a file can declare a size whose pixels take gigabytes.
  if (stbi_info(path.c_str(), &w, &h, &channels) == 0) throw decode_error(false);
  if (w < 1 || h < 1 || w > kMaxImageSide || h > kMaxImageSide) throw size_error(w, h);
  unsigned char* data = stbi_load(path.c_str(), &w, &h, &channels, 4);
  if (data == nullptr) throw decode_error(true);
  if (w < 1 || h < 1 || w > kMaxImageSide || h > kMaxImageSide) {  // as the header said
    stbi_image_free(data);
    throw size_error(w, h);
  }
  Image image(w, h);
  std::memcpy(image.rgba.data(), data, image.rgba.size());
  stbi_image_free(data);
  return image;
}

Image resize_box(const Image& image, int width, int height) {
  if (image.width < 1 || image.height < 1 || width < 1 || height < 1 ||
      image.rgba.size() != std::size_t(image.width) * std::size_t(image.height) * 4) {
    throw std::invalid_argument("resize_box: empty image or target size");
  }
  // Exact area sums (box_resample.hpp, as for the hashes), rounded to nearest once.
  const std::vector<std::int64_t> sums =
      detail::box_resample(image.rgba.data(), image.width, image.height, 4, width, height);
  Image result(width, height);
  const std::int64_t area = std::int64_t(image.width) * std::int64_t(image.height);
  for (std::size_t i = 0; i < sums.size(); ++i) {
    result.rgba[i] = std::uint8_t((sums[i] + area / 2) / area);
  }
  return result;
}

void blit(Image& dst, const Image& src, int x0, int y0) {
  for (int y = std::max(0, -y0); y < src.height && y0 + y < dst.height; ++y) {
    const int x_begin = std::max(0, -x0);
    const int x_end = std::min(src.width, dst.width - x0);
    if (x_end <= x_begin) return;
    std::memcpy(dst.pixel(x0 + x_begin, y0 + y), src.pixel(x_begin, y),
                std::size_t(x_end - x_begin) * 4);
  }
}

}  // namespace simreel::render
