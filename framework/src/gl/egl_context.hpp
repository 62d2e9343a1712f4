// A headless OpenGL 4.5 core context, owned by one object.
//
// EglContext::open() picks a display the way the user asked: an EGL device by
// index, "surfaceless" for Mesa's surfaceless platform, or, by default, the
// first that works of NVIDIA devices, other hardware devices, software
// devices and finally Mesa surfaceless. No window system and no surface are
// involved: rendering goes to framebuffer objects. The object is move-only;
// its destructor destroys the context and releases the display. GL objects
// made in the context must be deleted before it goes (with it current).
//
// A context is current on at most one thread; callers make it current at the
// entry of every operation (cheap when it already is). open() leaves it
// current on the calling thread; release_current() lets it go, so that
// another thread can take it.
#pragma once

#include <EGL/egl.h>

#include <string>
#include <vector>

#include "gl/egl_display.hpp"

namespace gtrack::gl {

struct ContextRequest {
  // "" = GTRACK_EGL_DEVICE, or automatic when that is unset too;
  // a device index ("0", "1", ...); or "surfaceless".
  std::string device;
  // llvmpipe's LP_NUM_THREADS for a software display, unless the user's
  // environment sets it; 0 = llvmpipe's own default (every core), left unset. llvmpipe reads it when a
  // display is initialised, so it only applies to the first context on it.
  int software_threads = 0;
};

class EglContext {
 public:
  // Throws gtrack::Error listing every display tried and why it failed. The
  // message starts with "gl backend: no EGL context" when none could be made.
  static EglContext open(const ContextRequest& request);
  // Like open() but over the given candidates only; nothing thrown, an empty
  // context when none works (used to probe for hardware). Before the first
  // software candidate, llvmpipe's thread count is set from
  // `software_threads` (0: every core) unless LP_NUM_THREADS is set.
  static EglContext try_open(const std::vector<DisplayCandidate>& candidates, std::string& why,
                             int software_threads = 0);

  EglContext() = default;
  EglContext(EglContext&& other) noexcept;
  EglContext& operator=(EglContext&& other) noexcept;
  EglContext(const EglContext&) = delete;
  EglContext& operator=(const EglContext&) = delete;
  ~EglContext();

  explicit operator bool() const { return context_ != EGL_NO_CONTEXT; }

  // Throws gtrack::Error with the EGL error name on failure (for example
  // EGL_BAD_ACCESS when the context is current on another thread).
  void make_current() const;
  // Makes no context current on the calling thread if this one is.
  void release_current() const noexcept;

  const std::string& display_label() const { return label_; }
  const std::string& gl_renderer() const { return renderer_; }
  const std::string& gl_version() const { return version_; }
  // software_renderer() of its GL_RENDERER: rendering runs on the CPU.
  bool software() const;

 private:
  void reset() noexcept;

  EGLDisplay display_ = EGL_NO_DISPLAY;
  EGLContext context_ = EGL_NO_CONTEXT;
  std::string label_;
  std::string renderer_;
  std::string version_;
};

// Whether a GL_RENDERER string names a renderer that runs on the CPU
// (llvmpipe, softpipe, swrast, SwiftShader).
bool software_renderer(const std::string& gl_renderer);

// The device request in force: `explicit_request` if not empty, else
// GTRACK_EGL_DEVICE, else "".
std::string effective_device_request(const std::string& explicit_request);

}  // namespace gtrack::gl
