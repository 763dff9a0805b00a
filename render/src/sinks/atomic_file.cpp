// The one atomic-write helper (atomic_file.hpp): temporary name, fsync, rename.
#include "simreel/render/atomic_file.hpp"

#include <fcntl.h>
#include <unistd.h>

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

}  // namespace

AtomicFile::AtomicFile(fs::path path) : path_(std::move(path)) {
  const fs::path dir = path_.parent_path();
  std::error_code ec;
  if (!dir.empty()) fs::create_directories(dir, ec);
  // Built piecewise: GCC 12 warns falsely on "." + string&&.
  std::string name = ".";
  name += path_.filename().string();
  name += ".tmp-";
  name += std::to_string(long(::getpid()));
  name += "-";
  name += std::to_string(std::hash<std::thread::id>{}(std::this_thread::get_id()) % 1000000);
  tmp_ = dir / name;
  // "e" (glibc: O_CLOEXEC): a child spawned meanwhile (ffmpeg, another sink's) must not keep
  // the temporary open.
  file_ = std::fopen(tmp_.c_str(), "wbe");
  if (file_ == nullptr) fail(path_, std::strerror(errno));
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
    fs::rename(tmp_, path_, ec);
    if (ec) error = ec.message();
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
  done_ = true;
}

void write_file_atomic(const fs::path& path, std::string_view bytes) {
  AtomicFile f(path);
  f.write(bytes);
  f.commit();
}

}  // namespace simreel::render
