// simreel: headless physics animations. JSON scene in; PNG frames, video, CSV state, hashes out.
#include <CLI/CLI.hpp>

#include <iostream>

#include "commands.hpp"
#include "effect_scene.hpp"
#include "json_reader.hpp"
#include "simreel/render/atomic_file.hpp"
#include "simreel/render/context.hpp"
#include "simreel/render/image.hpp"
#include "simreel/sim/world.hpp"

namespace {

void add_run_options(CLI::App* cmd, simreel::app::RunOptions& o) {
  cmd->add_option("scene", o.scene, "Scene file (JSON)")->required();
  cmd->add_option("--frames", o.frames,
                  "N: frames 0..N-1 (overrides the scene's \"frames\"); A:B: simulate from frame 0 but output "
                  "only frames A..B-1");
  cmd->add_option("--fps", o.fps, "Frames per second; the sampling time is 1/fps");
  cmd->add_option("--seed", o.seed, "Random seed (overrides the scene's \"seed\")");
  cmd->add_option("--set", o.overrides,
                  "Override a scene value by JSON pointer, e.g. --set /emitters/0/rate=500 "
                  "(VALUE is read as JSON; a bare word is a string)")
      ->take_all()
      ->allow_extra_args(false);
  cmd->add_option("--threads", o.threads,
                  "Simulation threads (overrides simulation.threads; 0 = all cores); results are identical at any count");
  cmd->add_option("--memory-limit", o.memory_limit,
                  "Refuse scenes whose estimated memory exceeds this many bytes (K, M, G suffixes; default "
                  "$SIMREEL_MEMORY_LIMIT or half the physical memory)");
}

}  // namespace

