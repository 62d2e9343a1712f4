// Creating, making current and destroying the headless GL context.
#include "gl/egl_context.hpp"

#include <GL/glcorearb.h>

#include <algorithm>
#include <cctype>
#include <cstdlib>
#include <utility>

#include "gtrack/error.hpp"
#include "gtrack/log.hpp"

namespace gtrack::gl {

namespace {

bool has_word(const char* list, const std::string& word) {
  if (list == nullptr) return false;
  const std::string s = std::string(" ") + list + " ";
  return s.find(" " + word + " ") != std::string::npos;
}

// Whether the user's own environment fixes llvmpipe's thread count, captured
// before gtrack ever sets it so that later requests may change our value.
bool user_sets_lp_threads() {
  static const bool set = std::getenv("LP_NUM_THREADS") != nullptr;
  return set;
}

// Set only for a count asked for (0, every core, is llvmpipe's own
// default), before the display is initialised, which reads it. (Other
// threads may run then, a frame reader's among them: setenv is not safe
// against their getenv; with 0 nothing is written.)
void set_software_threads(int threads) {
  if (user_sets_lp_threads() || threads <= 0) return;
  setenv("LP_NUM_THREADS", std::to_string(threads).c_str(), 1);
}

// A context current on a thread stays bound to it after the thread ends
// (Mesa does not let it go): no other thread could take it again, nor
// delete the renderer's objects. A thread that makes a context current
// releases its EGL state when it ends.
void release_at_thread_exit() {
  struct Release {
    ~Release() { eglReleaseThread(); }
  };
  thread_local Release release;
  (void)release;
}

std::string lowercase(std::string s) {
  for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

}  // namespace

std::string effective_device_request(const std::string& explicit_request) {
  if (!explicit_request.empty()) return explicit_request;
  const char* env = std::getenv("GTRACK_EGL_DEVICE");
  return env ? std::string(env) : std::string();
}

EglContext EglContext::try_open(const std::vector<DisplayCandidate>& candidates, std::string& why,
                                int software_threads) {
  bool threads_set = false;
  for (const DisplayCandidate& c : candidates) {
    // llvmpipe reads its thread count when its context is made; the
    // environment is left alone while a GPU is tried.
    if (!threads_set && (c.kind == DisplayKind::software || c.kind == DisplayKind::surfaceless)) {
      set_software_threads(software_threads);
      threads_set = true;
    }
    std::string reason;
    const EGLDisplay display = acquire_display(c, reason);
    if (display == EGL_NO_DISPLAY) {
      why += (why.empty() ? "" : "; ") + reason;
      continue;
    }
    auto fail = [&](const std::string& step) {
      why += (why.empty() ? "" : "; ") + c.label + ": " + step + " failed with " + egl_error_name(eglGetError());
      release_display(display);
    };
    const char* ext = eglQueryString(display, EGL_EXTENSIONS);
    if (!has_word(ext, "EGL_KHR_surfaceless_context")) {
      why += (why.empty() ? "" : "; ") + c.label + ": no EGL_KHR_surfaceless_context";
      release_display(display);
      continue;
    }
    if (!eglBindAPI(EGL_OPENGL_API)) {
      fail("eglBindAPI(EGL_OPENGL_API)");
      continue;
    }
    // A configless context needs no surface type at all; drivers without
    // EGL_KHR_no_config_context get any pbuffer-capable GL config instead.
    EGLConfig config = EGL_NO_CONFIG_KHR;
    if (!has_word(ext, "EGL_KHR_no_config_context") && !has_word(ext, "EGL_MESA_configless_context")) {
      const EGLint wanted[] = {EGL_SURFACE_TYPE, EGL_PBUFFER_BIT, EGL_RENDERABLE_TYPE, EGL_OPENGL_BIT, EGL_NONE};
      EGLint n = 0;
      if (!eglChooseConfig(display, wanted, &config, 1, &n) || n < 1) {
        fail("eglChooseConfig");
        continue;
      }
    }
    const EGLint attributes[] = {EGL_CONTEXT_MAJOR_VERSION, 4, EGL_CONTEXT_MINOR_VERSION, 5,
                                 EGL_CONTEXT_OPENGL_PROFILE_MASK, EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT, EGL_NONE};
    const EGLContext context = eglCreateContext(display, config, EGL_NO_CONTEXT, attributes);
    if (context == EGL_NO_CONTEXT) {
      fail("eglCreateContext(OpenGL 4.5 core)");
      continue;
    }
    if (!eglMakeCurrent(display, EGL_NO_SURFACE, EGL_NO_SURFACE, context)) {
      const std::string err = egl_error_name(eglGetError());
      eglDestroyContext(display, context);
      why += (why.empty() ? "" : "; ") + c.label + ": eglMakeCurrent failed with " + err;
      release_display(display);
      continue;
    }
    release_at_thread_exit();
    EglContext out;
    out.display_ = display;
    out.context_ = context;
    out.label_ = c.label;
    auto get_string = reinterpret_cast<PFNGLGETSTRINGPROC>(eglGetProcAddress("glGetString"));
    if (get_string != nullptr) {
      const auto* r = reinterpret_cast<const char*>(get_string(GL_RENDERER));
      const auto* v = reinterpret_cast<const char*>(get_string(GL_VERSION));
      out.renderer_ = r ? r : "";
      out.version_ = v ? v : "";
    }
    return out;
  }
  return {};
}

EglContext EglContext::open(const ContextRequest& request) {
  const std::string wanted = effective_device_request(request.device);
  std::string no_devices;
  const std::vector<DisplayCandidate> devices = list_devices(&no_devices);

  std::vector<DisplayCandidate> order;
  if (wanted.empty()) {
    // A GPU left unused is refused rather than worked around on the CPU
    // a hundred times slower; asking for "surfaceless" takes that choice.
    if (const std::string missing = nvidia_without_egl(devices); !missing.empty()) {
      throw Error("gl backend: " + missing +
                  " ([render] egl_device = \"surfaceless\" renders on the CPU through Mesa on purpose)");
    }
    // A GPU first (NVIDIA's, then any other), then Mesa's surfaceless
    // platform (llvmpipe), then a software EGL device.
    for (DisplayKind kind : {DisplayKind::nvidia, DisplayKind::hardware}) {
      for (const auto& d : devices) {
        if (d.kind == kind) order.push_back(d);
      }
    }
    if (surfaceless_available()) order.push_back(surfaceless_candidate());
    for (const auto& d : devices) {
      if (d.kind == DisplayKind::software) order.push_back(d);
    }
  } else if (lowercase(wanted) == "surfaceless") {
    if (!surfaceless_available()) {
      throw Error("gl backend: no EGL context: EGL_MESA_platform_surfaceless is not offered by this EGL library");
    }
    order.push_back(surfaceless_candidate());
  } else {
    size_t used = 0;
    int index = -1;
    try {
      index = std::stoi(wanted, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (used != wanted.size() || index < 0) {
      throw Error("gl backend: EGL device '" + wanted +
                  "' is neither a device index nor 'surfaceless' (set by RenderOptions::egl_device or "
                  "GTRACK_EGL_DEVICE)");
    }
    if (static_cast<size_t>(index) >= devices.size()) {
      std::string list;
      for (const auto& d : devices) list += (list.empty() ? "" : ", ") + d.label;
      throw Error("gl backend: EGL device " + wanted + " does not exist; devices: " +
                  (list.empty() ? "none: " + no_devices : list));
    }
    order.push_back(devices[static_cast<size_t>(index)]);
  }

  std::string why;
  EglContext context = try_open(order, why, request.software_threads);
  if (!context) {
    if (order.empty()) why = "no EGL device and no Mesa surfaceless platform (is an EGL vendor library installed?)";
    throw Error("gl backend: no EGL context with OpenGL 4.5 core could be created: " + why);
  }
  // A device tried first that failed (a GPU without its EGL vendor library,
  // say) is worth knowing about when a slower one was taken instead.
  if (!why.empty()) logger().warn("gl backend: using {} after: {}", context.display_label(), why);
  return context;
}

EglContext::EglContext(EglContext&& other) noexcept
    : display_(std::exchange(other.display_, EGL_NO_DISPLAY)),
      context_(std::exchange(other.context_, EGL_NO_CONTEXT)),
      label_(std::move(other.label_)),
      renderer_(std::move(other.renderer_)),
      version_(std::move(other.version_)) {}

EglContext& EglContext::operator=(EglContext&& other) noexcept {
  if (this != &other) {
    reset();
    display_ = std::exchange(other.display_, EGL_NO_DISPLAY);
    context_ = std::exchange(other.context_, EGL_NO_CONTEXT);
    label_ = std::move(other.label_);
    renderer_ = std::move(other.renderer_);
    version_ = std::move(other.version_);
  }
  return *this;
}

EglContext::~EglContext() { reset(); }

void EglContext::reset() noexcept {
  if (context_ == EGL_NO_CONTEXT) return;
  if (eglQueryAPI() != EGL_OPENGL_API) eglBindAPI(EGL_OPENGL_API);
  if (eglGetCurrentContext() == context_) eglMakeCurrent(display_, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
  eglDestroyContext(display_, context_);
  release_display(display_);
  context_ = EGL_NO_CONTEXT;
  display_ = EGL_NO_DISPLAY;
}

void EglContext::make_current() const {
  // eglGetCurrentContext() answers for the thread's bound API, which is
  // OpenGL ES on a thread that never chose one.
  if (eglQueryAPI() != EGL_OPENGL_API) eglBindAPI(EGL_OPENGL_API);
  if (eglGetCurrentContext() == context_) return;
  if (!eglMakeCurrent(display_, EGL_NO_SURFACE, EGL_NO_SURFACE, context_)) {
    const EGLint e = eglGetError();
    throw Error("gl backend: eglMakeCurrent failed with " + egl_error_name(e) +
                (e == EGL_BAD_ACCESS ? std::string(" (its context is current on another thread: a gl renderer is "
                                                   "used by one thread at a time, until that thread ends)")
                                     : std::string()));
  }
  release_at_thread_exit();
}

void EglContext::release_current() const noexcept {
  if (context_ == EGL_NO_CONTEXT) return;
  if (eglQueryAPI() != EGL_OPENGL_API) eglBindAPI(EGL_OPENGL_API);
  if (eglGetCurrentContext() == context_) eglMakeCurrent(display_, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
}

bool software_renderer(const std::string& gl_renderer) {
  const std::string r = lowercase(gl_renderer);
  return r.find("llvmpipe") != std::string::npos || r.find("softpipe") != std::string::npos ||
         r.find("swrast") != std::string::npos || r.find("swiftshader") != std::string::npos;
}

bool EglContext::software() const { return software_renderer(renderer_); }

}  // namespace gtrack::gl
