#include "golden.hpp"

#include <algorithm>
#include <fstream>
#include <utility>

#include "json_reader.hpp"
#include "simreel/render/image_hash.hpp"

namespace simreel::app {

namespace fs = std::filesystem;

FrameHashes hash_frame(const render::Image& image, int frame) {
  return {frame, render::phash(image), render::dhash(image), render::chash(image)};
}

bool is_hashed_frame(const HashRecord& r, int frame) {
  return frame >= r.first && frame < r.end && (frame - r.first) % r.every == 0;
}

namespace {

std::string range_text(const HashRecord& r) {
  return std::to_string(r.first) + ":" + std::to_string(r.end);
}

}  // namespace

nlohmann::ordered_json to_json(const HashRecord& r) {
  nlohmann::ordered_json j = nlohmann::ordered_json::object();
  j["simreel_hashes"] = r.format;
  j["scene"] = r.scene;
  j["set"] = r.overrides;
  j["seed"] = r.seed;
  j["size"] = std::to_string(r.width) + "x" + std::to_string(r.height);
  j["fps"] = r.fps;
  j["frames"] = range_text(r);
  j["hash_every"] = r.every;
  j["backend"] = r.backend;
  j["tolerance"] = {{"phash", r.tolerance.phash}, {"dhash", r.tolerance.dhash}, {"chash", r.tolerance.chash}};
  j["simreel_version"] = r.simreel_version;
  j["gl_renderer"] = r.gl_renderer;
  j["gl_version"] = r.gl_version;
  if (!r.note.empty()) j["note"] = r.note;
  nlohmann::ordered_json frames = nlohmann::ordered_json::array();
  for (const FrameHashes& f : r.frames) {
    frames.push_back({{"frame", f.frame},
                      {"phash", render::hash_to_hex(f.phash)},
                      {"dhash", render::hash_to_hex(f.dhash)},
                      {"chash", render::hash_to_hex(f.chash)}});
  }
  j["hashes"] = std::move(frames);
  return j;
}

HashRecord read_hash_record(const fs::path& path) {
  const std::string file = path.string();
  const nlohmann::json doc = parse_json_file(path, "golden");
  std::vector<std::string> errors;
  if (!doc.is_object()) throw SceneError(file + ": expected a JSON object, found " + describe(doc));
  ObjectReader top(doc, "", file, errors);
  HashRecord r;
  // Each value's own check comes first; a follow-up error ("missing", "found nothing") is only
  // for a value that was absent or of the right type, not a second message about the same one.
  const auto clean_since = [&](std::size_t before) { return errors.size() == before; };
  std::size_t before = errors.size();
  const long long format = top.integer("simreel_hashes", -1, 1, kHashFormat);
  if (format < 0 && clean_since(before)) top.error_at("/simreel_hashes", "missing: expected 1 or 2 (a file written by `simreel render --hash`)");
  r.format = int(std::max(1LL, format));
  before = errors.size();
  r.scene = top.string("scene", "");
  if (r.scene.empty() && clean_since(before)) top.error_at("/scene", "expected the scene path, found nothing");
  if (const nlohmann::json* set = top.get("set")) {
    if (!set->is_array()) {
      top.error("set", "an array of \"POINTER=VALUE\" strings", *set);
    } else {
      for (std::size_t i = 0; i < set->size(); ++i) {
        if ((*set)[i].is_string()) {
          r.overrides.push_back((*set)[i].get<std::string>());
        } else {
          top.error_at("/set/" + std::to_string(i), "expected a \"POINTER=VALUE\" string, found " + describe((*set)[i]));
        }
      }
    }
  }
  r.seed = top.integer("seed", 0, 0, std::numeric_limits<long long>::max());
  before = errors.size();
  const std::string size = top.string("size", "");
  if (const auto wh = parse_pair(size, 'x', 16, 8192)) {
    r.width = int(wh->first);
    r.height = int(wh->second);
  } else if (clean_since(before)) {
    top.error_at("/size", "expected \"WIDTHxHEIGHT\" with each in [16, 8192], found \"" + size + "\"");
  }
  r.fps = top.number("fps", 30.0, 0.0, 1000.0, true);
  before = errors.size();
  const std::string frames = top.string("frames", "");
  if (const auto fe = parse_pair(frames, ':', 0, kMaxFrames); fe && fe->first < fe->second) {
    r.first = int(fe->first);
    r.end = int(fe->second);
  } else if (clean_since(before)) {
    top.error_at("/frames", "expected \"FIRST:END\" with 0 <= FIRST < END <= " + std::to_string(kMaxFrames) +
                                ", found \"" + frames + "\"");
  }
  r.every = int(top.integer("hash_every", 1, 1, 1000000));
  r.backend = top.choice("backend", "osmesa", {"osmesa", "egl"});
  if (const nlohmann::json* tol = top.get("tolerance")) {
    if (tol->is_number_integer()) {
      const int t = tol->get<int>();
      if (t < 0 || t > 64) top.error("tolerance", "an integer in [0, 64] or an object", *tol);
      r.tolerance = {t, t, t};
    } else if (tol->is_object()) {
      ObjectReader t(*tol, "/tolerance", file, errors);
      r.tolerance.phash = int(t.integer("phash", r.tolerance.phash, 0, 64));
      r.tolerance.dhash = int(t.integer("dhash", r.tolerance.dhash, 0, 64));
      r.tolerance.chash = int(t.integer("chash", r.tolerance.chash, 0, 64));
      t.finish();
    } else {
      top.error("tolerance", "an integer in [0, 64] or an object {\"phash\", \"dhash\", \"chash\"}", *tol);
    }
  }
  r.simreel_version = top.string("simreel_version", "");
  r.gl_renderer = top.string("gl_renderer", "");
  r.gl_version = top.string("gl_version", "");
  r.note = top.string("note", "");
  if (const nlohmann::json* hashes = top.get("hashes")) {
    if (!hashes->is_array()) {
      top.error("hashes", "an array of {\"frame\", \"phash\", \"dhash\", \"chash\"}", *hashes);
    } else {
      for (std::size_t i = 0; i < hashes->size(); ++i) {
        const std::string ptr = "/hashes/" + std::to_string(i);
        if (!(*hashes)[i].is_object()) {
          top.error_at(ptr, "expected an object, found " + describe((*hashes)[i]));
          continue;
        }
        ObjectReader e((*hashes)[i], ptr, file, errors);
        FrameHashes f;
        before = errors.size();
        f.frame = int(e.integer("frame", -1, 0, 100000000));
        if (f.frame < 0 && clean_since(before)) e.error_at(ptr + "/frame", "missing: expected the frame number");
        if (f.frame >= 0 && errors.empty() && !is_hashed_frame(r, f.frame)) {
          e.error_at(ptr + "/frame", "frame " + std::to_string(f.frame) + " is not one the record hashes (frames " +
                                         range_text(r) + " every " + std::to_string(r.every) + ")");
        }
        for (auto [key, slot] : {std::pair{"phash", &f.phash}, std::pair{"dhash", &f.dhash},
                                 std::pair{"chash", &f.chash}}) {
          before = errors.size();
          const std::string hex = e.string(key, "");
          if (!clean_since(before)) continue;
          try {
            *slot = render::parse_hash(hex);
          } catch (const std::invalid_argument&) {
            e.error_at(ptr + "/" + key, hex.empty() ? std::string("missing: expected 16 hex digits")
                                                    : "expected 16 hex digits, found \"" + hex + "\"");
          }
        }
        e.finish();
        r.frames.push_back(f);
      }
    }
  }
  top.finish();
  if (!errors.empty()) throw SceneError(errors);
  return r;
}

namespace {

class HashRecorder final : public render::FrameSink {
 public:
  HashRecorder(fs::path path, HashRecord record) : path_(std::move(path)), record_(std::move(record)) {}
  void write(const render::Image& frame, int index) override {
    if (is_hashed_frame(record_, index)) record_.frames.push_back(hash_frame(frame, index));
  }
  void finish() override { write_file_atomic(path_, to_json(record_).dump(2) + "\n"); }
  void abort() noexcept override {}
  [[nodiscard]] std::string describe() const override { return path_.string(); }

 private:
  fs::path path_;
  HashRecord record_;
};

}  // namespace

std::unique_ptr<render::FrameSink> make_hash_recorder(const fs::path& path, HashRecord record) {
  return std::make_unique<HashRecorder>(path, std::move(record));
}

std::string scene_relative_to_golden(const fs::path& scene, const fs::path& golden) {
  const fs::path abs_scene = fs::absolute(scene).lexically_normal();
  const fs::path folder = fs::absolute(golden).lexically_normal().parent_path();
  const fs::path rel = abs_scene.lexically_relative(folder);
  return rel.empty() ? abs_scene.string() : rel.generic_string();
}

fs::path golden_frames_dir(const fs::path& golden) {
  fs::path dir = golden;
  dir.replace_extension(".frames");
  return dir;
}

}  // namespace simreel::app
