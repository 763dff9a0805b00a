// `simreel sweep`: render every combination of a few scene values (and seeds) in parallel child
// processes and lay the results out in one labelled contact sheet, like Houdini's Wedge.
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <fcntl.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <csignal>
#include <cstring>
#include <limits>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <map>
#include <optional>
#include <thread>

#include "commands.hpp"
#include "simreel/sim/ranges.hpp"
#include "json_reader.hpp"
#include "run_options.hpp"
#include "signal_scope.hpp"
#include "simreel/render/atomic_file.hpp"
#include "simreel/render/image.hpp"
#include "simreel/render/text_overlay.hpp"

extern char** environ;

namespace simreel::app {

namespace fs = std::filesystem;

namespace {

/// The most variants one sweep renders.
constexpr std::size_t kMaxVariants = 256;

/// One varied value: "/emitters/0/rate" with its values as given ("200", "[1,2,3]").
struct Axis {
  std::string pointer;
  std::string label;  ///< shown on the sheet: the pointer's last token, or the pointer if ambiguous
  std::vector<std::string> values;
  bool seed = false;  ///< the --seeds axis
};

/// Splits "V1,V2,..." at the commas outside brackets, braces and strings.
std::vector<std::string> split_values(const std::string& text) {
  std::vector<std::string> out;
  std::string cur;
  int depth = 0;
  bool in_string = false;
  for (std::size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    if (in_string) {
      if (c == '\\' && i + 1 < text.size()) cur += text[i++];
      else if (c == '"') in_string = false;
    } else if (c == '"') {
      in_string = true;
    } else if (c == '[' || c == '{') {
      ++depth;
    } else if (c == ']' || c == '}') {
      --depth;
    } else if (c == ',' && depth == 0) {
      out.push_back(cur);
      cur.clear();
      continue;
    }
    cur += c;
  }
  out.push_back(cur);
  return out;
}

Axis parse_vary(const std::string& text) {
  const auto eq = text.find('=');
  if (eq == std::string::npos || eq == 0 || text.front() != '/')
    throw SceneError("--vary " + text + ": expected POINTER=V1,V2,... with a JSON pointer, e.g. /emitters/0/rate=100,200,400");
  Axis a;
  a.pointer = text.substr(0, eq);
  a.values = split_values(text.substr(eq + 1));
  for (const auto& v : a.values)
    if (v.empty()) throw SceneError("--vary " + text + ": expected a value between every two commas, found an empty one");
  // The label: the tokens after the last array index ("/emitters/0/start_speed/mean" ->
  // "start_speed/mean"), or the whole pointer without its leading '/'.
  std::size_t from = 1;
  for (std::size_t i = 1; i < a.pointer.size();) {
    const std::size_t next = std::min(a.pointer.find('/', i), a.pointer.size());
    const std::string token = a.pointer.substr(i, next - i);
    if (!token.empty() && token.find_first_not_of("0123456789") == std::string::npos) from = next + 1;
    i = next + 1;
  }
  a.label = from < a.pointer.size() ? a.pointer.substr(from) : a.pointer.substr(1);
  return a;
}

/// Text safe in a file name: letters, digits, '.', '-'; everything else '_'.
std::string file_safe(const std::string& text) {
  std::string out;
  for (const char c : text) {
    const bool plain = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '.' || c == '-';
    out += plain ? c : '_';
  }
  return out.size() > 40 ? out.substr(0, 40) : out;
}

struct Variant {
  std::vector<std::size_t> index;  ///< one value index per axis
  std::vector<std::string> sets;   ///< "--set" assignments of the varied values
  std::optional<long long> seed;
  std::string name;                ///< "03_rate-400_seed-2": file stem of its video and golden
  std::string label;               ///< "rate=400 seed=2"
};

/// A temporary folder removed (with what is in it) when the sweep ends, however it ends.
struct TempFolder {
  fs::path path;
  TempFolder() {
    std::string tmpl = (fs::temp_directory_path() / "simreel-sweep-XXXXXX").string();
    if (::mkdtemp(tmpl.data()) == nullptr) throw render::IoError("cannot create a temporary folder in " + fs::temp_directory_path().string());
    path = tmpl;
  }
  ~TempFolder() {
    std::error_code ec;
    fs::remove_all(path, ec);
  }
  TempFolder(const TempFolder&) = delete;
  TempFolder& operator=(const TempFolder&) = delete;
};

// A signal to the sweep is passed on to every running child, which stops as `render` does (the
// first finishes its frame, a second stops at once and removes its temporaries); the sweep starts
// no more, waits for them, removes its scratch folder and then ends by the signal. The children
// lead their own process groups, so a Ctrl-C at the terminal reaches each once, through the
// sweep; before, a SIGTERM to the sweep alone left them running and the scratch folder behind.
volatile std::sig_atomic_t g_sweep_signal = 0;
std::atomic<pid_t> g_sweep_children[kMaxVariants];  // by variant index; 0 when not running

extern "C" void on_sweep_signal(int signal) {
  g_sweep_signal = signal;
  for (auto& child : g_sweep_children) {
    const pid_t pid = child.load();
    if (pid > 0) ::kill(pid, signal);
  }
}

/// Starts `args` (argv[0] = this program) with stdout and stderr into `log`, leading its own
/// process group; returns its pid.
pid_t spawn_child(const std::vector<std::string>& args, const fs::path& log) {
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, STDIN_FILENO, "/dev/null", O_RDONLY, 0);
  posix_spawn_file_actions_addopen(&actions, STDOUT_FILENO, log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_adddup2(&actions, STDOUT_FILENO, STDERR_FILENO);
  std::vector<char*> argv;
  for (const auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
  argv.push_back(nullptr);
  // One thread per child: the children run side by side on the cores (OpenMP and llvmpipe).
  std::vector<std::string> env_text = {"OMP_NUM_THREADS=1", "LP_NUM_THREADS=1"};
  std::vector<char*> envp;
  for (auto& e : env_text) envp.push_back(e.data());
  for (char** e = environ; *e != nullptr; ++e) {
    const std::string_view v(*e);
    if (v.rfind("OMP_NUM_THREADS=", 0) != 0 && v.rfind("LP_NUM_THREADS=", 0) != 0) envp.push_back(*e);
  }
  envp.push_back(nullptr);
  posix_spawnattr_t attributes;
  posix_spawnattr_init(&attributes);
  posix_spawnattr_setflags(&attributes, POSIX_SPAWN_SETPGROUP);
  posix_spawnattr_setpgroup(&attributes, 0);
  pid_t pid = -1;
  const int rc = posix_spawn(&pid, "/proc/self/exe", &actions, &attributes, argv.data(), envp.data());
  posix_spawnattr_destroy(&attributes);
  posix_spawn_file_actions_destroy(&actions);
  if (rc != 0) throw render::IoError("cannot start a simreel child process: " + std::string(std::strerror(rc)));
  return pid;
}

/// The last non-empty line of a child's log, for the one-line error.
std::string last_line(const fs::path& log) {
  std::string text;
  try {
    text = read_regular_file(log, "log", 1 << 20);
  } catch (const SceneError&) {
    return "";
  }
  while (!text.empty() && (text.back() == '\n' || text.back() == '\r')) text.pop_back();
  const auto nl = text.rfind('\n');
  std::string line = nl == std::string::npos ? text : text.substr(nl + 1);
  if (line.rfind("simreel: ", 0) == 0) line.erase(0, 9);
  return line;
}

void fill(render::Image& image, std::uint8_t grey) {
  for (std::size_t i = 0; i < image.rgba.size(); i += 4) {
    image.rgba[i] = image.rgba[i + 1] = image.rgba[i + 2] = grey;
    image.rgba[i + 3] = 255;
  }
}

/// Lays the variants' strips out in a grid: the last axis across, the others down; column
/// headers on top, row labels on the left, a title line above.
render::Image compose_sheet(const std::vector<Axis>& axes, const std::vector<Variant>& variants,
                            const std::vector<render::Image>& cells, const std::string& title) {
  const std::size_t cols = axes.back().values.size();
  const std::size_t rows = variants.size() / cols;
  int cw = 0, ch = 0;
  for (const auto& c : cells) {
    cw = std::max(cw, c.width);
    ch = std::max(ch, c.height);
  }
  render::TextStyle style;
  style.scale = cw >= 240 ? 2 : 1;
  style.background = {0, 0, 0, 0};
  const int gap = 4;
  auto header = [&](std::size_t col) { return axes.back().label + "=" + axes.back().values[col]; };
  auto row_label = [&](std::size_t row) {
    std::string text;
    const Variant& v = variants[row * cols];
    for (std::size_t a = 0; a + 1 < axes.size(); ++a)
      text.append(a > 0 ? "\n" : "").append(axes[a].label).append("=").append(axes[a].values[v.index[a]]);
    return text;
  };
  int label_w = 0;
  for (std::size_t r = 0; r < rows && axes.size() > 1; ++r)
    label_w = std::max(label_w, render::measure_text(row_label(r), style).width + 2 * gap);
  int header_h = 0;
  for (std::size_t c = 0; c < cols; ++c) header_h = std::max(header_h, render::measure_text(header(c), style).height + gap);
  const int title_h = render::measure_text(title, style).height + gap;
  const int width = std::max(label_w + int(cols) * (cw + gap) + gap, render::measure_text(title, style).width + 2 * gap);
  render::Image sheet(width, title_h + header_h + int(rows) * (ch + gap) + gap);
  fill(sheet, 24);
  render::TextStyle title_style = style;
  title_style.color = {255, 220, 120, 255};
  render::draw_text(sheet, gap, gap / 2, title, title_style);
  for (std::size_t c = 0; c < cols; ++c)
    render::draw_text(sheet, label_w + gap + int(c) * (cw + gap), title_h, header(c), style);
  for (std::size_t r = 0; r < rows; ++r) {
    const int y = title_h + header_h + gap + int(r) * (ch + gap);
    if (axes.size() > 1) render::draw_text(sheet, gap, y, row_label(r), style);
    for (std::size_t c = 0; c < cols; ++c) render::blit(sheet, cells[r * cols + c], label_w + gap + int(c) * (cw + gap), y);
  }
  return sheet;
}

}  // namespace

int sweep_command(const SweepOptions& o) {
  if (o.contact_sheet.empty()) throw SceneError("--contact-sheet: expected FILE.png, the sheet the sweep makes");
  if (fs::path(o.contact_sheet).extension() != ".png")
    throw SceneError("--contact-sheet " + o.contact_sheet + ": expected a .png file");
  if (o.vary.empty() && o.seeds.empty())
    throw SceneError("--vary: expected at least one --vary POINTER=V1,V2,... (or --seeds 1,2,3)");
  if (o.strip < 1 || o.strip > 16) throw SceneError("--strip " + std::to_string(o.strip) + ": expected 1..16 frames per variant");
  if (o.hash && o.output_dir.empty()) throw SceneError("--hash: expected -o DIR too (the goldens go there, one per variant)");
  check_outputs({{"--contact-sheet", o.contact_sheet, false}, {"-o", o.output_dir, true}});
  int jobs = o.jobs ? *o.jobs : int(std::max(1u, std::thread::hardware_concurrency()));
  if (jobs < 1 || jobs > 256) throw SceneError("--jobs " + std::to_string(jobs) + ": expected 1..256");

  std::vector<Axis> axes;
  for (const auto& v : o.vary) {
    axes.push_back(parse_vary(v));
    for (std::size_t i = 0; i + 1 < axes.size(); ++i)
      if (axes[i].pointer == axes.back().pointer) throw SceneError("--vary " + v + ": " + axes.back().pointer + " is varied twice");
  }
  for (auto& a : axes) {
    const bool ambiguous = std::count_if(axes.begin(), axes.end(), [&](const Axis& b) { return b.label == a.label; }) > 1;
    if (ambiguous) a.label = a.pointer;
  }
  if (!o.seeds.empty()) {
    Axis s;
    s.seed = true;
    s.label = "seed";
    for (const auto& v : split_values(o.seeds)) {
      if (!parse_integer(v, 0, std::numeric_limits<long long>::max()))
        throw SceneError("--seeds " + o.seeds + ": expected integers >= 0 separated by commas, found \"" + v + "\"");
      s.values.push_back(v);
    }
    axes.push_back(s);
  }
  std::size_t count = 1;
  for (const auto& a : axes) {
    count *= a.values.size();
    if (count > kMaxVariants)
      throw SceneError("--vary: " + std::to_string(count) + "+ combinations, expected at most " + std::to_string(kMaxVariants));
  }

  // Every combination, the last axis fastest; each is checked here before anything renders.
  std::vector<Variant> variants;
  std::uint64_t most_bytes = 0;  // the largest variant's memory estimate
  for (std::size_t n = 0; n < count; ++n) {
    Variant v;
    std::size_t rest = n;
    v.index.assign(axes.size(), 0);
    for (std::size_t a = axes.size(); a-- > 0;) {
      v.index[a] = rest % axes[a].values.size();
      rest /= axes[a].values.size();
    }
    char prefix[16];
    std::snprintf(prefix, sizeof prefix, "%02zu", n);
    v.name = prefix;
    for (std::size_t a = 0; a < axes.size(); ++a) {
      const std::string& value = axes[a].values[v.index[a]];
      if (axes[a].seed) v.seed = std::stoll(value);
      else v.sets.push_back(axes[a].pointer + "=" + value);
      if (a > 0) v.label.append(" ");
      v.label.append(axes[a].label).append("=").append(value);
      v.name.append("_").append(file_safe(axes[a].label));
      v.name.append("-").append(file_safe(value));
    }
    RunOptions run = o;
    for (const auto& s : v.sets) run.overrides.push_back(s);
    if (v.seed) run.seed = v.seed;
    run.renders = true;
    try {
      most_bytes = std::max(most_bytes, estimate_memory(prepare_scene(run), true).bytes);
    } catch (const SceneError& e) {
      std::vector<std::string> messages;
      for (const auto& m : e.messages()) messages.push_back("variant " + v.label + ": " + m);
      throw SceneError(messages);
    }
    variants.push_back(std::move(v));
  }
  // Each variant fits the memory budget alone (prepare_scene checked it); `jobs` of them at once
  // must fit it together, or a wide sweep of large frames runs the machine out of memory.
  std::string lowered;
  if (const std::uint64_t budget = memory_limit(o.memory_limit);
      most_bytes > 0 && std::uint64_t(jobs) * most_bytes > budget) {
    const int fit = int(std::max<std::uint64_t>(1, budget / most_bytes));
    lowered = " (--jobs " + std::to_string(jobs) + " lowered: a variant needs about " +
              std::to_string((most_bytes + (1u << 20) - 1) >> 20) + " MiB of the " + std::to_string(budget >> 20) +
              " MiB memory budget)";
    jobs = fit;
  }
  int first = 0, end = 0;
  {
    RunOptions run = o;
    run.renders = true;
    const Scene scene = prepare_scene(run, &first);
    end = scene.frames;
  }

  // Before the scratch folder exists, so that no signal can leave it behind.
  // Without SA_RESTART, so that waitpid returns at the signal.
  g_sweep_signal = 0;
  std::optional<SignalScope> signals(std::in_place, on_sweep_signal, std::initializer_list<int>{SIGINT, SIGTERM, SIGHUP},
                                     false);
  const TempFolder temp;
  std::vector<int> codes(variants.size(), -1);
  std::map<pid_t, std::size_t> running;
  std::size_t next = 0;
  auto cell_path = [&](std::size_t i) { return temp.path / ("cell_" + std::to_string(i) + ".png"); };
  auto log_path = [&](std::size_t i) { return temp.path / ("log_" + std::to_string(i) + ".txt"); };
  const std::string frames = std::to_string(first) + ":" + std::to_string(end);
  std::cout << "sweep: " << variants.size() << " variants of " << o.scene << ", frames " << frames << ", " << jobs
            << " at a time" << lowered << "\n";
  while ((next < variants.size() && g_sweep_signal == 0) || !running.empty()) {
    while (g_sweep_signal == 0 && next < variants.size() && int(running.size()) < jobs) {
      const Variant& v = variants[next];
      std::vector<std::string> args = {"simreel", "render", o.scene, "-q", "--threads", "1", "--frames", frames,
                                       "--contact-sheet", cell_path(next).string(),
                                       "--sheet", std::to_string(o.strip) + "x1"};
      for (const auto& s : o.overrides) args.insert(args.end(), {"--set", s});
      for (const auto& s : v.sets) args.insert(args.end(), {"--set", s});
      if (v.seed) args.insert(args.end(), {"--seed", std::to_string(*v.seed)});
      else if (o.seed) args.insert(args.end(), {"--seed", std::to_string(*o.seed)});
      if (o.fps) args.insert(args.end(), {"--fps", sim::exact_number(*o.fps)});
      if (o.size) args.insert(args.end(), {"--size", *o.size});
      if (o.backend) args.insert(args.end(), {"--backend", *o.backend});
      if (o.memory_limit) args.insert(args.end(), {"--memory-limit", *o.memory_limit});
      if (!o.output_dir.empty()) args.insert(args.end(), {"-o", (fs::path(o.output_dir) / (v.name + ".mp4")).string()});
      if (o.hash) args.insert(args.end(), {"--hash", (fs::path(o.output_dir) / (v.name + ".json")).string()});
      const pid_t child = spawn_child(args, log_path(next));
      running[child] = next;
      g_sweep_children[next].store(child);
      // A signal that came between the check above and the line before did not reach it.
      if (const int signal = g_sweep_signal; signal != 0) ::kill(child, signal);
      ++next;
    }
    int status = 0;
    const pid_t pid = ::waitpid(-1, &status, 0);
    if (pid < 0) {
      if (errno == EINTR) continue;
      break;
    }
    const auto it = running.find(pid);
    if (it == running.end()) continue;
    const std::size_t i = it->second;
    running.erase(it);
    g_sweep_children[i].store(0);
    codes[i] = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
    std::cout << (codes[i] == 0 ? "done " : g_sweep_signal != 0 ? "stopped " : "FAILED ") << variants[i].name << " ("
              << variants[i].label << ")\n"
              << std::flush;
  }
  signals.reset();
  if (const int signal = g_sweep_signal; signal != 0) {
    const auto done = std::count(codes.begin(), codes.end(), 0);
    std::cerr << "simreel: sweep interrupted by signal " << signal << ": " << done << " of " << variants.size()
              << " variants finished; no sheet written\n";
    std::error_code ec;
    fs::remove_all(temp.path, ec);
    render::stop_by_signal(signal);
  }
  int worst = 0;
  for (std::size_t i = 0; i < variants.size(); ++i) {
    if (codes[i] == 0) continue;
    std::cerr << "simreel: variant " << variants[i].label << " failed (exit " << codes[i] << "): " << last_line(log_path(i))
              << "\n";
    worst = std::max(worst, codes[i] == 2 ? 2 : 1);
  }
  if (worst != 0) return worst;

  std::vector<render::Image> cells;
  for (std::size_t i = 0; i < variants.size(); ++i) cells.push_back(render::read_image(cell_path(i)));
  const std::string title = fs::path(o.scene).filename().string() + "  frames " + frames + "  (" +
                            std::to_string(variants.size()) + " variants)";
  render::write_png(o.contact_sheet, compose_sheet(axes, variants, cells, title), 6);
  std::cout << "wrote " << o.contact_sheet << "\n";
  if (!o.output_dir.empty()) {
    for (const auto& v : variants) {
      std::cout << "wrote " << (fs::path(o.output_dir) / (v.name + ".mp4")).string() << "\n";
      if (o.hash) std::cout << "wrote " << (fs::path(o.output_dir) / (v.name + ".json")).string() << "\n";
    }
  }
  return 0;
}

}  // namespace simreel::app
