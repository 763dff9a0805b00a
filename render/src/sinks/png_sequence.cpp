// The PNG-sequence sink (frame_sink.hpp): one PNG per frame, each written atomically.
#include <cstdio>
#include <string>
#include <system_error>

#include "simreel/render/frame_sink.hpp"

namespace simreel::render {

namespace fs = std::filesystem;

namespace {

class PngSequenceSink final : public FrameSink {
 public:
  PngSequenceSink(fs::path dir, int compression) : dir_(std::move(dir)), compression_(compression) {
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

 private:
  fs::path dir_;
  int compression_;
};

}  // namespace

std::unique_ptr<FrameSink> make_png_sequence(const fs::path& dir, int compression) {
  return std::make_unique<PngSequenceSink>(dir, compression);
}

}  // namespace simreel::render
