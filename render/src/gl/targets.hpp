#pragma once
// Private: textures and framebuffers the passes render into, and the checks that turn an
// incomplete framebuffer or a GL error into a ContextError.

#include "simreel/render/gl_table.hpp"

namespace simreel::render::detail {

/// A width x height 2-D texture with `filter` for both minification and magnification and
/// clamp-to-edge wrapping, no data; left bound to GL_TEXTURE_2D on the active unit.
GLuint make_texture_2d(const GlTable& gl, int width, int height, GLint internal, GLenum format,
                       GLenum type, GLint filter);

/// "GL_FRAMEBUFFER_INCOMPLETE_ATTACHMENT", ...
const char* framebuffer_status_name(GLenum status);

/// Checks the framebuffer bound to GL_FRAMEBUFFER. @throws ContextError "renderer: the <what>
/// framebuffer (<width>x<height>) is incomplete: <status>".
void check_framebuffer(const GlTable& gl, const char* what, int width, int height);

/// @throws ContextError "renderer: OpenGL error 0x0502 while <stage>" if GL reports one.
void check_error(const GlTable& gl, const char* stage);

}  // namespace simreel::render::detail
