#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <system_error>
#include <utility>

#include "simreel/render/frame_sink.hpp"
#include "simreel/render/text_overlay.hpp"

namespace simreel::render {

namespace fs = std::filesystem;

std::vector<int> contact_sheet_frames(int first, int count, int cells) {
  if (cells < 1 || count < 1) {
    throw std::invalid_argument("contact sheet: need at least one cell and one frame");
  }
  std::vector<int> frames;
  const int n = std::min(cells, count);
  for (int i = 0; i < n; ++i) {
    // Integer rounding of i * (count - 1) / (n - 1): first and last frame exactly.
    const long long num = 2LL * i * (count - 1) + (n - 1);
    const int offset = n == 1 ? 0 : int(num / (2LL * (n - 1)));
    frames.push_back(first + offset);
  }
  return frames;
}

namespace {

class ContactSheetSink final : public FrameSink {
 public:
  ContactSheetSink(fs::path path, int width, int height, std::vector<int> frames,
                   const ContactSheetLayout& layout)
      : path_(std::move(path)), frames_(std::move(frames)), layout_(layout) {
    if (width < 1 || height < 1 || layout.columns < 1 || layout.rows < 1 ||
        layout.thumb_width < 8 || layout.gap < 0) {
      throw std::invalid_argument("contact sheet: bad frame size or layout");
    }
    thumb_w_ = std::min(layout.thumb_width, width);
    thumb_h_ = std::max(1, int(std::lround(double(thumb_w_) * height / width)));
    const int rows_used = std::min(
        layout.rows, int((frames_.size() + std::size_t(layout.columns) - 1) / std::size_t(layout.columns)));
    sheet_ = Image(layout.columns * (thumb_w_ + layout.gap) + layout.gap,
                   std::max(1, rows_used) * (thumb_h_ + layout.gap) + layout.gap);
    for (std::size_t i = 0; i < sheet_.rgba.size(); i += 4) {
      sheet_.rgba[i] = sheet_.rgba[i + 1] = sheet_.rgba[i + 2] = 24;
      sheet_.rgba[i + 3] = 255;
    }
    const fs::path dir = path_.parent_path();
    if (!dir.empty()) {
      std::error_code ec;
      fs::create_directories(dir, ec);
      if (ec) throw IoError("cannot create directory " + dir.string() + ": " + ec.message());
    }
  }

  void write(const Image& frame, int index) override {
    const auto it = std::find(frames_.begin(), frames_.end(), index);
    if (it == frames_.end()) return;
    const int cell = int(it - frames_.begin());
    if (cell >= layout_.columns * layout_.rows) return;
    const int x = layout_.gap + (cell % layout_.columns) * (thumb_w_ + layout_.gap);
    const int y = layout_.gap + (cell / layout_.columns) * (thumb_h_ + layout_.gap);
    blit(sheet_, resize_box(frame, thumb_w_, thumb_h_), x, y);
    TextStyle style;
    style.scale = thumb_w_ >= 240 ? 2 : 1;
    draw_text(sheet_, x, y, std::to_string(index), style);
  }

  void finish() override { write_png(path_, sheet_, 6); }
  void abort() noexcept override {}
  [[nodiscard]] std::string describe() const override { return path_.string(); }

 private:
  fs::path path_;
  std::vector<int> frames_;
  ContactSheetLayout layout_;
  int thumb_w_ = 0;
  int thumb_h_ = 0;
  Image sheet_;
};

}  // namespace

std::unique_ptr<FrameSink> make_contact_sheet(const fs::path& path, int width, int height,
                                              std::vector<int> frames,
                                              const ContactSheetLayout& layout) {
  return std::make_unique<ContactSheetSink>(path, width, height, std::move(frames), layout);
}

}  // namespace simreel::render
