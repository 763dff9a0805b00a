#pragma once
/// @file commands.hpp
/// The subcommands of the `simreel` program, one file each (cmd_<name>.cpp). Each returns the process exit code:
/// 0 ok, 1 runtime failure, 2 bad input or usage. Exceptions are mapped in main.cpp.

#include <optional>
#include <string>
#include <vector>

namespace simreel::app {

/// Options shared by commands that load and run a scene.
struct RunOptions {
  std::string scene;
  std::vector<std::string> overrides;  ///< --set POINTER=VALUE, applied in order
  /// --frames: "N" renders frames 0..N-1; "A:B" simulates from frame 0 but renders and writes
  /// only frames A..B-1 (frame numbers in file names stay absolute).
  std::optional<std::string> frames;
  std::optional<double> fps;
  std::optional<std::string> size;     ///< "WxH"
  std::optional<long long> seed;
  std::optional<std::string> backend;  ///< "osmesa" | "egl"
  std::optional<int> threads;          ///< --threads: overrides simulation.threads (0 = all cores)
  /// --memory-limit (or SIMREEL_MEMORY_LIMIT): bytes with an optional K, M or G suffix; the
  /// scene's estimated memory must fit (default: half the physical memory).
  std::optional<std::string> memory_limit;
  bool renders = false;  ///< the command renders: framebuffers count in the estimate
};

struct RenderOptions : RunOptions {
  std::vector<std::string> outputs;  ///< directories (PNG) or .mp4/.webm/.gif files; default out/<stem>/ + out/<stem>.mp4
  int png_compression = 1;  ///< zlib level; 1 keeps PNG writing well below render time
  int crf = 18;
  std::string bitrate;               ///< e.g. "4M"; replaces --crf
  std::string contact_sheet;         ///< PNG of thumbnails, "" = none
  std::string sheet_grid = "4x4";    ///< COLSxROWS of the contact sheet
  std::string hash_file;             ///< --hash FILE.json, "" = none
  int hash_every = 1;
  bool overlay = false;              ///< frame number and time drawn onto written frames
  bool sync_writes = false;          ///< write outputs on the render thread (for measurements)
  bool quiet = false;
  /// --cache DIR: restore each frame from a `simreel bake` cache instead of simulating.
  std::string cache;
};

/// `simreel bake`: the engine state per frame into a cache folder (sim_cache.hpp).
struct BakeOptions : RunOptions {
  std::string cache;    ///< --cache DIR
  bool resume = false;  ///< continue from the last complete frame of DIR
  bool ply = false;     ///< also DIR/ply/*.ply per frame (particles, cloth)
  bool quiet = false;
};

struct CheckOptions {
  /// Golden files, or folders searched (recursively, in name order) for JSON files that hold
  /// "simreel_hashes".
  std::vector<std::string> goldens;
  std::optional<int> tolerance;  ///< overrides every kind's tolerance
  bool update = false;
  std::string out_dir;           ///< where comparison images go on mismatch ("" = nowhere)
  std::optional<std::string> backend;
  bool allow_outside = false;    ///< the golden's scene may lie outside the golden's folder
  /// Folders trusted to hold the scenes of format-2 goldens besides each golden's folder and the
  /// working directory (--root).
  std::vector<std::string> roots;
  std::string junit;             ///< --junit FILE.xml, "" = none
  std::string report_dir;        ///< --report DIR: index.html + images of failing frames
};

/// `simreel sweep`: every combination of the --vary values (and --seeds) rendered by child
/// processes, laid out in one labelled contact sheet.
struct SweepOptions : RunOptions {
  std::vector<std::string> vary;     ///< "POINTER=V1,V2,..." (values read as JSON; commas inside [] {} "" kept)
  std::string seeds;                 ///< "1,2,3": one more axis, "" = none
  std::string contact_sheet;         ///< the sheet (PNG), required
  std::string output_dir;            ///< -o DIR: each variant's video DIR/NN_<values>.mp4, "" = none
  bool hash = false;                 ///< also a golden per variant, DIR/NN_<values>.json
  int strip = 3;                     ///< frames per variant on the sheet, sampled evenly from the range
  std::optional<int> jobs;           ///< child processes at once (default: the core count)
};

/// Exit codes: 0, 1, 2 as above; 130 (128 + SIGINT) or 143 (SIGTERM) when interrupted, after
/// finishing the frame being made and closing every output so that it plays.
int render_command(const RenderOptions& options);
/// 0 baked; 2 bad options, scene, or a cache that --resume cannot continue (names the file and
/// what differs); 1 a run-time failure (disk full, diverged).
int bake_command(const BakeOptions& options);
/// Re-renders what each golden hash record describes and compares hashes frame by frame; prints
/// "N passed, M failed". 0 all within tolerance (or updated), 1 a mismatch, 2 a bad golden file,
/// scene or path (the other goldens are still checked).
int check_command(const CheckOptions& options);
/// 0 the sheet (and videos, goldens) written; 1 a variant failed at run time; 2 bad options or a
/// variant's scene is not valid (checked before anything renders).
int sweep_command(const SweepOptions& options);
/// `simreel schema [-o FILE]`: the scene JSON Schema (draft 2020-12) on stdout or written atomically.
int schema_command(const std::string& output);
/// The schema's text (scene keys from the loader's readers, effect presets' knobs).
std::string scene_schema_text();
/// The CSV files `simreel simulate` writes (empty: not written); at least one is needed.
struct SimulateExports {
  std::string particles;  ///< --export: frame,time,system,id,x,y,z,vx,vy,vz
  std::string bodies;     ///< --export-bodies: frame,time,body,x,y,z,qw,qx,qy,qz,vx,vy,vz,wx,wy,wz
  std::string joints;     ///< --export-joints: frame,time,joint,anchor_error,fx,fy,fz,force,angle,twist,broken
};
int simulate_command(const RunOptions& options, const SimulateExports& exports);
int validate_command(const std::string& scene, const std::vector<std::string>& overrides);
/// algorithm: "phash", "dhash", "chash" or "all" (the three on one line).
int hash_command(const std::vector<std::string>& images, const std::string& algorithm);
/// `simreel presets [EFFECT] [--json]`: lists every effect and its knobs with type, default,
/// range and unit; with --json, prints a ready-to-paste emitter object with every knob at its
/// default; with --expand, prints the emitters and force fields the effect derives (with the
/// knobs of `sets`, "KNOB=VALUE") as scene JSON. Returns the exit code (2 for an unknown effect).
int presets_command(const std::string& effect, bool as_json, bool expand = false,
                    const std::vector<std::string>& sets = {});

}  // namespace simreel::app
