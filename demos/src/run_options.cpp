#include "run_options.hpp"
#include "simreel/sim/ranges.hpp"

#include "scene_read.hpp"

#include <unistd.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <limits>

#include "simreel/render/atomic_file.hpp"

#include <stdexcept>

namespace simreel::app {

std::pair<int, int> parse_frames(const std::string& text) {
  if (text.find_first_not_of("0123456789:") == std::string::npos) {
    if (const auto n = parse_integer(text, 1, kMaxFrames)) return {0, int(*n)};
    if (const auto r = parse_pair(text, ':', 0, kMaxFrames); r && r->first < r->second)
      return {int(r->first), int(r->second)};
  }
  throw SceneError("--frames " + text + ": expected a count N in [1, " + std::to_string(kMaxFrames) +
                   "] or a range A:B with 0 <= A < B <= " + std::to_string(kMaxFrames));
}

void check_outputs(const std::vector<OutputPath>& outputs) {
  namespace fs = std::filesystem;
  std::vector<std::pair<fs::path, const OutputPath*>> seen;
  for (const OutputPath& out : outputs) {
    if (out.path.empty()) continue;
    std::error_code ec;
    if (out.folder) {
      if (const std::string kind = render::file_kind(out.path); !kind.empty() && kind != "a directory")
        throw SceneError(out.option + " " + out.path + ": is " + kind + ", expected a folder or a new name");
    } else if (const std::string why = render::unreplaceable_output(out.path); !why.empty()) {
      throw SceneError(out.option + " " + out.path + ": " + why);
    }
    // The nearest folder above it that exists must be a folder: under a regular file (-o
    // notes.txt/frames) the output could only fail once the render had started.
    for (fs::path up = fs::path(out.path).parent_path(); !up.empty(); up = up.parent_path()) {
      const std::string kind = render::file_kind(up);
      if (kind.empty()) {  // (not there: its own parent decides)
        if (up == up.parent_path()) break;
        continue;
      }
      if (kind != "a directory")
        throw SceneError(out.option + " " + out.path + ": " + up.string() + " is " + kind + ", expected a folder");
      break;
    }
    // Same path however spelled ("a.gif", "./a.gif", a link to it).
    fs::path key = fs::weakly_canonical(fs::absolute(out.path, ec), ec);
    if (ec) key = fs::absolute(out.path).lexically_normal();
    for (const auto& [other, first] : seen)
      if (other == key)
        throw SceneError(out.option + " " + out.path + ": the same path as " + first->option + " " + first->path +
                         "; expected a different name for each output");
    seen.emplace_back(key, &out);
  }
}

namespace {

// Rough costs, on the high side: a particle's engine arrays (SoA: position, velocity, force,
// mass, radius, age, lifespan, colour, id, split depth), its renderer upload and the views; a
// cloth vertex with its springs and the implicit solver's 3x3 blocks; a pixel's multisampled
// colour and depth per sample plus the resolve, post-processing and writer-queue images.
constexpr std::uint64_t kBytesPerParticle = 192;
constexpr std::uint64_t kBytesPerClothVertex = 2048;
constexpr std::uint64_t kBytesPerSample = 8;
constexpr std::uint64_t kBytesPerPixel = 96;

std::string mib(std::uint64_t bytes) { return std::to_string((bytes + (1u << 20) - 1) >> 20) + " MiB"; }

}  // namespace

MemoryEstimate estimate_memory(const Scene& scene, bool renders) {
  MemoryEstimate m;
  auto add = [&m](std::string what, std::uint64_t bytes) {
    m.bytes += bytes;
    m.items.emplace_back(std::move(what), bytes);
  };
  for (std::size_t i = 0; i < scene.emitters.size(); ++i)
    add("/emitters/" + std::to_string(i) + "/max_particles",
        std::uint64_t(scene.emitters[i].system.emitter.max_particles) * kBytesPerParticle);
  for (std::size_t i = 0; i < scene.cloths.size(); ++i)
    add("/cloths/" + std::to_string(i) + "/rows, columns",
        std::uint64_t(scene.cloths[i].def.rows) * scene.cloths[i].def.columns * kBytesPerClothVertex);
  if (renders) {
    const std::uint64_t pixels = std::uint64_t(scene.render.width) * std::uint64_t(scene.render.height);
    const std::uint64_t samples = std::uint64_t(std::max(1, scene.render.msaa_samples));
    add("/render/width, height, msaa (or --size)", pixels * (samples * kBytesPerSample + kBytesPerPixel));
  }
  return m;
}

std::uint64_t memory_limit(const std::optional<std::string>& option) {
  std::string text;
  std::string source;
  if (option) {
    text = *option;
    source = "--memory-limit " + text;
  } else if (const char* env = std::getenv("SIMREEL_MEMORY_LIMIT"); env != nullptr && *env != '\0') {
    text = env;
    source = std::string("SIMREEL_MEMORY_LIMIT=") + env;
  } else {
    const long pages = ::sysconf(_SC_PHYS_PAGES);
    const long page = ::sysconf(_SC_PAGE_SIZE);
    if (pages <= 0 || page <= 0) return std::numeric_limits<std::uint64_t>::max();
    return std::uint64_t(pages) * std::uint64_t(page) / 2;
  }
  int shift = 0;
  if (!text.empty()) {
    switch (text.back()) {
      case 'k': case 'K': shift = 10; break;
      case 'm': case 'M': shift = 20; break;
      case 'g': case 'G': shift = 30; break;
      default: break;
    }
  }
  const auto n = parse_integer(shift != 0 ? std::string_view(text).substr(0, text.size() - 1) : std::string_view(text),
                               1, std::numeric_limits<long long>::max() >> shift);
  if (!n) throw SceneError(source + ": expected a number of bytes >= 1 with an optional K, M or G suffix, e.g. 8G");
  return std::uint64_t(*n) << shift;
}

void check_memory(const Scene& scene, const RunOptions& o) {
  const std::uint64_t limit = memory_limit(o.memory_limit);
  const MemoryEstimate m = estimate_memory(scene, o.renders);
  if (m.bytes <= limit) return;
  auto items = m.items;
  std::sort(items.begin(), items.end(), [](const auto& a, const auto& b) { return a.second > b.second; });
  std::string largest;
  for (std::size_t i = 0; i < items.size() && i < 3; ++i)
    largest += (i ? ", " : "") + items[i].first + " (" + mib(items[i].second) + ")";
  throw SceneError(scene.file + ": the scene needs about " + mib(m.bytes) + " of memory, expected at most " +
                   mib(limit) + " (--memory-limit, SIMREEL_MEMORY_LIMIT, default half the physical memory); "
                   "largest: " + largest);
}

Scene prepare_scene(const RunOptions& o, int* first) {
  Scene scene = load_scene(o.scene, o.overrides);
  if (first != nullptr) *first = 0;
  if (o.frames) {
    const auto [a, b] = parse_frames(*o.frames);
    if (first != nullptr) *first = a;
    scene.frames = b;
  }
  if (o.fps) {
    if (!(*o.fps > 0.0 && *o.fps <= 1000.0))
      throw SceneError("--fps " + sim::format_number(*o.fps) + ": expected a number in (0, 1000]");
    if (std::string m = scene_read::steps_per_frame_problem(*o.fps, scene.world.max_step); !m.empty())
      throw SceneError("--fps " + sim::format_number(*o.fps) + " with " + scene.file + ": /simulation/max_step: " + m);
    scene.fps = *o.fps;
  }
  if (o.seed) {
    if (*o.seed < 0) throw SceneError("--seed " + std::to_string(*o.seed) + ": expected an integer >= 0");
    scene.seed = std::uint64_t(*o.seed);
  }
  if (o.size) {
    std::string size = *o.size;
    for (char& c : size) c = c == 'X' ? 'x' : c;
    const auto wh = parse_pair(size, 'x', 16, 8192);
    if (!wh) throw SceneError("--size " + *o.size + ": expected WIDTHxHEIGHT with each in [16, 8192], e.g. 1280x720");
    scene.render.width = int(wh->first);
    scene.render.height = int(wh->second);
  }
  if (o.backend) {
    try {
      scene.backend = render::parse_backend(*o.backend);
    } catch (const std::invalid_argument&) {
      throw SceneError("--backend " + *o.backend + ": expected osmesa or egl");
    }
  }
  if (o.threads) {
    if (*o.threads < 0 || *o.threads > 1024)
      throw SceneError("--threads " + std::to_string(*o.threads) + ": expected an integer in [0, 1024] (0 = all cores)");
    scene.world.threads = *o.threads;
  }
  check_memory(scene, o);
  return scene;
}

}  // namespace simreel::app
