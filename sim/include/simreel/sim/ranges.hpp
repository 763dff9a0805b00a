#pragma once
/// @file ranges.hpp
/// The accepted range of every numeric definition field that both the scene loader (demos/,
/// JSON key of the same name) and the engine's validation check, written once. The loader
/// reports a value outside with the file and JSON pointer; the engine's validate() functions
/// throw std::invalid_argument naming the field, the range and the value. Both therefore reject
/// exactly the same values. Units are those of the field (SI, degrees where the name says so);
/// the comment of each constant gives the book section of the quantity (Coutinho, *Dynamic
/// Simulations of Multibody Systems*).
///
/// Eigen-free and constexpr, so the loader and tests can use it without the engine's types.

#include <charconv>
#include <cstdint>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <string>

namespace simreel::sim {

/// A closed interval [min, max], or (min, max] when `min_open`. NaN is never inside. An infinite
/// value is inside only if `infinity_ok` (and the bound on its side is infinite): "no upper
/// bound" means any finite value unless said otherwise.
struct Range {
  double min = -std::numeric_limits<double>::infinity();
  double max = std::numeric_limits<double>::infinity();
  bool min_open = false;     ///< min itself is outside
  bool infinity_ok = false;  ///< +inf is a meaningful value (e.g. "no limit")

  [[nodiscard]] constexpr bool contains(double x) const {
    if (!(min_open ? x > min : x >= min) || !(x <= max)) return false;  // NaN fails here
    return infinity_ok || (x > -std::numeric_limits<double>::infinity() &&
                           x < std::numeric_limits<double>::infinity());
  }
};

/// An integer interval [min, max] (counts, indices).
struct IntRange {
  long long min = 0;
  long long max = std::numeric_limits<long long>::max();

