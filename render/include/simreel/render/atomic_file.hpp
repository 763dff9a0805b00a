#pragma once
/// @file atomic_file.hpp
/// The one way simreel writes a file: to a temporary name in the target's directory, flushed and
/// fsync'ed, then renamed over the final name. A reader (or a crash, a full disk, a Ctrl-C) never
/// sees a half-written file under the final name. Used by every writer: PNG frames, contact
/// sheets, videos (ffmpeg writes the temporary), CSV exports and golden JSON.

#include <sys/types.h>

#include <cstdio>
#include <filesystem>
#include <string>
#include <string_view>

namespace simreel::render {

/// A file being written atomically. The temporary is `.NAME.tmp-PID-TID` beside the final path
/// (same directory, so the rename cannot cross file systems). Destroying an AtomicFile that was
/// not committed removes the temporary; the final name is never touched.
class AtomicFile {
 public:
  /// Creates the parent directory if missing and opens the temporary for writing (close-on-exec,
  /// so child processes such as ffmpeg do not inherit it). A `path` that is a symbolic link to a
  /// regular file is written through: the file it names is replaced and the link kept.
  /// @throws IoError naming `path` and the system's reason, or unreplaceable_output()'s.
  explicit AtomicFile(std::filesystem::path path);
  ~AtomicFile();
  AtomicFile(const AtomicFile&) = delete;
  AtomicFile& operator=(const AtomicFile&) = delete;

  /// The open temporary (for writers that need a FILE*); null after commit/discard.
  [[nodiscard]] std::FILE* file() const { return file_; }
  /// The temporary's path (for a child process that writes it, e.g. ffmpeg).
  [[nodiscard]] const std::filesystem::path& temporary() const { return tmp_; }
  [[nodiscard]] const std::filesystem::path& path() const { return path_; }

  /// Appends bytes. @throws IoError naming the final path (e.g. disk full).
  void write(std::string_view bytes);
  /// Flushes, fsyncs and closes the temporary, then renames it to the final name. For a
  /// temporary written by another process (ffmpeg), call it after that process exited: the
  /// fsync covers the file's data whoever wrote it.
  /// @throws IoError naming the final path; the temporary is removed.
  void commit();
  /// Closes and removes the temporary; the final name is untouched. Never throws.
  void discard() noexcept;

 private:
  std::filesystem::path path_;
  std::filesystem::path target_;  ///< what the rename replaces: path_, or the file its links name
  std::filesystem::path tmp_;
  std::FILE* file_ = nullptr;
  bool done_ = false;
  int slot_ = -1;  ///< in the hard-stop registry (remove_temporaries_now)
};

/// For a signal handler's hard stop (a second Ctrl-C): kills the process group of every
/// registered child (ffmpeg writing a video's temporary) and unlinks every AtomicFile temporary
/// not yet committed or discarded. Async-signal-safe; the caller then re-raises the signal.
void remove_temporaries_now() noexcept;
/// Ends the program by `signal` after remove_temporaries_now(): restores the signal's default
/// action and re-raises it, so the exit status still names the signal (130 in a shell for
/// SIGINT). Async-signal-safe; for a signal handler's hard stop.
void stop_by_signal(int signal) noexcept;
/// Installs stop_by_signal as the handler of SIGINT, SIGTERM and SIGHUP, so that a program
/// interrupted anywhere, in any command, leaves no temporary and no ffmpeg child behind. A
/// signal the parent set to be ignored (nohup, a background job) stays ignored. Commands that
/// stop more gently (render's first Ctrl-C) install their own handlers over it and restore it.
/// Call once at start-up, before any AtomicFile exists.
void remove_temporaries_on_signals() noexcept;
/// Registers a child process that leads its own process group (killed by
/// remove_temporaries_now); unregister it once reaped. Never throws; at most 16 at once.
void register_child(pid_t pid) noexcept;
void unregister_child(pid_t pid) noexcept;

/// Creates the directories above `path`; "" when they exist, otherwise why not, naming the
/// component that is a file where a directory is needed ("out/a.csv is a file, expected a
/// directory"). Never throws.
std::string make_parent_directories(const std::filesystem::path& path);

/// What is at `path` (following symbolic links), for messages: "a regular file", "a directory",
/// "a character device", "a block device", "a FIFO", "a socket", "not a regular file"; "" when
/// nothing is there. Never throws.
std::string file_kind(const std::filesystem::path& path);

/// Why `path` cannot be an AtomicFile's final name, or "" when it can (absent, or a regular file,
/// directly or through symbolic links). The rename would replace whatever is there, so a
/// directory, a device (/dev/null, /dev/stdout's terminal or pipe), a FIFO or a socket is refused:
/// "is a character device, expected a regular file or a new name". Never throws.
std::string unreplaceable_output(const std::filesystem::path& path);

/// Writes `bytes` to `path` atomically (AtomicFile). @throws IoError naming the path.
void write_file_atomic(const std::filesystem::path& path, std::string_view bytes);

}  // namespace simreel::render
