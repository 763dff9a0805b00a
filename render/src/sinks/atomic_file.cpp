// The one atomic-write helper (atomic_file.hpp): temporary name, fsync, rename.
#include "simreel/render/atomic_file.hpp"

#include <fcntl.h>
#include <signal.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstring>
#include <functional>
#include <system_error>
#include <thread>

#include "simreel/render/image.hpp"

namespace simreel::render {

namespace fs = std::filesystem;

namespace {

[[noreturn]] void fail(const fs::path& path, const std::string& why) {
  throw IoError("cannot write " + path.string() + ": " + why);
}

// The hard-stop registry: open temporaries and the children writing them, read by
// remove_temporaries_now() from a signal handler, so only fixed arrays and atomics. A slot is
// free (0), being filled (1) or ready (2); the handler reads ready slots only.
constexpr int kTempSlots = 64;
constexpr std::size_t kTempPathMax = 4096;
std::atomic<int> g_temp_state[kTempSlots];
char g_temp_path[kTempSlots][kTempPathMax];
constexpr int kChildSlots = 16;
std::atomic<pid_t> g_children[kChildSlots];

int register_temporary(const fs::path& tmp) noexcept {
  const std::string& text = tmp.native();
  if (text.size() >= kTempPathMax) return -1;
  for (int i = 0; i < kTempSlots; ++i) {
    int expected = 0;
    if (!g_temp_state[i].compare_exchange_strong(expected, 1)) continue;
    std::memcpy(g_temp_path[i], text.c_str(), text.size() + 1);
    g_temp_state[i].store(2);
    return i;
  }
  return -1;  // more than 64 at once: still removed on every ordinary path
}

void unregister_temporary(int slot) noexcept {
  if (slot >= 0) g_temp_state[slot].store(0);
}

}  // namespace

void register_child(pid_t pid) noexcept {
  for (auto& c : g_children) {
    pid_t expected = 0;
    if (c.compare_exchange_strong(expected, pid)) return;
  }
}

void unregister_child(pid_t pid) noexcept {
  for (auto& c : g_children) {
    pid_t expected = pid;
    c.compare_exchange_strong(expected, 0);
  }
}

void remove_temporaries_now() noexcept {
  for (auto& c : g_children) {
    const pid_t pid = c.load();
    if (pid > 0) ::kill(-pid, SIGKILL);  // its own process group (the video sink spawns it so)
  }
  for (int i = 0; i < kTempSlots; ++i)
    if (g_temp_state[i].load() == 2) ::unlink(g_temp_path[i]);
}

void stop_by_signal(int signal) noexcept {
  remove_temporaries_now();
  struct sigaction dfl {};
  dfl.sa_handler = SIG_DFL;
  sigemptyset(&dfl.sa_mask);
  ::sigaction(signal, &dfl, nullptr);
  // Pending while this handler runs (the signal is blocked in it); delivered on return.
  ::raise(signal);
}

namespace {
extern "C" void on_signal_stop(int signal) { stop_by_signal(signal); }
}  // namespace

void remove_temporaries_on_signals() noexcept {
  for (const int signal : {SIGINT, SIGTERM, SIGHUP}) {
    struct sigaction old {};
    if (::sigaction(signal, nullptr, &old) != 0 || old.sa_handler == SIG_IGN) continue;
    struct sigaction action {};
    action.sa_handler = on_signal_stop;
    sigemptyset(&action.sa_mask);
    ::sigaction(signal, &action, nullptr);
  }
}

std::string make_parent_directories(const fs::path& path) {
  const fs::path dir = path.parent_path();
  if (dir.empty()) return "";
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (!ec) return "";
  // Name the component that is in the way: "out.csv/x.csv" has a file where a folder must be.
  for (fs::path p = dir; !p.empty(); p = p.parent_path()) {
    std::error_code e;
    const auto st = fs::status(p, e);
    if (fs::exists(st) && !fs::is_directory(st)) return p.string() + " is a file, expected a directory";
    if (p == p.parent_path()) break;
  }
  return "cannot create directory " + dir.string() + ": " + ec.message();
}

std::string file_kind(const fs::path& path) {
  std::error_code ec;
  const fs::file_status st = fs::status(path, ec);
  switch (st.type()) {
    case fs::file_type::none:
    case fs::file_type::not_found: return "";
    case fs::file_type::regular: return "a regular file";
    case fs::file_type::directory: return "a directory";
    case fs::file_type::character: return "a character device";
    case fs::file_type::block: return "a block device";
    case fs::file_type::fifo: return "a FIFO";
    case fs::file_type::socket: return "a socket";
    default: return "not a regular file";
  }
}

std::string unreplaceable_output(const fs::path& path) {
  const std::string kind = file_kind(path);
  if (kind.empty() || kind == "a regular file") return "";
  // Renaming the finished temporary over it would replace the device or FIFO itself (as root,
  // `--hash /dev/full` turned /dev/full into a JSON file), not write into it.
  return "is " + kind + ", expected a regular file or a new name";
}

AtomicFile::AtomicFile(fs::path path) : path_(std::move(path)), target_(path_) {
  if (const std::string problem = unreplaceable_output(path_); !problem.empty()) fail(path_, problem);
  {
    // A link to a regular file: replace the file, keep the link (a rename over the link would
    // turn it into a copy and leave the file it named stale).
    std::error_code ec;
    if (fs::is_symlink(fs::symlink_status(path_, ec)) && fs::is_regular_file(path_, ec)) {
      const fs::path real = fs::canonical(path_, ec);
      if (!ec) target_ = real;
    }
  }
  const fs::path dir = target_.parent_path();
  if (const std::string problem = make_parent_directories(target_); !problem.empty()) fail(path_, problem);
  // Built piecewise: GCC 12 warns falsely on "." + string&&.
  std::string name = ".";
  name += target_.filename().string();
  name += ".tmp-";
  name += std::to_string(long(::getpid()));
  name += "-";
  name += std::to_string(std::hash<std::thread::id>{}(std::this_thread::get_id()) % 1000000);
  tmp_ = dir / name;
  // "e" (glibc: O_CLOEXEC): a child spawned meanwhile (ffmpeg, another sink's) must not keep
  // the temporary open.
  // Registered before it exists: a signal from here on removes it (unlinking a name not yet
  // created is harmless), so none can come between the open and the registration and leave it.
  slot_ = register_temporary(tmp_);
  file_ = std::fopen(tmp_.c_str(), "wbe");
  if (file_ == nullptr) {
    const int err = errno;
    unregister_temporary(slot_);
    slot_ = -1;
    fail(path_, std::strerror(err));
  }
}

AtomicFile::~AtomicFile() {
  if (!done_) discard();
}

void AtomicFile::write(std::string_view bytes) {
  if (file_ == nullptr) fail(path_, "file already closed");
  if (std::fwrite(bytes.data(), 1, bytes.size(), file_) != bytes.size()) {
    const int err = errno;
    discard();
    fail(path_, err != 0 ? std::strerror(err) : "write failed (disk full?)");
  }
}

void AtomicFile::commit() {
  if (done_) fail(path_, "file already committed or discarded");
  std::string error;
  if (file_ != nullptr) {
    // fsync before rename: after a power loss the final name holds the old file or the whole
    // new one, never an empty one.
    const bool flushed = std::fflush(file_) == 0 && ::fsync(::fileno(file_)) == 0;
    const int err = errno;
    const bool closed = std::fclose(file_) == 0;
    file_ = nullptr;
    if (!flushed || !closed) error = err != 0 ? std::strerror(err) : "write failed (disk full?)";
  }
  std::error_code ec;
  if (error.empty()) {
    fs::rename(tmp_, target_, ec);
    if (ec) error = ec.message();
  }
  if (error.empty()) {
    unregister_temporary(slot_);
    slot_ = -1;
  }
  if (!error.empty()) {
    discard();
    fail(path_, error);
  }
  done_ = true;
}

void AtomicFile::discard() noexcept {
  if (file_ != nullptr) std::fclose(file_);
  file_ = nullptr;
  std::error_code ec;
  if (!tmp_.empty()) fs::remove(tmp_, ec);
  unregister_temporary(slot_);
  slot_ = -1;
  done_ = true;
}

void write_file_atomic(const fs::path& path, std::string_view bytes) {
  AtomicFile f(path);
  f.write(bytes);
  f.commit();
}

}  // namespace simreel::render
