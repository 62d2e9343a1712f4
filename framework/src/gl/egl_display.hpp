// Which EGL displays the gl backend can open, and their lifetime.
//
// A candidate is either an EGL device (EGL_EXT_device_enumeration +
// EGL_EXT_platform_device: an NVIDIA GPU, a Mesa DRM device, or Mesa's
// software device) or Mesa's surfaceless platform. EGL keeps one display per
// (platform, device) for the whole process and eglTerminate() invalidates
// every context made on it, so initialised displays are reference counted
// here: the last context to go terminates the display, no earlier.
#pragma once

#include <EGL/egl.h>
#include <EGL/eglext.h>

#include <string>
#include <vector>

namespace gtrack::gl {

enum class DisplayKind { nvidia, hardware, software, surfaceless };

struct DisplayCandidate {
  std::string label;  // for messages: "EGL device 1 (/dev/dri/renderD128)", "Mesa surfaceless"
  DisplayKind kind = DisplayKind::surfaceless;
  EGLenum platform = 0;
  void* native = nullptr;  // the EGLDeviceEXT, or EGL_DEFAULT_DISPLAY
};

// The EGL devices in enumeration order (empty when EGL has no device
// enumeration, or no EGL vendor library is installed; `why` then says which).
std::vector<DisplayCandidate> list_devices(std::string* why = nullptr);
// When the machine has an NVIDIA GPU (its device nodes) but `devices` holds
// no GPU device at all (NVIDIA's EGL vendor library missing, a container
// without graphics capability), what is missing; "" otherwise. Rendering
// would then go to Mesa's CPU rasteriser on a machine with a GPU.
std::string nvidia_without_egl(const std::vector<DisplayCandidate>& devices);
// Mesa's surfaceless platform, if the EGL client library offers it.
bool surfaceless_available();
DisplayCandidate surfaceless_candidate();

// An initialised display for the candidate, or EGL_NO_DISPLAY with the reason
// in `why`. Every successful acquire is paired with one release.
EGLDisplay acquire_display(const DisplayCandidate& candidate, std::string& why);
void release_display(EGLDisplay display);

// "EGL_BAD_MATCH" etc. for an eglGetError code.
std::string egl_error_name(EGLint code);

}  // namespace gtrack::gl
