// Forces and integrators (Coutinho §3.3, App. B): per-system keys, force fields, attractor springs.
#include <algorithm>

#include "scene_read.hpp"

namespace simreel::app::scene_read {

void particle_forces(ObjectReader& r, sim::ParticleSystemDef& s) {
  static const std::vector<std::string> names = {"semi_implicit_euler", "explicit_euler", "rk2",
                                                 "rk4", "implicit_euler", "adaptive"};
  static const sim::Integrator values[] = {sim::Integrator::semi_implicit_euler, sim::Integrator::explicit_euler,
                                           sim::Integrator::rk2, sim::Integrator::rk4,
                                           sim::Integrator::implicit_euler, sim::Integrator::adaptive};
  const std::string in = r.choice("integrator", "semi_implicit_euler", names);
  s.integrator = values[std::find(names.begin(), names.end(), in) - names.begin()];
  s.tolerance = r.number("tolerance", s.tolerance, ranges::kSystemTolerance);
  s.charge = distribution(r, "charge", s.charge, -kInf, kInf, "C");
  if (const json* pj = object_member(r, "pair_forces")) {
    ObjectReader o(*pj, r.pointer("pair_forces"), r.file(), r.errors());
    s.pair_forces.gravitational_G = o.number("gravitational_G", 0.0, ranges::kPairG);
    s.pair_forces.coulomb_K = o.number("coulomb_K", 0.0, ranges::kPairK);
    s.pair_forces.cutoff = o.number("cutoff", 1.0, ranges::kPairCutoff);
    s.pair_forces.softening = o.number("softening", s.pair_forces.softening, ranges::kPairSoftening);
    o.finish();
  }
  object_array(r, "initial_particles", [&](const json& j, const std::string& p, std::size_t) {
    ObjectReader o(j, p, r.file(), r.errors());
    sim::InitialParticle q;
    if (!o.has("position")) o.error_at(p, "expected a \"position\" [x, y, z] (m)");
    q.position = to_vec(o.vec3("position", {0, 0, 0}));
    q.velocity = to_vec(o.vec3("velocity", {0, 0, 0}));
    q.mass = o.number("mass", s.emitter.mass.mean, ranges::kParticleMassMin, ranges::kParticleFloatMax);
    q.radius = o.number("radius", s.emitter.radius.mean, ranges::kParticleRadiusMin, ranges::kParticleFloatMax);
    q.charge = o.number("charge", 0.0);
    o.finish();
    s.initial_particles.push_back(q);
  });
  if (s.initial_particles.size() > s.emitter.max_particles)
    r.error_at(r.pointer("initial_particles"), "expected at most max_particles (" +
                                                   std::to_string(s.emitter.max_particles) + ") particles");
  const long long n_init = (long long)(s.initial_particles.size());
  object_array(r, "springs", [&](const json& j, const std::string& p, std::size_t) {
    ObjectReader o(j, p, r.file(), r.errors());
    sim::SpringDef sp;
    if (n_init < 2) o.error_at(p, "expected springs only between initial_particles (at least 2)");
    if (!o.has("a") || !o.has("b")) o.error_at(p, "expected \"a\" and \"b\" (indices into initial_particles)");
    // Their upper bound depends on the scene: the schema (KeyLog) records them without one.
    for (const char* key : {"a", "b"}) o.record(key, {{"type", "integer"}, {"minimum", 0}});
    sp.a = std::uint64_t(o.integer("a", 0, 0, std::max(0LL, n_init - 1)));
    sp.b = std::uint64_t(o.integer("b", 1, 0, std::max(0LL, n_init - 1)));
    if (sp.a == sp.b && o.has("a")) o.error_at(o.pointer("b"), "expected b different from a");
    sp.stiffness = o.number("stiffness", sp.stiffness, ranges::kSpringStiffness);
    sp.damping = o.number("damping", sp.damping, ranges::kSpringDamping);
    const json* rl = o.get("rest_length");
    if (rl && rl->is_string() && rl->get<std::string>() == "initial") sp.rest_length = -1.0;
    else if (rl) sp.rest_length = o.number("rest_length", -1.0, 0.0, kInf);
    o.finish();
    s.springs.push_back(sp);
  });
}

namespace {

/// Names of systems (emitter names) in a "systems" array of strings.
std::vector<std::string> system_names(ObjectReader& r, const std::string& key) {
  std::vector<std::string> out;
  const json* a = r.get(key);
  if (!a) return out;
  if (!a->is_array()) {
    r.error(key, "an array of emitter names", *a);
    return out;
  }
  for (std::size_t i = 0; i < a->size(); ++i) {
    if (!(*a)[i].is_string())
      r.error_at(r.pointer(key) + "/" + std::to_string(i), "expected an emitter name, found " + describe((*a)[i]));
    else
      out.push_back((*a)[i].get<std::string>());
  }
  return out;
}

}  // namespace

ForceFieldScene force_field(const json& j, const std::string& ptr, const std::string& file,
                            std::vector<std::string>& errors) {
  ForceFieldScene f;
  sim::ForceFieldDef& d = f.def;
  ObjectReader r(j, ptr, file, errors);
  const std::string type =
      r.choice("type", "uniform", {"uniform", "attractor", "vortex", "curl_noise", "blast"});
  d.kind = type == "attractor" ? sim::FieldKind::attractor
           : type == "vortex"  ? sim::FieldKind::vortex
           : type == "curl_noise" ? sim::FieldKind::curl_noise
           : type == "blast"      ? sim::FieldKind::blast
                                  : sim::FieldKind::uniform;
  if (const json* rj = object_member(r, "region")) {
    ObjectReader o(*rj, r.pointer("region"), file, errors);
    const std::string shape = o.choice("shape", "everywhere", {"everywhere", "sphere", "box"});
    d.shape = shape == "sphere" ? sim::RegionShape::sphere
              : shape == "box"  ? sim::RegionShape::box
                                : sim::RegionShape::everywhere;
    d.transform.translation = to_vec(o.vec3("center", {0, 0, 0}));
    d.transform.rotation = rotation_from_deg(o.vec3("rotation_deg", {0, 0, 0}));
    if (d.shape == sim::RegionShape::sphere) d.radius = o.number("radius", 1.0, ranges::kFieldRadius);
    if (d.shape == sim::RegionShape::box) {
      const auto he = o.numbers("half_extents", {1, 1, 1}, 3, ranges::kFieldHalfExtent);
      d.half_extents = sim::Vec3(he[0], he[1], he[2]);
    }
    o.finish();
  }
  const std::string falloff = r.choice("falloff", "none", {"none", "linear", "quadratic"});
  d.falloff = falloff == "linear" ? sim::Falloff::linear
              : falloff == "quadratic" ? sim::Falloff::quadratic
                                       : sim::Falloff::none;
  d.path = keyframe_path(r, "path");
  switch (d.kind) {
    case sim::FieldKind::uniform:
      d.acceleration = to_vec(r.vec3("acceleration", {0, 0, 0}));
      d.force = to_vec(r.vec3("force", {0, 0, 0}));
      d.wind = to_vec(r.vec3("wind", {0, 0, 0}));
      d.drag = r.number("drag", d.drag, ranges::kFieldDrag);
      break;
    case sim::FieldKind::blast:
      d.impulse = r.number("impulse", 0.0, ranges::kFieldImpulse);
      d.time = r.number("time", 0.0, ranges::kFieldTime);
      break;
    case sim::FieldKind::attractor:
      d.strength = r.number("strength", d.strength);
      break;
    case sim::FieldKind::vortex:
      d.strength = r.number("strength", d.strength);
      d.axis = to_vec(r.vec3("axis", {0, 0, 1}));
      if (d.axis.norm() < 1e-12) r.error_at(r.pointer("axis"), "expected a non-zero axis");
      d.inward_strength = r.number("inward_strength", 0.0);
      break;
    case sim::FieldKind::curl_noise:
      d.amplitude = r.number("amplitude", d.amplitude, ranges::kFieldAmplitude);
      d.frequency = r.number("frequency", d.frequency, ranges::kFieldFrequency);
      d.scroll = to_vec(r.vec3("scroll", {0, 0, 0}));
      d.drag = r.number("drag", d.drag, ranges::kFieldDrag);
      break;
  }
  d.bodies = r.boolean("bodies", true);
  d.particles = r.boolean("particles", true);
  f.systems = system_names(r, "systems");
  r.finish();
  return f;
}

AttractorSpringScene attractor_spring(const json& j, const std::string& ptr, const std::string& file,
                                      std::vector<std::string>& errors) {
  AttractorSpringScene a;
  ObjectReader r(j, ptr, file, errors);
  if (!r.has("system")) r.error_at(ptr, "expected a \"system\" (an emitter name)");
  a.system = r.string("system", "");
  if (const json* ids = r.get("ids")) {
    if (!ids->is_array()) r.error("ids", "an array of particle ids (integers >= 0)", *ids);
    else
      for (std::size_t i = 0; i < ids->size(); ++i) {
        const json& v = (*ids)[i];
        if (!v.is_number_integer() || v.get<long long>() < 0)
          r.error_at(r.pointer("ids") + "/" + std::to_string(i), "expected a particle id (integer >= 0), found " + describe(v));
        else
          a.def.ids.push_back(v.get<std::uint64_t>());
      }
  }
  a.def.anchor = to_vec(r.vec3("anchor", {0, 0, 0}));
  a.def.path = keyframe_path(r, "path");
  a.def.stiffness = r.number("stiffness", a.def.stiffness, ranges::kAttractorStiffness);
  a.def.damping = r.number("damping", a.def.damping, ranges::kAttractorDamping);
  r.finish();
  return a;
}

}  // namespace simreel::app::scene_read
