// Loading the GL entry points through EGL and naming GL errors.
#include "gl/gl_api.hpp"

#include <EGL/egl.h>

#include <cstdio>
#include <cstring>

#include "gtrack/error.hpp"

namespace gtrack::gl {

void Api::load() {
#define GTRACK_GL_LOAD(type, name)                                                              \
  name = reinterpret_cast<type>(eglGetProcAddress("gl" #name));                                 \
  if (name == nullptr) throw Error("gl backend: the driver does not provide gl" #name " (OpenGL 4.5 needed)");
  GTRACK_GL_FUNCTIONS(GTRACK_GL_LOAD)
#undef GTRACK_GL_LOAD
}

std::string gl_error_name(GLenum code) {
  switch (code) {
    case GL_NO_ERROR: return "GL_NO_ERROR";
    case GL_INVALID_ENUM: return "GL_INVALID_ENUM";
    case GL_INVALID_VALUE: return "GL_INVALID_VALUE";
    case GL_INVALID_OPERATION: return "GL_INVALID_OPERATION";
    case GL_INVALID_FRAMEBUFFER_OPERATION: return "GL_INVALID_FRAMEBUFFER_OPERATION";
    case GL_OUT_OF_MEMORY: return "GL_OUT_OF_MEMORY";
    case GL_STACK_UNDERFLOW: return "GL_STACK_UNDERFLOW";
    case GL_STACK_OVERFLOW: return "GL_STACK_OVERFLOW";
    case GL_CONTEXT_LOST: return "GL_CONTEXT_LOST";
    default: {
      char buf[32];
      std::snprintf(buf, sizeof buf, "GL error 0x%04X", code);
      return buf;
    }
  }
}

void Api::check(const char* what) const {
  const GLenum code = GetError();
  if (code == GL_NO_ERROR) return;
  // Drain the remaining flags so that the next check reports its own step.
  for (int i = 0; i < 16 && GetError() != GL_NO_ERROR; ++i) {
  }
  throw Error(std::string("gl backend: ") + what + ": " + gl_error_name(code));
}

bool Api::has_extension(const char* name) const {
  GLint n = 0;
  GetIntegerv(GL_NUM_EXTENSIONS, &n);
  for (GLint i = 0; i < n; ++i) {
    const auto* e = reinterpret_cast<const char*>(GetStringi(GL_EXTENSIONS, static_cast<GLuint>(i)));
    if (e != nullptr && std::strcmp(e, name) == 0) return true;
  }
  return false;
}

}  // namespace gtrack::gl
