// Value readers shared by the scene loader's readers: rotations, distributions, keyframe paths.
#include <algorithm>
#include <cmath>
#include <sstream>
#include <system_error>

#include "scene_read.hpp"
#include "simreel/sim/ranges.hpp"
#include "simreel/render/image.hpp"

namespace simreel::app::scene_read {

sim::Quat rotation_from_deg(const std::array<double, 3>& r) {
  return sim::Quat(Eigen::AngleAxisd(r[2] * kDeg, sim::Vec3::UnitZ()) *
                   Eigen::AngleAxisd(r[1] * kDeg, sim::Vec3::UnitY()) *
                   Eigen::AngleAxisd(r[0] * kDeg, sim::Vec3::UnitX()));
}

std::string steps_per_frame_problem(double fps, double max_step) {
  if (!(fps > 0.0) || !(max_step > 0.0)) return "";  // reported by the keys' own ranges
  const double steps = std::ceil((1.0 / fps) / max_step);
  if (steps <= double(ranges::kMaxStepsPerAdvance)) return "";
  std::ostringstream m;
  m << "one frame (1/fps = " << 1.0 / fps << " s) at max_step " << max_step << " s needs " << steps
    << " internal steps, expected at most " << ranges::kMaxStepsPerAdvance
    << " (raise fps or simulation.max_step)";
  return m.str();
}

const json* object_member(ObjectReader& r, const std::string& key) {
  const json* v = r.get(key);
  if (v && !v->is_object()) {
    r.error(key, "an object", *v);
    return nullptr;
  }
  return v;
}

sim::Distribution distribution(ObjectReader& r, const std::string& key, sim::Distribution fallback,
                               double min, double max, const std::string& unit) {
  if (KeyLog::current() != nullptr) {
    // A number, {"mean", "deviation", "min", "max"} or {"min", "max"} (Coutinho §3.8).
    json number = {{"type", "number"}};
    if (std::isfinite(min)) number["minimum"] = min;
    if (std::isfinite(max)) number["maximum"] = max;
    const json object = {{"type", "object"},
                         {"properties",
                          {{"mean", number}, {"deviation", {{"type", "number"}, {"minimum", 0}}}, {"min", number},
                           {"max", number}}},
                         {"additionalProperties", false}};
    r.record(key, {{"anyOf", {number, object}}, {"default", fallback.mean}, {"x-unit", unit}});
  }
  const json* v = r.get(key);
  if (!v) return fallback;
  const std::string range = std::string(" in [") + (std::isfinite(min) ? sim::format_number(min) : "-inf") + ", " +
                            (std::isfinite(max) ? sim::format_number(max) : "inf") + "]";
  if (v->is_number()) {
    const double x = r.number(key, fallback.mean, min, max);
    fallback.mean = x;
    fallback.deviation = 0.0;
    return fallback;
  }
  if (!v->is_object()) {
    r.error(key, "a number (" + unit + ") or {\"mean\": ..., \"deviation\": ...}", *v);
    return fallback;
  }
  ObjectReader o(*v, r.pointer(key), r.file(), r.errors());
  sim::Distribution d = fallback;
  if (!o.has("mean") && !o.has("deviation") && o.has("min") && o.has("max")) {
    d.uniform = true;
    d.min = o.number("min", min, min, max);
    d.max = o.number("max", max, min, max);
    if (!std::isfinite(d.min) || !std::isfinite(d.max)) o.error_at(o.pointer(), "expected finite min and max");
    if (d.min > d.max) o.error_at(o.pointer("min"), "expected min <= max");
    d.mean = 0.5 * (d.min + d.max);
    d.deviation = 0.0;
    o.finish();
    return d;
  }
  if (!o.has("mean"))
    o.error_at(o.pointer(), "expected a \"mean\" (" + unit +
                                ") in the distribution, or \"min\" and \"max\" alone for a uniform one");
  d.mean = o.number("mean", fallback.mean, min, max);
  d.deviation = o.number("deviation", 0.0, 0.0, kInf);
  d.min = o.number("min", std::max(min, fallback.min), min, max);
  d.max = o.number("max", std::min(max, fallback.max), min, max);
  if (d.min > d.max) o.error_at(o.pointer("min"), "expected min <= max");
  o.finish();
  return d;
}

sim::KeyframePath keyframe_path(ObjectReader& r, const std::string& key) {
  sim::KeyframePath path;
  const json* v = object_member(r, key);
  if (!v) return path;
  ObjectReader o(*v, r.pointer(key), r.file(), r.errors());
  path.loop = o.boolean("loop", false);
  path.smooth = o.boolean("smooth", true);
  const json* keys = o.get("keys");
  if (!keys || !keys->is_array() || keys->empty()) {
    o.error("keys", "a non-empty array of {\"time\", \"position\", \"rotation_deg\"}", keys ? *keys : json());
  } else {
    for (std::size_t i = 0; i < keys->size(); ++i) {
      const json& k = (*keys)[i];
      const std::string kp = o.pointer("keys") + "/" + std::to_string(i);
      if (!k.is_object()) {
        o.error_at(kp, "expected an object, found " + describe(k));
        continue;
      }
      ObjectReader kr(k, kp, r.file(), r.errors());
      sim::Keyframe kf;
      if (!kr.has("time")) kr.error_at(kp, "expected a \"time\" (s)");
      kf.time = kr.number("time", 0.0, ranges::kKeyframeTime);
      kf.position = to_vec(kr.vec3("position", {0, 0, 0}));
      kf.rotation = rotation_from_deg(kr.vec3("rotation_deg", {0, 0, 0}));
      kr.finish();
      if (!path.keys.empty() && !(kf.time > path.keys.back().time))
        kr.error_at(kr.pointer("time"), "expected times strictly increasing, found " + describe(k.value("time", json())) +
                                            " after " + describe(json(path.keys.back().time)));
      path.keys.push_back(kf);
    }
  }
  o.finish();
  return path;
}

std::array<double, 3> mesh_scale(ObjectReader& r) {
  const json* sj = r.get("scale");
  if (sj != nullptr && sj->is_number()) {
    const double k = r.number("scale", 1.0, 0.0, kInf, true);
    return {k, k, k};
  }
  if (sj == nullptr) return {1, 1, 1};
  const auto k = r.numbers("scale", {1, 1, 1}, 3, 0.0, kInf, true);
  return {k[0], k[1], k[2]};
}

bool scale_keeps_mesh_finite(ObjectReader& r, const std::array<double, 3>& scale,
                             const std::vector<Eigen::Vector3f>& positions) {
  double reach = 0.0;
  for (const auto& p : positions)
    for (int k = 0; k < 3; ++k) reach = std::max(reach, std::abs(double(p[k]) * scale[std::size_t(k)]));
  if (reach <= kMaxScaledCoordinate) return true;
  const json* sj = r.get("scale");
  std::ostringstream m;
  m << "expected a scale that keeps the mesh within +-" << kMaxScaledCoordinate
    << " m (its vertices are drawn as 32-bit floats), found " << (sj != nullptr ? describe(*sj) : "1")
    << ": a vertex reaches " << reach << " m";
  r.error_at(r.pointer("scale"), m.str());
  return false;
}

std::string texture_problem(const std::filesystem::path& path) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) return path.string() + " is not a file";
  // Decoded here as well as by the renderer: a malformed image is bad input, refused with the
  // scene's other errors, not a failure after the outputs were opened.
  try {
    (void)render::read_image(path);
  } catch (const render::IoError& e) {
    return e.what();
  }
  return {};
}

bool mesh_textures_readable(ObjectReader& r, const std::string& key, const std::filesystem::path& path,
                            const assets::TriangleMesh& mesh) {
  std::vector<std::filesystem::path> seen;  // materials often share one image
  for (const assets::MeshMaterial& m : mesh.materials) {
    const std::string tex = m.texture.string();
    if (tex.empty() || tex[0] == '*' || std::find(seen.begin(), seen.end(), m.texture) != seen.end()) continue;
    seen.push_back(m.texture);
    const std::string why = texture_problem(m.texture);
    if (why.empty()) continue;
    r.error_at(r.pointer(key), path.filename().string() + "'s material \"" + m.name + "\" names the texture " +
                                   m.texture.filename().string() + ": expected an image file (PNG, JPEG, ...) (" + why + ")");
    return false;
  }
  return true;
}

}  // namespace simreel::app::scene_read
