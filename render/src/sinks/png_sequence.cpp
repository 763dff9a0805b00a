// The PNG-sequence sink (frame_sink.hpp): one PNG per frame, each written atomically.
#include <algorithm>
#include <cstdio>
#include <string>
#include <system_error>
#include <thread>

#include "simreel/render/frame_sink.hpp"

namespace simreel::render {

namespace fs = std::filesystem;

namespace {

class PngSequenceSink final : public FrameSink {
 public:
  PngSequenceSink(fs::path dir, int compression, int threads)
      : dir_(std::move(dir)), compression_(compression), threads_(threads) {
    std::error_code ec;
    fs::create_directories(dir_, ec);
    if (ec) throw IoError("cannot create directory " + dir_.string() + ": " + ec.message());
  }

  void write(const Image& frame, int index) override {
    if (index < 0) throw IoError("cannot write frame " + std::to_string(index) + " to " + describe());
    char name[32];
    std::snprintf(name, sizeof name, "frame_%05d.png", index);
    write_png(dir_ / name, frame, compression_);
  }
  // Every frame is complete on its own once written, so there is nothing to close or discard.
  void finish() override {}
  void abort() noexcept override {}
  [[nodiscard]] std::string describe() const override {
    return (dir_ / "frame_%05d.png").string();
  }
  // Each frame is its own file, written through its own temporary: frames compress in parallel.
  [[nodiscard]] int concurrency() const override { return threads_; }

 private:
  fs::path dir_;
  int compression_;
  int threads_;
};

}  // namespace

std::unique_ptr<FrameSink> make_png_sequence(const fs::path& dir, int compression, int threads) {
  if (threads <= 0) {
    const unsigned cores = std::thread::hardware_concurrency();
    threads = static_cast<int>(std::clamp(cores, 1u, 4u));
  }
  return std::make_unique<PngSequenceSink>(dir, compression, threads);
}

}  // namespace simreel::render
