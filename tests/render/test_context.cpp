// Both backends give an OpenGL 3.3+ core context, load the whole table, and draw the same frame.
#include <gtest/gtest.h>

#include <cstdlib>
#include <cstring>
#include <iostream>
#include <optional>
#include <stdexcept>
#include <string>

#include "render_test_util.hpp"
#include "simreel/render/context.hpp"
#include "simreel/render/gl_table.hpp"
#include "simreel/render/image_hash.hpp"
#include "simreel/render/renderer.hpp"

namespace simreel::render {
namespace {

class RenderContext : public ::testing::TestWithParam<Backend> {};

TEST_P(RenderContext, IsCoreProfileAtLeast33WithARendererString) {
  const auto context = create_context(GetParam());
  const GlTable& gl = context->gl();
  GLint major = 0;
  GLint minor = 0;
  GLint profile = 0;
  gl.GetIntegerv(GL_MAJOR_VERSION, &major);
  gl.GetIntegerv(GL_MINOR_VERSION, &minor);
  gl.GetIntegerv(GL_CONTEXT_PROFILE_MASK, &profile);
  EXPECT_GE(major * 10 + minor, 33) << context->version_string();
  EXPECT_NE(profile & GL_CONTEXT_CORE_PROFILE_BIT, 0) << context->version_string();
  EXPECT_FALSE(context->renderer_string().empty());
  EXPECT_FALSE(context->version_string().empty());
  EXPECT_EQ(context->backend_name(), GetParam() == Backend::osmesa ? "osmesa" : "egl");
  EXPECT_EQ(gl.GetError(), GLenum(GL_NO_ERROR));
  std::cout << "[ " << context->backend_name() << " ] " << context->renderer_string() << " | "
            << context->version_string() << "\n";
}

TEST_P(RenderContext, RendersTheSmallScene) {
  const auto context = create_context(GetParam());
  Renderer renderer(*context, test::small_settings());
  test::build_small_scene(renderer);
  const Image image = renderer.render();
  ASSERT_EQ(image.width, test::kWidth);
  ASSERT_EQ(image.height, test::kHeight);
  EXPECT_GT(test::find_blob(image, test::is_warm).count, 50);  // the box is there
}

INSTANTIATE_TEST_SUITE_P(Backends, RenderContext,
                         ::testing::Values(Backend::osmesa, Backend::egl),
                         [](const auto& info) {
                           return std::string(info.param == Backend::osmesa ? "osmesa" : "egl");
                         });

TEST(RenderBackend, ParsesNames) {
  EXPECT_EQ(parse_backend("osmesa"), Backend::osmesa);
  EXPECT_EQ(parse_backend("egl"), Backend::egl);
  EXPECT_THROW(parse_backend("vulkan"), std::invalid_argument);
  EXPECT_THROW(parse_backend("OSMesa"), std::invalid_argument);
}

TEST(RenderBackend, OsmesaAndEglDrawTheSameFrame) {
  auto draw = [](Backend backend) {
    const auto context = create_context(backend);
    Renderer renderer(*context, test::small_settings());
    test::build_small_scene(renderer);
    return renderer.render();
  };
  const Image a = draw(Backend::osmesa);
  const Image b = draw(Backend::egl);
  const bool identical = a.rgba == b.rgba;
  std::cout << "[ osmesa vs egl ] " << (identical ? "byte-identical" : "different bytes")
            << ", pHash distance " << hamming(phash(a), phash(b)) << "\n";
  RecordProperty("byte_identical", identical ? "yes" : "no");
  EXPECT_LE(hamming(phash(a), phash(b)), 2);
  EXPECT_LE(hamming(dhash(a), dhash(b)), 2);
}

/// Sets an environment variable for one scope and restores it.
class ScopedEnv {
 public:
  ScopedEnv(const char* name, const char* value) : name_(name) {
    if (const char* old = std::getenv(name)) old_ = old;
    setenv(name, value, 1);
  }
  ~ScopedEnv() {
    if (old_) {
      setenv(name_, old_->c_str(), 1);
    } else {
      unsetenv(name_);
    }
  }
  ScopedEnv(const ScopedEnv&) = delete;
  ScopedEnv& operator=(const ScopedEnv&) = delete;

 private:
  const char* name_;
  std::optional<std::string> old_;
};

TEST(RenderBackend, EglDeviceChoiceDrawsTheSameFrameAndATypoIsAnError) {
  auto draw = [] {
    const auto context = create_context(Backend::egl);
    Renderer renderer(*context, test::small_settings());
    test::build_small_scene(renderer);
    return renderer.render();
  };
  const Image by_default = draw();
  Image surfaceless;
  {
    const ScopedEnv env("SIMREEL_EGL_DEVICE", "surfaceless");
    surfaceless = draw();
  }
  // Here (no hardware device) the default is the surfaceless platform: the same renderer.
  EXPECT_EQ(by_default.rgba, surfaceless.rgba);
  {
    // Device 0 exists wherever EGL can enumerate devices (Mesa lists its software device).
    const ScopedEnv env("SIMREEL_EGL_DEVICE", "0");
    EXPECT_EQ(draw().rgba, by_default.rgba) << "device 0 (llvmpipe) draws what surfaceless draws";
  }
  for (const char* bad : {"99", "gpu", "-1", "1x"}) {
    const ScopedEnv env("SIMREEL_EGL_DEVICE", bad);
    try {
      (void)create_context(Backend::egl);
      FAIL() << "SIMREEL_EGL_DEVICE=" << bad << " was accepted";
    } catch (const ContextError& e) {
      EXPECT_NE(std::string(e.what()).find(std::string("SIMREEL_EGL_DEVICE=") + bad), std::string::npos)
          << e.what();
    }
  }
}

// A fake loader that knows every entry point but one.
void* all_but_blit(const char* name) {
  static int dummy;
  return std::strcmp(name, "glBlitFramebuffer") == 0 ? nullptr : static_cast<void*>(&dummy);
}

TEST(RenderBackend, GlTableNamesTheMissingEntryPoint) {
  GlTable table;
  try {
    table.load(&all_but_blit);
    FAIL() << "load() accepted a missing entry point";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("glBlitFramebuffer"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace simreel::render
