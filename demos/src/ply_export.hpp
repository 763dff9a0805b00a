#pragma once
/// @file ply_export.hpp
/// Interchange: particles and cloth of one frame as binary PLY (little-endian, PLY 1.0), the
/// point-cloud and mesh format that Blender, Houdini, MeshLab and Open3D read (docs/cache.md).
///
/// Particles: `element vertex N` with float x y z (m, world, z up), float vx vy vz (m/s),
/// uchar red green blue alpha (the linear RGBA drawn, times 255, rounded), float radius (m),
/// uint id (the stable particle id, low 32 bits).
/// Cloth: the same vertex properties (colour: the cloth's, radius: half its thickness, id: the
/// vertex index, plus float nx ny nz) and `element face T` of `list uchar uint vertex_indices`.

#include <filesystem>
#include <string>

#include "simreel/sim/cloth.hpp"
#include "simreel/sim/particle_system.hpp"

namespace simreel::app {

/// The bytes of a particle PLY (appended to `out`, which is cleared first).
void particles_ply(const sim::ParticleView& v, std::string& out);
/// The bytes of a cloth PLY; rgba in [0, 1], radius (m).
void cloth_ply(const sim::ClothView& v, const float rgba[4], float radius, std::string& out);

/// DIR/ply/system<I>.<FRAME>.ply and DIR/ply/cloth<I>.<FRAME>.ply (frame as 5 digits).
std::filesystem::path ply_file(const std::filesystem::path& dir, const std::string& object, int index, int frame);

}  // namespace simreel::app
