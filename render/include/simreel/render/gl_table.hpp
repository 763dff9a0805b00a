#pragma once
/// @file gl_table.hpp
/// The project's own OpenGL function table, loaded through a context's getProcAddress (the way
/// glad does it), so the OSMesa and EGL backends share every line of renderer code.

// glcorearb.h declares every core entry point's PFN type (gl.h + glext.h lack those of GL 1.0
// and 1.1). It must come before any <GL/gl.h>, which would otherwise hide its GL 1.1 block.
#include <GL/glcorearb.h>

namespace simreel::render {

using GetProcAddress = void* (*)(const char* name);

/// Every GL entry point the renderer uses. Members named as in GL without the `gl` prefix.
/// Nothing in simreel calls GL except through this table.
struct GlTable {
#define SIMREEL_GL_FUNCTIONS(X)                                                                \
  X(PFNGLGETSTRINGPROC, GetString) X(PFNGLGETERRORPROC, GetError)                              \
  X(PFNGLVIEWPORTPROC, Viewport) X(PFNGLCLEARCOLORPROC, ClearColor) X(PFNGLCLEARPROC, Clear)   \
  X(PFNGLENABLEPROC, Enable) X(PFNGLDISABLEPROC, Disable) X(PFNGLBLENDFUNCPROC, BlendFunc)     \
  X(PFNGLBLENDFUNCSEPARATEPROC, BlendFuncSeparate) X(PFNGLDEPTHMASKPROC, DepthMask)            \
  X(PFNGLDEPTHFUNCPROC, DepthFunc) X(PFNGLCULLFACEPROC, CullFace)                              \
  X(PFNGLREADPIXELSPROC, ReadPixels) X(PFNGLPIXELSTOREIPROC, PixelStorei)                      \
  X(PFNGLFINISHPROC, Finish) X(PFNGLGETINTEGERVPROC, GetIntegerv)                              \
  X(PFNGLCREATESHADERPROC, CreateShader) X(PFNGLSHADERSOURCEPROC, ShaderSource)                \
  X(PFNGLCOMPILESHADERPROC, CompileShader) X(PFNGLGETSHADERIVPROC, GetShaderiv)                \
  X(PFNGLGETSHADERINFOLOGPROC, GetShaderInfoLog) X(PFNGLDELETESHADERPROC, DeleteShader)        \
  X(PFNGLCREATEPROGRAMPROC, CreateProgram) X(PFNGLATTACHSHADERPROC, AttachShader)              \
  X(PFNGLLINKPROGRAMPROC, LinkProgram) X(PFNGLGETPROGRAMIVPROC, GetProgramiv)                  \
  X(PFNGLGETPROGRAMINFOLOGPROC, GetProgramInfoLog) X(PFNGLUSEPROGRAMPROC, UseProgram)          \
  X(PFNGLDELETEPROGRAMPROC, DeleteProgram)                                                     \
  X(PFNGLGETUNIFORMLOCATIONPROC, GetUniformLocation) X(PFNGLUNIFORM1IPROC, Uniform1i)          \
  X(PFNGLUNIFORM1FPROC, Uniform1f) X(PFNGLUNIFORM2FPROC, Uniform2f)                            \
  X(PFNGLUNIFORM3FPROC, Uniform3f) X(PFNGLUNIFORM4FPROC, Uniform4f)                            \
  X(PFNGLUNIFORMMATRIX3FVPROC, UniformMatrix3fv) X(PFNGLUNIFORMMATRIX4FVPROC, UniformMatrix4fv) \
  X(PFNGLGENVERTEXARRAYSPROC, GenVertexArrays) X(PFNGLBINDVERTEXARRAYPROC, BindVertexArray)    \
  X(PFNGLDELETEVERTEXARRAYSPROC, DeleteVertexArrays) X(PFNGLGENBUFFERSPROC, GenBuffers)        \
  X(PFNGLBINDBUFFERPROC, BindBuffer) X(PFNGLBUFFERDATAPROC, BufferData)                        \
  X(PFNGLBUFFERSUBDATAPROC, BufferSubData) X(PFNGLDELETEBUFFERSPROC, DeleteBuffers)            \
  X(PFNGLENABLEVERTEXATTRIBARRAYPROC, EnableVertexAttribArray)                                 \
  X(PFNGLVERTEXATTRIBPOINTERPROC, VertexAttribPointer)                                         \
  X(PFNGLVERTEXATTRIBDIVISORPROC, VertexAttribDivisor)                                         \
  X(PFNGLDRAWARRAYSPROC, DrawArrays) X(PFNGLDRAWELEMENTSPROC, DrawElements)                    \
  X(PFNGLDRAWARRAYSINSTANCEDPROC, DrawArraysInstanced)                                         \
  X(PFNGLGENFRAMEBUFFERSPROC, GenFramebuffers) X(PFNGLBINDFRAMEBUFFERPROC, BindFramebuffer)    \
  X(PFNGLDELETEFRAMEBUFFERSPROC, DeleteFramebuffers)                                           \
  X(PFNGLFRAMEBUFFERRENDERBUFFERPROC, FramebufferRenderbuffer)                                 \
  X(PFNGLCHECKFRAMEBUFFERSTATUSPROC, CheckFramebufferStatus)                                   \
  X(PFNGLGENRENDERBUFFERSPROC, GenRenderbuffers) X(PFNGLBINDRENDERBUFFERPROC, BindRenderbuffer) \
  X(PFNGLDELETERENDERBUFFERSPROC, DeleteRenderbuffers)                                         \
  X(PFNGLRENDERBUFFERSTORAGEMULTISAMPLEPROC, RenderbufferStorageMultisample)                   \
  X(PFNGLRENDERBUFFERSTORAGEPROC, RenderbufferStorage)                                         \
  X(PFNGLBLITFRAMEBUFFERPROC, BlitFramebuffer)                                               \
  X(PFNGLGENTEXTURESPROC, GenTextures) X(PFNGLDELETETEXTURESPROC, DeleteTextures)              \
  X(PFNGLBINDTEXTUREPROC, BindTexture) X(PFNGLACTIVETEXTUREPROC, ActiveTexture)                \
  X(PFNGLTEXIMAGE2DPROC, TexImage2D) X(PFNGLTEXPARAMETERIPROC, TexParameteri)                  \
  X(PFNGLFRAMEBUFFERTEXTURE2DPROC, FramebufferTexture2D)                                       \
  X(PFNGLDRAWBUFFERPROC, DrawBuffer) X(PFNGLREADBUFFERPROC, ReadBuffer)                        \
  X(PFNGLPOLYGONOFFSETPROC, PolygonOffset)                                                     \
  X(PFNGLGENERATEMIPMAPPROC, GenerateMipmap)
#define SIMREEL_GL_MEMBER(type, name) type name = nullptr;
  SIMREEL_GL_FUNCTIONS(SIMREEL_GL_MEMBER)
#undef SIMREEL_GL_MEMBER

  /// Loads every entry point. @throws std::runtime_error naming the first one missing.
  void load(GetProcAddress get_proc_address);
};

}  // namespace simreel::render
