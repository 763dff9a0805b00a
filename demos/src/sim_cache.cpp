#include "sim_cache.hpp"
#include "simreel/sim/ranges.hpp"

#include <cinttypes>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iterator>
#include <limits>
#include <sstream>

#include <nlohmann/json.hpp>

#include "json_reader.hpp"
#include "run_options.hpp"
#include "simreel/render/atomic_file.hpp"
#include "simreel/sim/world.hpp"

namespace simreel::app {

namespace fs = std::filesystem;

namespace {

constexpr char kFrameMagic[8] = {'S', 'R', 'C', 'A', 'C', 'H', 'E', '1'};
/// magic, format (u32), reserved (u32), frame (u64), key (u64), payload bytes (u64), payload FNV (u64)
constexpr std::size_t kHeaderBytes = 8 + 4 + 4 + 8 + 8 + 8 + 8;

struct Fnv {
  std::uint64_t h = 0xcbf29ce484222325ULL;
  void bytes(const void* p, std::size_t n) {
    const auto* b = static_cast<const unsigned char*>(p);
    for (std::size_t i = 0; i < n; ++i) h = (h ^ b[i]) * 0x100000001b3ULL;
  }
  void text(const std::string& s) {
    const std::uint64_t n = s.size();
    bytes(&n, sizeof n);
    bytes(s.data(), s.size());
  }
  template <class T>
  void value(const T& v) {
    bytes(&v, sizeof v);
  }
};

std::string hex16(std::uint64_t v) {
  char buf[17];
  std::snprintf(buf, sizeof buf, "%016" PRIx64, v);
  return buf;
}

template <class T>
void put(std::string& s, const T& v) {
  s.append(reinterpret_cast<const char*>(&v), sizeof v);
}
template <class T>
T get(const char* p) {
  T v;
  std::memcpy(&v, p, sizeof v);
  return v;
}

std::string read_all(const fs::path& p, bool& ok) {
  std::ifstream in(p, std::ios::binary);
  ok = bool(in);
  if (!ok) return {};
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

/// The header check shared by read_frame and check_frame_header; `size` the file's size.
std::string check_header(const fs::path& p, const char* h, std::uint64_t size, int frame, std::uint64_t key) {
  const std::string f = p.string();
  if (size < kHeaderBytes)
    return f + ": truncated (" + std::to_string(size) + " bytes, shorter than the " +
           std::to_string(kHeaderBytes) + "-byte header)";
  if (std::memcmp(h, kFrameMagic, 8) != 0) return f + ": not a simreel cache frame (bad magic)";
  if (const auto v = get<std::uint32_t>(h + 8); v != std::uint32_t(kCacheFormat))
    return f + ": cache format " + std::to_string(v) + ", this build reads " + std::to_string(kCacheFormat);
  if (const auto fr = get<std::uint64_t>(h + 16); fr != std::uint64_t(frame))
    return f + ": holds frame " + std::to_string(fr) + ", expected frame " + std::to_string(frame);
  if (const auto k = get<std::uint64_t>(h + 24); k != key)
    return f + ": baked with another scene, overrides, seed, fps or build (key " + hex16(k) +
           ", the manifest's " + hex16(key) + ")";
  const auto n = get<std::uint64_t>(h + 32);
  if (size != kHeaderBytes + n)
    return f + ": truncated or padded (" + std::to_string(size) + " bytes, the header says " +
           std::to_string(kHeaderBytes + n) + ")";
  return {};
}

}  // namespace

std::uint64_t CacheIdentity::key() const {
  Fnv f;
  f.text(scene_hash);
  f.value(std::uint64_t(overrides.size()));
  for (const auto& o : overrides) f.text(o);
  f.value(seed);
  f.value(fps);
  f.text(simreel_version);
  f.value(state_format);
  return f.h;
}

std::string file_hash(const fs::path& file) {
  bool ok = false;
  const std::string bytes = read_all(file, ok);
  if (!ok) throw SceneError(file.string() + ": cannot read the scene file");
  Fnv f;
  f.bytes(bytes.data(), bytes.size());
  return hex16(f.h);
}

CacheIdentity cache_identity(const Scene& scene, const fs::path& scene_file, const std::vector<std::string>& overrides) {
  CacheIdentity id;
  id.scene_hash = file_hash(scene_file);
  id.overrides = overrides;
  id.seed = scene.seed;
  id.fps = scene.fps;
  id.simreel_version = SIMREEL_VERSION;
  id.state_format = sim::World::state_format();
  return id;
}

fs::path manifest_path(const fs::path& dir) { return dir / "manifest.json"; }

fs::path frame_path(const fs::path& dir, int frame) {
  char name[32];
  std::snprintf(name, sizeof name, "frame_%05d.state", frame);
  return dir / "state" / name;
}

fs::path ply_dir(const fs::path& dir) { return dir / "ply"; }

void write_manifest(const fs::path& dir, const CacheManifest& m) {
  nlohmann::ordered_json j = nlohmann::ordered_json::object();
  j["simreel_cache"] = kCacheFormat;
  j["simreel_version"] = m.id.simreel_version;
  j["state_format"] = m.id.state_format;
  j["scene"] = m.scene;
  j["scene_hash"] = m.id.scene_hash;
  j["overrides"] = m.id.overrides;
  j["seed"] = m.id.seed;
  j["fps"] = m.id.fps;
  j["frames"] = m.frames;
  j["complete"] = m.complete;
  j["ply"] = m.ply;
  j["key"] = hex16(m.id.key());
  render::write_file_atomic(manifest_path(dir), j.dump(2) + "\n");
}

CacheManifest read_manifest(const fs::path& dir) {
  const fs::path p = manifest_path(dir);
  std::error_code ec;
  if (!fs::exists(fs::symlink_status(p, ec)))
    throw SceneError(p.string() + ": no cache manifest (expected a folder written by `simreel bake`)");
  // A regular file of bounded size (a FIFO here blocked the read forever), parsed with line and
  // column in its errors; each key checked for its type and range like a scene's, so a hand-edited
  // "frames": 1e12 or "seed": -1 is named, not cast into a wrong number.
  const nlohmann::json j = parse_json_file(p, "cache manifest");
  const std::string file = p.string();
  if (!j.is_object()) throw SceneError(file + ": expected a JSON object, found " + describe(j));
  std::vector<std::string> errors;
  ObjectReader r(j, "", file, errors);
  for (const char* key : {"simreel_cache", "simreel_version", "state_format", "scene", "scene_hash", "overrides",
                          "seed", "fps", "frames", "complete", "ply"})
    if (!r.has(key)) r.error_at(std::string("/") + key, "missing");
  if (!errors.empty()) throw SceneError(errors);
  if (const long long f = r.integer("simreel_cache", kCacheFormat, 0, std::numeric_limits<int>::max());
      errors.empty() && f != kCacheFormat)
    throw SceneError(file + ": /simreel_cache: format " + std::to_string(f) + ", this build reads " +
                     std::to_string(kCacheFormat));
  CacheManifest m;
  m.id.simreel_version = r.string("simreel_version", "");
  m.id.state_format = std::uint32_t(r.integer("state_format", 0, 0, std::numeric_limits<std::uint32_t>::max()));
  m.scene = r.string("scene", "");
  m.id.scene_hash = r.string("scene_hash", "");
  if (const nlohmann::json* o = r.get("overrides"); o != nullptr && !o->is_array()) {
    r.error("overrides", "an array of \"POINTER=VALUE\" strings", *o);
  } else if (o != nullptr) {
    for (std::size_t i = 0; i < o->size(); ++i) {
      if ((*o)[i].is_string())
        m.id.overrides.push_back((*o)[i].get<std::string>());
      else
        r.error_at("/overrides/" + std::to_string(i), "expected a \"POINTER=VALUE\" string, found " + describe((*o)[i]));
    }
  }
  m.id.seed = std::uint64_t(r.integer("seed", 0, 0, std::numeric_limits<long long>::max()));
  m.id.fps = r.number("fps", 30.0, 0.0, 1000.0, true);
  m.frames = int(r.integer("frames", 1, 1, kMaxFrames));
  m.complete = r.boolean("complete", false);
  m.ply = r.boolean("ply", false);
  if (!errors.empty()) throw SceneError(errors);
  return m;
}

std::string identity_difference(const CacheIdentity& found, const CacheIdentity& wanted) {
  std::vector<std::string> d;
  if (found.scene_hash != wanted.scene_hash)
    d.push_back("scene hash " + found.scene_hash + " differs from the scene file's " + wanted.scene_hash);
  if (found.overrides != wanted.overrides) {
    auto list = [](const std::vector<std::string>& v) {
      std::string s = "[";
      for (std::size_t i = 0; i < v.size(); ++i) s += (i ? ", " : "") + v[i];
      return s + "]";
    };
    d.push_back("overrides " + list(found.overrides) + " differ from --set " + list(wanted.overrides));
  }
  if (found.seed != wanted.seed)
    d.push_back("seed " + std::to_string(found.seed) + " differs from " + std::to_string(wanted.seed));
  // Exact texts: two rates that differ past the sixth digit must not read as the same number.
  if (found.fps != wanted.fps)
    d.push_back("fps " + sim::exact_number(found.fps) + " differs from " + sim::exact_number(wanted.fps));
  if (found.simreel_version != wanted.simreel_version)
    d.push_back("baked by simreel " + found.simreel_version + ", this is " + wanted.simreel_version);
  if (found.state_format != wanted.state_format)
    d.push_back("state format " + std::to_string(found.state_format) + ", this build reads " +
                std::to_string(wanted.state_format));
  std::string out;
  for (std::size_t i = 0; i < d.size(); ++i) out += (i ? "; " : "") + d[i];
  return out;
}

void write_frame(const fs::path& dir, int frame, std::uint64_t key, const std::string& state, std::string& scratch) {
  scratch.clear();
  scratch.append(kFrameMagic, 8);
  put(scratch, std::uint32_t(kCacheFormat));
  put(scratch, std::uint32_t(0));
  put(scratch, std::uint64_t(frame));
  put(scratch, key);
  put(scratch, std::uint64_t(state.size()));
  Fnv f;
  f.bytes(state.data(), state.size());
  put(scratch, f.h);
  scratch += state;
  render::write_file_atomic(frame_path(dir, frame), scratch);
}

namespace {

/// Why the frame file `p` cannot be read ("" when it is a regular file, whose size goes to `size`).
/// A FIFO in its place blocked `render --cache` and `bake --resume` forever.
std::string frame_file_problem(const fs::path& p, int frame, std::uint64_t& size) {
  std::error_code ec;
  const fs::file_status st = fs::status(p, ec);
  if (!fs::exists(st)) return p.string() + ": missing (frame " + std::to_string(frame) + " is not in the cache)";
  if (!fs::is_regular_file(st))
    return p.string() + ": not a regular file (a device, FIFO, socket or folder), expected a cache frame";
  size = fs::file_size(p, ec);
  if (ec) return p.string() + ": cannot read: " + ec.message();
  return {};
}

}  // namespace

namespace {

/// Opens frame `frame`'s file, reads its header into `h` and checks it against the file's size
/// (`size`) and the manifest's `key`; "" when it is good, `in` then placed at the payload.
std::string open_frame(const fs::path& p, int frame, std::uint64_t key, std::ifstream& in,
                       char (&h)[kHeaderBytes], std::uint64_t& size) {
  if (std::string e = frame_file_problem(p, frame, size); !e.empty()) return e;
  in.open(p, std::ios::binary);
  if (!in) return p.string() + ": cannot read (permission denied or unreadable)";
  in.read(h, kHeaderBytes);
  return check_header(p, h, size, frame, key);
}

}  // namespace

std::string read_frame(const fs::path& dir, int frame, std::uint64_t key, std::string& state) {
  const fs::path p = frame_path(dir, frame);
  std::ifstream in;
  char h[kHeaderBytes] = {};
  std::uint64_t size = 0;
  if (std::string e = open_frame(p, frame, key, in, h, size); !e.empty()) return e;
  // The header and the file's size agree on the payload's length: read that much, no more.
  std::string bytes(std::size_t(size - kHeaderBytes), '\0');
  in.read(bytes.data(), std::streamsize(bytes.size()));
  if (std::size_t(in.gcount()) != bytes.size())
    return p.string() + ": truncated while read (" + std::to_string(kHeaderBytes + std::size_t(in.gcount())) +
           " of " + std::to_string(size) + " bytes)";
  Fnv f;
  f.bytes(bytes.data(), bytes.size());
  if (f.h != get<std::uint64_t>(h + 40))
    return p.string() + ": corrupt (checksum " + hex16(f.h) + ", the header says " + hex16(get<std::uint64_t>(h + 40)) +
           ")";
  state = std::move(bytes);
  return {};
}

std::string check_frame_header(const fs::path& dir, int frame, std::uint64_t key) {
  std::ifstream in;
  char h[kHeaderBytes] = {};
  std::uint64_t size = 0;
  return open_frame(frame_path(dir, frame), frame, key, in, h, size);
}

void remove_stale_temporaries(const fs::path& dir) {
  for (const fs::path& d : {dir, dir / "state", ply_dir(dir)}) {
    std::error_code ec;
    if (!fs::is_directory(d, ec)) continue;
    for (const auto& e : fs::directory_iterator(d, ec)) {
      const std::string name = e.path().filename().string();
      if (name.size() > 1 && name[0] == '.' && name.find(".tmp-") != std::string::npos) fs::remove(e.path(), ec);
    }
  }
}

}  // namespace simreel::app