int main(int argc, char** argv) {
  // Before anything can create a temporary: a signal in any command (bake's state files, a
  // golden, a report) removes the temporaries and ffmpeg children, then ends the program.
  simreel::render::remove_temporaries_on_signals();
  CLI::App app{"simreel: physics animations without a display"};
  app.require_subcommand(1);
  app.set_version_flag("--version", std::string("simreel ") + SIMREEL_VERSION);

  simreel::app::RenderOptions render_opts;
  auto* render = app.add_subcommand("render", "Simulate a scene and render its frames to PNG and/or video");
  add_run_options(render, render_opts);
  render->add_option("-o,--output", render_opts.outputs,
                     "Output: a directory (PNG frames frame_00000.png...) or a .mp4/.webm/.gif file; repeatable "
                     "(default: out/<scene>/ and out/<scene>.mp4)");
  render->add_option("--size", render_opts.size, "Frame size WIDTHxHEIGHT, e.g. 1280x720");
  render->add_option("--backend", render_opts.backend, "OpenGL context: osmesa (default) or egl");
  render->add_option("--png-compression", render_opts.png_compression,
                     "zlib level for PNG frames (0-9, default 1: fastest useful; 6-9 halve the files at 4-20x the time)")
      ->check(CLI::Range(0, 9));
  render->add_option("--crf", render_opts.crf, "Constant quality for MP4 (H.264, 0-51) and WebM (VP9, 0-63); lower is better")
      ->check(CLI::Range(0, 63));
  render->add_option("--bitrate", render_opts.bitrate, "Target video bit rate instead of --crf, e.g. 4M or 800k");
  render->add_option("--contact-sheet", render_opts.contact_sheet,
                     "Also write one PNG of thumbnails sampled evenly from the rendered frames, labelled with frame numbers");
  render->add_option("--sheet", render_opts.sheet_grid, "Contact sheet grid COLSxROWS (default 4x4)");
  render->add_option("--hash", render_opts.hash_file,
                     "Write the phash/dhash/chash of the rendered frames and how they were made to FILE.json (a golden "
                     "for `simreel check`)");
  render->add_option("--hash-every", render_opts.hash_every, "Hash every K-th frame of the range (default 1)");
  render->add_flag("--overlay", render_opts.overlay, "Draw the frame number and time onto PNG/video/sheet frames");
  render->add_flag("--sync-writes", render_opts.sync_writes,
                   "Write outputs on the render thread instead of writer threads (for measurements)");
  render->add_flag("-q,--quiet", render_opts.quiet, "No progress line");
  render->add_option("--cache", render_opts.cache,
                     "Restore each frame from this `simreel bake` folder instead of simulating (same scene, --set, "
                     "--seed and --fps as the bake); frames are byte-identical to a straight render");

  simreel::app::BakeOptions bake_opts;
  auto* bake = app.add_subcommand("bake", "Simulate once and write the complete engine state per frame into a cache folder");
  add_run_options(bake, bake_opts);
  bake->add_option("--cache", bake_opts.cache, "Cache folder (manifest.json, state/frame_NNNNN.state, ply/)")->required();
  bake->add_flag("--resume", bake_opts.resume,
                 "Continue a killed bake from its last complete frame (the result is byte-identical to an "
                 "uninterrupted bake)");
  bake->add_flag("--ply", bake_opts.ply,
                 "Also write each frame's particles and cloth as binary PLY (ply/system<I>.<FRAME>.ply, "
                 "ply/cloth<I>.<FRAME>.ply) for Blender, Houdini, MeshLab, Open3D");
  bake->add_flag("-q,--quiet", bake_opts.quiet, "No progress line");

  simreel::app::SweepOptions sweep_opts;
  auto* sweep = app.add_subcommand("sweep", "Render every combination of scene values (a wedge) into one labelled sheet");
  add_run_options(sweep, sweep_opts);
  sweep->add_option("--vary", sweep_opts.vary,
                    "POINTER=V1,V2,...: values of one scene value to try (read as JSON); repeatable, every "
                    "combination is rendered")
      ->take_all();
  sweep->add_option("--seeds", sweep_opts.seeds, "Seeds to try, e.g. 1,2,3 (one more axis)");
  sweep->add_option("--contact-sheet", sweep_opts.contact_sheet,
                    "The sheet: the last axis across, the others down, labelled with their values")
      ->required();
  sweep->add_option("--strip", sweep_opts.strip, "Frames per variant on the sheet, evenly from the range (default 3)");
  sweep->add_option("--size", sweep_opts.size, "Frame size WIDTHxHEIGHT of every variant, e.g. 320x180");
  sweep->add_option("--backend", sweep_opts.backend, "OpenGL context: osmesa (default) or egl");
  sweep->add_option("-o,--output", sweep_opts.output_dir, "Also keep each variant's video as DIR/NN_<values>.mp4");
  sweep->add_flag("--hash", sweep_opts.hash, "Also write a golden per variant, DIR/NN_<values>.json (needs -o DIR)");
  sweep->add_option("--jobs", sweep_opts.jobs, "Variants rendered at once (default: the number of cores)");

  std::string schema_output;
  auto* schema = app.add_subcommand("schema", "Print the JSON Schema (draft 2020-12) of scene files, for editors");
  schema->add_option("-o,--output", schema_output, "Write it to FILE instead of stdout");

  simreel::app::RunOptions sim_opts;
  simreel::app::SimulateExports exports;
  auto* simulate = app.add_subcommand("simulate", "Simulate without rendering and export particle, body and joint state as CSV");
  add_run_options(simulate, sim_opts);
  auto* export_opt =
      simulate->add_option("--export", exports.particles, "CSV file: frame,time,system,id,x,y,z,vx,vy,vz (SI units)");
  auto* bodies_opt = simulate->add_option(
      "--export-bodies", exports.bodies,
      "CSV file, a row per frame per dynamic body: frame,time,body,x,y,z (m),qw,qx,qy,qz,vx,vy,vz (m/s),wx,wy,wz (rad/s)");
  auto* joints_opt = simulate->add_option(
      "--export-joints", exports.joints,
      "CSV file, a row per frame per joint: frame,time,joint,anchor_error (m),fx,fy,fz,force (N, on body b),angle,"
      "twist (rad),broken (0/1)");
  simulate->callback([&] {
    if (export_opt->count() + bodies_opt->count() + joints_opt->count() == 0)
      throw CLI::RequiredError("--export, --export-bodies or --export-joints");
  });

  std::string validate_scene;
  std::vector<std::string> validate_overrides;
  auto* validate = app.add_subcommand("validate", "Load and check a scene; print ok or every error");
  validate->add_option("scene", validate_scene, "Scene file (JSON)")->required();
  validate->add_option("--set", validate_overrides, "Override a scene value by JSON pointer")->take_all();

  std::vector<std::string> images;
  std::string algorithm = "phash";
  auto* hash = app.add_subcommand("hash", "Print a 64-bit perceptual hash (16 hex digits) of each image");
  hash->add_option("images", images, "PNG/JPEG images")->required();
  hash->add_option("--algorithm", algorithm, "phash (DCT, default), dhash, chash (colour layout) or all")
      ->check(CLI::IsMember({"phash", "dhash", "chash", "all"}));

  simreel::app::CheckOptions check_opts;
  std::string preset_name;
  bool preset_json = false;
  auto* presets = app.add_subcommand("presets", "List the effect presets (Coutinho §3.9.1) and their knobs with defaults");
  presets->add_option("effect", preset_name, "Only this effect");
  presets->add_flag("--json", preset_json, "Print an emitter object with every knob at its default, ready to paste");
  bool preset_expand = false;
  std::vector<std::string> preset_sets;
  presets->add_flag("--expand", preset_expand,
                    "Print the emitters and force fields the effect derives, as scene JSON (a base for \"overrides\")");
  presets->add_option("--set", preset_sets, "With --expand: set a knob, KNOB=VALUE (VALUE read as JSON)")->take_all();

  auto* check = app.add_subcommand("check", "Re-render what a golden hash file describes and compare frame hashes");
  check->add_option("goldens", check_opts.goldens,
                    "Golden files written by `render --hash` or `check --update`, or folders searched for them")
      ->required();
  check->add_option("--tolerance", check_opts.tolerance, "Largest Hamming distance accepted for every hash kind")
      ->check(CLI::Range(0, 64));
  check->add_flag("--update", check_opts.update,
                  "Rewrite the golden's hashes and its reference frames (GOLDEN.frames/NNNNN.png) from this run");
  check->add_option("--out", check_opts.out_dir, "On mismatch write expected | actual | difference images here");
  check->add_option("--backend", check_opts.backend, "OpenGL context (default: the golden's)");
  check->add_flag("--allow-outside", check_opts.allow_outside,
                  "Let the golden's scene path leave the golden's folder (absolute or with ..); off by default so "
                  "an untrusted golden cannot make check read other files");
  check->add_option("--root", check_opts.roots,
                    "Also trust scenes under this folder (besides each golden's folder and the working directory); "
                    "repeatable");
  check->add_option("--junit", check_opts.junit, "Write a JUnit XML file: one test case per golden");
  check->add_option("--report", check_opts.report_dir,
                    "Write DIR/index.html with expected | actual | difference images of every failing frame");

  render_opts.renders = true;
  sweep_opts.renders = true;
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForVersion& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    app.exit(e);
    return 2;
  }

  try {
    if (render->parsed()) return simreel::app::render_command(render_opts);
    if (bake->parsed()) return simreel::app::bake_command(bake_opts);
    if (schema->parsed()) return simreel::app::schema_command(schema_output);
    if (sweep->parsed()) return simreel::app::sweep_command(sweep_opts);
    if (simulate->parsed()) return simreel::app::simulate_command(sim_opts, exports);
    if (validate->parsed()) return simreel::app::validate_command(validate_scene, validate_overrides);
    if (hash->parsed()) return simreel::app::hash_command(images, algorithm);
    if (check->parsed()) return simreel::app::check_command(check_opts);
    if (presets->parsed()) return simreel::app::presets_command(preset_name, preset_json, preset_expand, preset_sets);
  } catch (const simreel::app::SceneError& e) {
    for (const auto& m : e.messages()) std::cerr << "simreel: error: " << m << "\n";
    return 2;
  } catch (const simreel::render::ContextError& e) {
    std::cerr << "simreel: " << e.what() << "\n";
    return 1;
  } catch (const simreel::render::IoError& e) {
    std::cerr << "simreel: " << e.what() << "\n";
    return 1;
  } catch (const simreel::sim::NonFiniteState& e) {
    std::cerr << "simreel: simulation diverged: " << e.what() << "\n";
    return 1;
  } catch (const std::exception& e) {
    std::cerr << "simreel: " << e.what() << "\n";
    return 1;
  }
  return 2;
}
