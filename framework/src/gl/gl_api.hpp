// The OpenGL 4.5 entry points the gl backend calls, loaded at run time.
//
// gtrack links libEGL only and takes every GL function from
// eglGetProcAddress (EGL_KHR_get_all_proc_addresses makes that valid for core
// functions too), so there is no loader library and no dependency on which
// libGL the system happens to provide. The list below is the whole GL surface
// the backend uses; load() fails with the name of the first missing function.
#pragma once

#include <GL/glcorearb.h>

#include <string>

namespace gtrack::gl {

#define GTRACK_GL_FUNCTIONS(X)                                      \
  X(PFNGLGETSTRINGPROC, GetString)                                  \
  X(PFNGLGETSTRINGIPROC, GetStringi)                                \
  X(PFNGLGETINTEGERVPROC, GetIntegerv)                              \
  X(PFNGLGETERRORPROC, GetError)                                    \
  X(PFNGLENABLEPROC, Enable)                                        \
  X(PFNGLDISABLEPROC, Disable)                                      \
  X(PFNGLLOGICOPPROC, LogicOp)                                      \
  X(PFNGLVIEWPORTPROC, Viewport)                                    \
  X(PFNGLCLIPCONTROLPROC, ClipControl)                              \
  X(PFNGLPIXELSTOREIPROC, PixelStorei)                              \
  X(PFNGLCREATESHADERPROC, CreateShader)                            \
  X(PFNGLSHADERSOURCEPROC, ShaderSource)                            \
  X(PFNGLCOMPILESHADERPROC, CompileShader)                          \
  X(PFNGLGETSHADERIVPROC, GetShaderiv)                              \
  X(PFNGLGETSHADERINFOLOGPROC, GetShaderInfoLog)                    \
  X(PFNGLDELETESHADERPROC, DeleteShader)                            \
  X(PFNGLCREATEPROGRAMPROC, CreateProgram)                          \
  X(PFNGLATTACHSHADERPROC, AttachShader)                            \
  X(PFNGLLINKPROGRAMPROC, LinkProgram)                              \
  X(PFNGLGETPROGRAMIVPROC, GetProgramiv)                            \
  X(PFNGLGETPROGRAMINFOLOGPROC, GetProgramInfoLog)                  \
  X(PFNGLDELETEPROGRAMPROC, DeleteProgram)                          \
  X(PFNGLUSEPROGRAMPROC, UseProgram)                                \
  X(PFNGLGETUNIFORMLOCATIONPROC, GetUniformLocation)                \
  X(PFNGLPROGRAMUNIFORM1IPROC, ProgramUniform1i)                    \
  X(PFNGLPROGRAMUNIFORM4FVPROC, ProgramUniform4fv)                  \
  X(PFNGLPROGRAMUNIFORMMATRIX4FVPROC, ProgramUniformMatrix4fv)      \
  X(PFNGLCREATEBUFFERSPROC, CreateBuffers)                          \
  X(PFNGLNAMEDBUFFERSTORAGEPROC, NamedBufferStorage)                \
  X(PFNGLNAMEDBUFFERSUBDATAPROC, NamedBufferSubData)                \
  X(PFNGLCLEARNAMEDBUFFERSUBDATAPROC, ClearNamedBufferSubData)      \
  X(PFNGLMAPNAMEDBUFFERRANGEPROC, MapNamedBufferRange)              \
  X(PFNGLUNMAPNAMEDBUFFERPROC, UnmapNamedBuffer)                    \
  X(PFNGLCOPYNAMEDBUFFERSUBDATAPROC, CopyNamedBufferSubData)        \
  X(PFNGLDELETEBUFFERSPROC, DeleteBuffers)                          \
  X(PFNGLBINDBUFFERBASEPROC, BindBufferBase)                        \
  X(PFNGLCREATETEXTURESPROC, CreateTextures)                        \
  X(PFNGLTEXTURESTORAGE2DPROC, TextureStorage2D)                    \
  X(PFNGLTEXTURESTORAGE3DPROC, TextureStorage3D)                    \
  X(PFNGLTEXTURESUBIMAGE2DPROC, TextureSubImage2D)                  \
  X(PFNGLCLEARTEXSUBIMAGEPROC, ClearTexSubImage)                    \
  X(PFNGLGETTEXTURESUBIMAGEPROC, GetTextureSubImage)                \
  X(PFNGLTEXTUREPARAMETERIPROC, TextureParameteri)                  \
  X(PFNGLBINDTEXTUREUNITPROC, BindTextureUnit)                      \
  X(PFNGLDELETETEXTURESPROC, DeleteTextures)                        \
  X(PFNGLCREATEFRAMEBUFFERSPROC, CreateFramebuffers)                \
  X(PFNGLNAMEDFRAMEBUFFERTEXTUREPROC, NamedFramebufferTexture)      \
  X(PFNGLNAMEDFRAMEBUFFERDRAWBUFFERPROC, NamedFramebufferDrawBuffer) \
  X(PFNGLCLEARNAMEDFRAMEBUFFERUIVPROC, ClearNamedFramebufferuiv) \
  X(PFNGLCHECKNAMEDFRAMEBUFFERSTATUSPROC, CheckNamedFramebufferStatus) \
  X(PFNGLBINDFRAMEBUFFERPROC, BindFramebuffer)                      \
  X(PFNGLDELETEFRAMEBUFFERSPROC, DeleteFramebuffers)                \
  X(PFNGLCREATEVERTEXARRAYSPROC, CreateVertexArrays)                \
  X(PFNGLBINDVERTEXARRAYPROC, BindVertexArray)                      \
  X(PFNGLDELETEVERTEXARRAYSPROC, DeleteVertexArrays)                \
  X(PFNGLDRAWARRAYSINSTANCEDPROC, DrawArraysInstanced)              \
  X(PFNGLDISPATCHCOMPUTEPROC, DispatchCompute)                      \
  X(PFNGLMEMORYBARRIERPROC, MemoryBarrier)                          \
  X(PFNGLFENCESYNCPROC, FenceSync)                                  \
  X(PFNGLCLIENTWAITSYNCPROC, ClientWaitSync)                        \
  X(PFNGLDELETESYNCPROC, DeleteSync)                                \
  X(PFNGLFLUSHPROC, Flush)                                          \
  X(PFNGLFINISHPROC, Finish)

struct Api {
#define GTRACK_GL_MEMBER(type, name) type name = nullptr;
  GTRACK_GL_FUNCTIONS(GTRACK_GL_MEMBER)
#undef GTRACK_GL_MEMBER

  // Fills every pointer; throws gtrack::Error naming the first one missing.
  void load();

  // Throws gtrack::Error "gl backend: <what>: GL_INVALID_..." if the GL error
  // flag is set. Not for every call: callers check after setup steps, and
  // once a batch, after its fence.
  void check(const char* what) const;

  bool has_extension(const char* name) const;
};

// "GL_INVALID_ENUM" etc. for a glGetError code.
std::string gl_error_name(GLenum code);

}  // namespace gtrack::gl
