// Finding ffmpeg on PATH and listing its encoders (frame_sink.hpp, sinks/ffmpeg.hpp).
#include "ffmpeg.hpp"

#include <cctype>
#include <cerrno>
#include <cstdlib>
#include <string>
#include <vector>

#include <fcntl.h>
#include <spawn.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include "simreel/render/frame_sink.hpp"

extern char** environ;

namespace simreel::render {

namespace fs = std::filesystem;

namespace detail {

// An empty PATH entry means the current directory, as for execvp.
fs::path find_on_path(const std::string& program) {
  const char* env = std::getenv("PATH");
  const std::string path = env != nullptr ? env : "/usr/local/bin:/usr/bin:/bin";
  std::size_t start = 0;
  while (start <= path.size()) {
    std::size_t end = path.find(':', start);
    if (end == std::string::npos) end = path.size();
    const std::string dir = path.substr(start, end - start);
    const fs::path candidate = fs::path(dir.empty() ? "." : dir) / program;
    struct stat st {};
    if (::stat(candidate.c_str(), &st) == 0 && S_ISREG(st.st_mode) &&
        ::access(candidate.c_str(), X_OK) == 0) {
      return candidate;
    }
    start = end + 1;
  }
  return {};
}

}  // namespace detail

using detail::find_on_path;

bool ffmpeg_available() { return !find_on_path("ffmpeg").empty(); }

bool ffmpeg_has_encoder(const std::string& name) {
  const fs::path ffmpeg = find_on_path("ffmpeg");
  if (ffmpeg.empty()) return false;
  // The list is read through a pipe with no shell in between.
  int fds[2];
  if (::pipe2(fds, O_CLOEXEC) != 0) return false;
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, 0, "/dev/null", O_RDONLY, 0);
  posix_spawn_file_actions_adddup2(&actions, fds[1], 1);
  posix_spawn_file_actions_addopen(&actions, 2, "/dev/null", O_WRONLY, 0);
  const std::string program = ffmpeg.string();
  std::vector<std::string> args = {program, "-hide_banner", "-encoders"};
  std::vector<char*> argv;
  for (std::string& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  pid_t pid = 0;
  const int rc = ::posix_spawn(&pid, program.c_str(), &actions, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  ::close(fds[1]);
  std::string text;
  if (rc == 0) {
    char buf[4096];
    for (;;) {
      const ssize_t n = ::read(fds[0], buf, sizeof buf);
      if (n < 0 && errno == EINTR) continue;
      if (n <= 0) break;
      text.append(buf, std::size_t(n));
    }
    int status = 0;
    while (::waitpid(pid, &status, 0) < 0 && errno == EINTR) {
    }
  }
  ::close(fds[0]);
  // Lines look like " V....D libvpx-vp9           libvpx VP9 (codec vp9)".
  std::size_t pos = 0;
  while ((pos = text.find(name, pos)) != std::string::npos) {
    const bool starts = pos > 0 && text[pos - 1] == ' ';
    const std::size_t end = pos + name.size();
    const bool ends = end < text.size() && std::isspace(static_cast<unsigned char>(text[end])) != 0;
    if (starts && ends) return true;
    pos = end;
  }
  return false;
}

}  // namespace simreel::render
