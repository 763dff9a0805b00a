#pragma once

#include <signal.h>
// Runs the simreel program as a user would and captures exit code, stdout and stderr.
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

namespace simreel::test {

/// A jet of big orange particles seen from close by (the effect fills a good part of the frame):
/// the scene the golden and workflow tests record and check.
inline const char* kGoldenScene = R"({
  "seed": 3, "fps": 30, "frames": 20,
  "camera": {"position": [1.5, -2.5, 0.9], "target": [0, 0, 0.6]},
  "colliders": [{"type": "plane", "restitution": 0.5}],
  "emitters": [{"name": "jet", "rate": 1500, "start_speed": {"mean": 4, "deviation": 0.3},
                "spread_deg": {"mean": 0, "deviation": 6}, "lifetime": 2, "position": [0, 0, 0.1],
                "particle_radius": 0.03,
                "color_over_lifetime": [{"t": 0, "color": [1, 0.5, 0.1, 1]}, {"t": 1, "color": [1, 0.3, 0.1, 1]}]}]
})";

inline int count_lines(const std::string& s) { return int(std::count(s.begin(), s.end(), '\n')); }

struct RunResult {
  int code = -1;
  std::string out;
  std::string err;
};

inline std::string slurp(const std::filesystem::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

/// For a forked child before it execs simreel: SIGINT, SIGTERM and SIGHUP at their default
/// actions and unblocked, as a Ctrl-C at a terminal finds them. simreel keeps a signal that its
/// parent ignores, and a test run started as a background job of a script inherits SIGINT
/// ignored: without this, a test that interrupts simreel would wait for it forever.
/// Async-signal-safe.
inline void default_signals_for_child() noexcept {
  sigset_t set;
  sigemptyset(&set);
  for (const int s : {SIGINT, SIGTERM, SIGHUP}) {
    struct sigaction dfl {};
    dfl.sa_handler = SIG_DFL;
    sigemptyset(&dfl.sa_mask);
    sigaction(s, &dfl, nullptr);
    sigaddset(&set, s);
  }
  sigprocmask(SIG_UNBLOCK, &set, nullptr);
}

/// A fresh temporary directory, removed by the destructor.
struct TempDir {
  std::filesystem::path path;
  TempDir() {
    std::string tmpl = (std::filesystem::temp_directory_path() / "simreel-test-XXXXXX").string();
    path = mkdtemp(tmpl.data());
  }
  ~TempDir() {
    std::error_code ec;
    std::filesystem::remove_all(path, ec);
  }
  std::filesystem::path operator/(const std::string& name) const { return path / name; }
};

/// `args` is appended to the program path as shell words (quote them yourself when needed).
inline RunResult run_simreel(const std::string& args, const std::string& env = "") {
  static int counter = 0;
  const auto dir = std::filesystem::temp_directory_path();
  const std::string tag = std::to_string(getpid()) + "-" + std::to_string(counter++);
  const auto out = dir / ("simreel-out-" + tag);
  const auto err = dir / ("simreel-err-" + tag);
  const std::string cmd = "cd " SIMREEL_SOURCE_DIR " && " + env + " " SIMREEL_BIN " " + args + " >" + out.string() +
                          " 2>" + err.string() + " </dev/null";
  const int status = std::system(cmd.c_str());
  RunResult r;
  r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  r.out = slurp(out);
  r.err = slurp(err);
  std::filesystem::remove(out);
  std::filesystem::remove(err);
  return r;
}

inline void write_file(const std::filesystem::path& p, const std::string& text) {
  std::ofstream(p, std::ios::binary) << text;
}

}  // namespace simreel::test
