// `simreel hash`: print perceptual hashes of image files.
#include <iostream>

#include "commands.hpp"
#include "golden.hpp"
#include "simreel/render/image.hpp"
#include "simreel/render/image_hash.hpp"

namespace simreel::app {

int hash_command(const std::vector<std::string>& images, const std::string& algorithm) {
  int code = 0;
  for (const auto& path : images) {
    try {
      const render::Image img = render::read_image(path);
      if (algorithm == "all") {
        const FrameHashes h = hash_frame(img, 0);
        std::cout << "phash " << render::hash_to_hex(h.phash) << "  dhash " << render::hash_to_hex(h.dhash)
                  << "  chash " << render::hash_to_hex(h.chash) << "  " << path << "\n";
        continue;
      }
      const std::uint64_t h = algorithm == "dhash"   ? render::dhash(img)
                              : algorithm == "chash" ? render::chash(img)
                                                     : render::phash(img);
      std::cout << render::hash_to_hex(h) << "  " << path << "\n";
    } catch (const render::IoError& e) {
      std::cerr << "simreel: " << e.what() << "\n";
      code = 2;
    }
  }
  return code;
}

}  // namespace simreel::app
