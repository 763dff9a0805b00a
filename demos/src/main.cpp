// simreel: headless physics animations. JSON scene in; PNG frames, video, CSV state, hashes out.
#include <CLI/CLI.hpp>

#include <iostream>

#include "commands.hpp"
#include "json_reader.hpp"
#include "simreel/render/context.hpp"
#include "simreel/render/image.hpp"
#include "simreel/sim/world.hpp"

namespace {

void add_run_options(CLI::App* cmd, simreel::app::RunOptions& o) {
  cmd->add_option("scene", o.scene, "Scene file (JSON)")->required();
  cmd->add_option("--frames", o.frames, "Number of frames (overrides the scene's \"frames\")");
  cmd->add_option("--fps", o.fps, "Frames per second; the sampling time is 1/fps");
  cmd->add_option("--seed", o.seed, "Random seed (overrides the scene's \"seed\")");
  cmd->add_option("--set", o.overrides,
                  "Override a scene value by JSON pointer, e.g. --set /emitters/0/rate=500 "
                  "(VALUE is read as JSON; a bare word is a string)")
      ->take_all()
      ->allow_extra_args(false);
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"simreel: physics animations without a display"};
  app.require_subcommand(1);
  app.set_version_flag("--version", std::string("simreel ") + SIMREEL_VERSION);

  simreel::app::RenderOptions render_opts;
  auto* render = app.add_subcommand("render", "Simulate a scene and render its frames to PNG and/or video");
  add_run_options(render, render_opts);
  render->add_option("-o,--output", render_opts.outputs,
                     "Output: a directory (PNG frames frame_00000.png...) or a .mp4/.gif file; repeatable "
                     "(default: out/<scene>/ and out/<scene>.mp4)");
  render->add_option("--size", render_opts.size, "Frame size WIDTHxHEIGHT, e.g. 1280x720");
  render->add_option("--backend", render_opts.backend, "OpenGL context: osmesa (default) or egl");
  render->add_option("--png-compression", render_opts.png_compression, "zlib level for PNG frames (0-9)")
      ->check(CLI::Range(0, 9));
  render->add_option("--crf", render_opts.crf, "H.264 quality for MP4 (0-51, lower is better)")->check(CLI::Range(0, 51));
  render->add_flag("-q,--quiet", render_opts.quiet, "No progress line");

  simreel::app::RunOptions sim_opts;
  std::string export_csv;
  auto* simulate = app.add_subcommand("simulate", "Simulate without rendering and export particle state as CSV");
  add_run_options(simulate, sim_opts);
  simulate->add_option("--export", export_csv, "CSV file: frame,time,system,id,x,y,z,vx,vy,vz (SI units)")
      ->required();

  std::string validate_scene;
  std::vector<std::string> validate_overrides;
  auto* validate = app.add_subcommand("validate", "Load and check a scene; print ok or every error");
  validate->add_option("scene", validate_scene, "Scene file (JSON)")->required();
  validate->add_option("--set", validate_overrides, "Override a scene value by JSON pointer")->take_all();

  std::vector<std::string> images;
  std::string algorithm = "phash";
  auto* hash = app.add_subcommand("hash", "Print a 64-bit perceptual hash (16 hex digits) of each image");
  hash->add_option("images", images, "PNG/JPEG images")->required();
  hash->add_option("--algorithm", algorithm, "phash (DCT, default) or dhash")
      ->check(CLI::IsMember({"phash", "dhash"}));

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
    if (simulate->parsed()) return simreel::app::simulate_command(sim_opts, export_csv);
    if (validate->parsed()) return simreel::app::validate_command(validate_scene, validate_overrides);
    if (hash->parsed()) return simreel::app::hash_command(images, algorithm);
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