  [[nodiscard]] constexpr bool contains(long long x) const { return x >= min && x <= max; }
};

namespace ranges {

inline constexpr double kInf = std::numeric_limits<double>::infinity();
inline constexpr Range kNonNegative{0.0, kInf};        ///< >= 0 and finite
inline constexpr Range kPositive{0.0, kInf, true};     ///< > 0 and finite
inline constexpr Range kUnit{0.0, 1.0};                ///< [0, 1]

// World (WorldDef; Coutinho §1.4.1: the engine picks internal steps inside one sampling time).
inline constexpr Range kWorldMaxStep{1e-6, 1.0};  ///< (s) largest internal step, [1e-6, 1]
/// Most internal steps one World::advance(sampling_time) may take (ceil(sampling_time /
/// max_step)); more is refused with std::invalid_argument instead of running for hours.
inline constexpr std::uint64_t kMaxStepsPerAdvance = 1'000'000;
inline constexpr Range kWorldBodySubsteps{1.0, 16.0};  ///< bodies' solver substeps per internal step (integer)
inline constexpr Range kWorldContactSpeed = kNonNegative;  ///< (m/s) resting-contact threshold (§3.6.3)
inline constexpr Range kWorldMaxSpeed{0.0, 3e38, true};     ///< (m/s) divergence bound on |v_k|
inline constexpr Range kWorldMaxDistance{0.0, 3e38, true};  ///< (m) divergence bound on |x_k|

// Keyframe paths (KeyframePath; kinematic objects, §1.4.1: the caller moves them).
inline constexpr Range kKeyframeTime = kNonNegative;    ///< (s) scene time of a key

// Emitters (EmitterDef; §3.8 emission, §3.9.1 particle systems).
inline constexpr Range kEmitterRate{0.0, 1e9};          ///< (particles/s)
inline constexpr IntRange kEmitterMaxParticles{1, 50'000'000};  ///< live particles per system
/// (kg, m) the largest mass and radius a particle may be born with: both are stored as 32-bit
/// floats, and a larger value becomes infinite (the particle is then reported as diverged at its
/// first step).
inline constexpr double kParticleFloatMax = 3e38;
/// (kg) the smallest particle mass: an emitter's draws are raised to it, a split's children too,
/// and an initial particle below it is refused (drag and every force divide by the mass; far
/// smaller, a float mass is zero).
inline constexpr double kParticleMassMin = 1e-12;
/// (m) the smallest particle radius: draws and size curves are raised to it, an initial
/// particle below it is refused.
inline constexpr double kParticleRadiusMin = 1e-6;
inline constexpr Range kEmitterSize = kPositive;        ///< (m) disk_radius, quad_size, sphere_radius, box_size, cube_size
inline constexpr Range kEmitterInheritVelocity = kUnit; ///< fraction of the emitter's path velocity
inline constexpr Range kEmitterColorDeviation = kNonNegative;  ///< deviation of each RGB channel
inline constexpr Range kBurstTime = kNonNegative;       ///< (s) first burst
inline constexpr Range kBurstRepeatInterval = kNonNegative;  ///< (s) 0 = once
inline constexpr Range kSizeKeyT = kUnit;               ///< age / lifetime of a size key
inline constexpr Range kSizeKeySize = kNonNegative;     ///< size factor
// Particle split (SplitDef; §3.9.1, the nine split parameters).
inline constexpr IntRange kSplitChildren{1, 1'000'000};
inline constexpr Range kSplitAge = kNonNegative;        ///< (s)
inline constexpr IntRange kSplitDelaySteps{1, 1'000'000};
inline constexpr IntRange kSplitDepth{1, 32};
inline constexpr Range kSplitVelocityFraction = kNonNegative;
inline constexpr Range kSplitDirectionDeviationDeg{0.0, 180.0};  ///< (degrees)
inline constexpr Range kSplitSizeFraction = kPositive;
inline constexpr Range kSplitLifetimeDeviation = kNonNegative;  ///< (s)

// Particle-system forces and integrators (ParticleSystemDef; §3.3 forces, App. B integrators).
inline constexpr Range kSystemDrag = kNonNegative;       ///< (kg/s) viscous drag, f = -drag v
/// (kg/m) quadratic drag, f = -drag_quadratic |v| v
inline constexpr Range kSystemDragQuadratic = kNonNegative;
inline constexpr Range kSystemTolerance = kPositive;     ///< (m) adaptive integrator's error bound
inline constexpr Range kPairG = kNonNegative;            ///< (N m²/kg²) gravitational constant
inline constexpr Range kPairK = kNonNegative;            ///< (N m²/C²) Coulomb constant
inline constexpr Range kPairCutoff = kPositive;          ///< (m) interaction cut-off
inline constexpr Range kPairSoftening = kNonNegative;    ///< (m)
inline constexpr Range kSpringStiffness = kNonNegative;  ///< (N/m) damped springs (§3.3)
inline constexpr Range kSpringDamping = kNonNegative;    ///< (N s/m)

// Force fields (ForceFieldDef; §3.3 fields in a region with drop-off; curl noise beyond the book).
inline constexpr Range kFieldRadius = kPositive;         ///< (m) sphere region
inline constexpr Range kFieldHalfExtent = kPositive;     ///< (m) box region, each axis
inline constexpr Range kFieldAmplitude = kNonNegative;   ///< (m/s) curl-noise velocity scale
inline constexpr Range kFieldFrequency = kPositive;      ///< (1/m) curl-noise spatial frequency
inline constexpr Range kFieldDrag = kNonNegative;        ///< (kg/s) pull towards the air velocity
inline constexpr Range kFieldImpulse = kNonNegative;     ///< (N s) momentum of a blast
inline constexpr Range kFieldTime = kNonNegative;        ///< (s) when a blast passes

// Attractor springs (AttractorSpringDef; §3.3 damped springs to an anchor).
inline constexpr Range kAttractorStiffness = kSpringStiffness;  ///< (N/m)
inline constexpr Range kAttractorDamping = kSpringDamping;      ///< (N s/m)

// Collision response (Material; §3.6.1 restitution and Coulomb friction).
inline constexpr Range kRestitution = kUnit;             ///< coefficient of restitution
inline constexpr Range kFriction = kNonNegative;         ///< Coulomb coefficient
// Droplets of a split hit (SplitOnHit).
inline constexpr IntRange kHitSplitCount{0, 64};
inline constexpr Range kHitSplitSpeedFraction = kNonNegative;
inline constexpr Range kHitSplitSizeFraction{0.0, 1.0, true};  ///< (0, 1]
inline constexpr Range kHitSplitLifetime = kPositive;    ///< (s)
inline constexpr Range kHitSplitSpreadDeg{0.0, 90.0};    ///< (degrees) from the normal
inline constexpr Range kHitSplitMinRadius = kNonNegative;  ///< (m)

// Colliders (§2: shapes).
inline constexpr Range kColliderSize = kPositive;        ///< (m) box half extents, sphere and cylinder radius, half height

// Dynamic bodies (BodyDef, ShapeDef; Ch. 4 rigid-body dynamics, App. D mass properties).
inline constexpr Range kBodyDensity = kPositive;         ///< (kg/m³) ShapeDef::density
/// (kg) a body's total mass when given (BodyDef::mass; the field's 0 means "from the densities").
inline constexpr Range kBodyMass = kPositive;
inline constexpr Range kBodyDamping = kNonNegative;      ///< (1/s) linear and angular damping
inline constexpr Range kBodyDragCoefficient = kNonNegative;  ///< C_d of the air drag (BodyDef)
inline constexpr Range kBodyDragArea = kNonNegative;     ///< (m²) 0: a quarter of the surface area

// Cloths (ClothDef; §3.9.2).
inline constexpr IntRange kClothGrid{1, 1024};           ///< rows, columns (vertices)
inline constexpr Range kClothSize = kPositive;           ///< (m) width, height
inline constexpr Range kClothMass = kPositive;           ///< (kg) whole cloth
inline constexpr Range kClothStiffness = kSpringStiffness;  ///< (N/m) stretch, shear, bend
inline constexpr Range kClothSpringDamping = kSpringDamping;  ///< (N s/m)
inline constexpr Range kClothMaxStrain{0.0, kInf, false, true};  ///< l / L - 1; +inf disables
inline constexpr Range kClothDamping = kNonNegative;     ///< (kg/s) per vertex
inline constexpr Range kClothGustAmplitude = kNonNegative;  ///< fraction of the wind speed
inline constexpr Range kClothGustFrequency = kPositive;  ///< (Hz)
inline constexpr Range kClothAero = kNonNegative;        ///< drag, lift coefficients; air density (kg/m³)
inline constexpr Range kClothThickness = kNonNegative;   ///< (m)
inline constexpr Range kClothFriction = kFriction;
inline constexpr Range kClothRestitution = kRestitution;

}  // namespace ranges

/// How a number reads in messages: ten significant digits, in fixed or exponent form as %g
/// picks ("0.1", "23.97602398", "1e-300", "inf", "nan"). std::to_string's six fixed decimals
/// printed 1e-300 as "0.000000" and 1e300 as a 301-digit integer.
inline std::string format_number(double x) {
  std::ostringstream s;
  s.precision(10);
  s << x;
  return s.str();
}

/// The shortest text that reads back as exactly x (std::to_chars' round-trip form, e.g.
/// "23.976023976"): for a number handed on to another run (a sweep's children), where
/// format_number() would round it.
inline std::string exact_number(double x) {
  char buf[32];
  const auto [end, ec] = std::to_chars(buf, buf + sizeof buf, x);
  return ec == std::errc() ? std::string(buf, end) : format_number(x);
}

/// How a range reads in messages: "in [0, 1]", "in (0, 1]", ">= 0 and finite", "> 0 and
/// finite", ">= 0 (infinity allowed)".
inline std::string describe(const Range& r) {
  std::ostringstream s;
  if (r.max == std::numeric_limits<double>::infinity()) {
    s << (r.min_open ? "> " : ">= ") << r.min << (r.infinity_ok ? " (infinity allowed)" : " and finite");
  } else {
    s << "in " << (r.min_open ? "(" : "[") << r.min << ", " << r.max << "]";
  }
  return s.str();
}
inline std::string describe(const IntRange& r) {
  return "in [" + std::to_string(r.min) + ", " + std::to_string(r.max) + "]";
}

/// @throws std::invalid_argument "`what` must be <describe(r)> (got `x`)" if x is outside.
inline void require_in(double x, const Range& r, const std::string& what) {
  if (r.contains(x)) return;
  std::ostringstream m;
  m << what << " must be " << describe(r) << " (got " << x << ")";
  throw std::invalid_argument(m.str());
}
inline void require_in(long long x, const IntRange& r, const std::string& what) {
  if (r.contains(x)) return;
  throw std::invalid_argument(what + " must be " + describe(r) + " (got " + std::to_string(x) + ")");
}

}  // namespace simreel::sim
