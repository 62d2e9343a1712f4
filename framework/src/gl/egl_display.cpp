// Enumerating EGL devices and reference-counting initialised displays.
#include "gl/egl_display.hpp"

#include <cstdio>
#include <cstring>
#include <filesystem>
#include <map>
#include <mutex>

namespace gtrack::gl {

namespace {

bool has_word(const char* list, const char* word) {
  if (list == nullptr) return false;
  const size_t n = std::strlen(word);
  for (const char* p = list; (p = std::strstr(p, word)) != nullptr; p += n) {
    const bool starts = p == list || p[-1] == ' ';
    const bool ends = p[n] == '\0' || p[n] == ' ';
    if (starts && ends) return true;
  }
  return false;
}

const char* client_extensions() {
  // Without EGL_EXT_client_extensions this fails with EGL_BAD_DISPLAY and
  // returns null, which simply means "no platform extensions".
  return eglQueryString(EGL_NO_DISPLAY, EGL_EXTENSIONS);
}

std::mutex& registry_mutex() {
  static std::mutex m;
  return m;
}

std::map<EGLDisplay, int>& registry() {
  static std::map<EGLDisplay, int> users;
  return users;
}

}  // namespace

std::string egl_error_name(EGLint code) {
  switch (code) {
    case EGL_SUCCESS: return "EGL_SUCCESS";
    case EGL_NOT_INITIALIZED: return "EGL_NOT_INITIALIZED";
    case EGL_BAD_ACCESS: return "EGL_BAD_ACCESS";
    case EGL_BAD_ALLOC: return "EGL_BAD_ALLOC";
    case EGL_BAD_ATTRIBUTE: return "EGL_BAD_ATTRIBUTE";
    case EGL_BAD_CONTEXT: return "EGL_BAD_CONTEXT";
    case EGL_BAD_CONFIG: return "EGL_BAD_CONFIG";
    case EGL_BAD_CURRENT_SURFACE: return "EGL_BAD_CURRENT_SURFACE";
    case EGL_BAD_DISPLAY: return "EGL_BAD_DISPLAY";
    case EGL_BAD_SURFACE: return "EGL_BAD_SURFACE";
    case EGL_BAD_MATCH: return "EGL_BAD_MATCH";
    case EGL_BAD_PARAMETER: return "EGL_BAD_PARAMETER";
    case EGL_BAD_NATIVE_PIXMAP: return "EGL_BAD_NATIVE_PIXMAP";
    case EGL_BAD_NATIVE_WINDOW: return "EGL_BAD_NATIVE_WINDOW";
    case EGL_CONTEXT_LOST: return "EGL_CONTEXT_LOST";
    case EGL_BAD_DEVICE_EXT: return "EGL_BAD_DEVICE_EXT";
    default: {
      char buf[32];
      std::snprintf(buf, sizeof buf, "EGL error 0x%04X", static_cast<unsigned>(code));
      return buf;
    }
  }
}

std::vector<DisplayCandidate> list_devices(std::string* why) {
  std::vector<DisplayCandidate> out;
  const auto none = [&](const char* reason) {
    if (why) *why = reason;
    return out;
  };
  const char* client = client_extensions();
  if (!has_word(client, "EGL_EXT_device_enumeration") && !has_word(client, "EGL_EXT_device_base")) {
    return none("the EGL library offers no EGL_EXT_device_enumeration (is an EGL vendor library installed?)");
  }
  if (!has_word(client, "EGL_EXT_platform_device")) return none("the EGL library offers no EGL_EXT_platform_device");
  auto query_devices = reinterpret_cast<PFNEGLQUERYDEVICESEXTPROC>(eglGetProcAddress("eglQueryDevicesEXT"));
  auto query_string =
      reinterpret_cast<PFNEGLQUERYDEVICESTRINGEXTPROC>(eglGetProcAddress("eglQueryDeviceStringEXT"));
  if (query_devices == nullptr) return none("the EGL library has no eglQueryDevicesEXT");

  EGLint count = 0;
  if (!query_devices(0, nullptr, &count) || count <= 0) {
    return none("EGL enumerates no device (is an EGL vendor library installed?)");
  }
  std::vector<EGLDeviceEXT> devices(static_cast<size_t>(count));
  if (!query_devices(count, devices.data(), &count)) return none("eglQueryDevicesEXT failed");
  devices.resize(static_cast<size_t>(count));

  for (size_t i = 0; i < devices.size(); ++i) {
    const char* ext = query_string ? query_string(devices[i], EGL_EXTENSIONS) : nullptr;
    const char* file = nullptr;
    if (query_string && has_word(ext, "EGL_EXT_device_drm")) file = query_string(devices[i], EGL_DRM_DEVICE_FILE_EXT);
    DisplayCandidate c;
    c.platform = EGL_PLATFORM_DEVICE_EXT;
    c.native = devices[i];
    if (has_word(ext, "EGL_NV_device_cuda")) {
      c.kind = DisplayKind::nvidia;
    } else if (has_word(ext, "EGL_MESA_device_software")) {
      c.kind = DisplayKind::software;
    } else {
      c.kind = DisplayKind::hardware;
    }
    std::string what = c.kind == DisplayKind::nvidia     ? "NVIDIA"
                       : c.kind == DisplayKind::software ? "software"
                       : file                            ? file
                                                         : "hardware";
    if (c.kind == DisplayKind::nvidia && file) what += std::string(" ") + file;
    c.label = "EGL device " + std::to_string(i) + " (" + what + ")";
    out.push_back(std::move(c));
  }
  return out;
}

std::string nvidia_without_egl(const std::vector<DisplayCandidate>& devices) {
  for (const auto& d : devices) {
    if (d.kind == DisplayKind::nvidia || d.kind == DisplayKind::hardware) return "";  // a GPU EGL can use
  }
  // The device nodes, which a container has only when a GPU is passed in
  // (the driver's /proc entry shows through in any container on the host).
  std::error_code ec;
  for (const char* file : {"/dev/nvidiactl", "/dev/nvidia0"}) {
    if (std::filesystem::exists(file, ec)) {
      return std::string("an NVIDIA GPU is here (") + file +
             ") but EGL lists no GPU device: NVIDIA's EGL vendor library (libEGL_nvidia.so.0 and "
             "/usr/share/glvnd/egl_vendor.d/10_nvidia.json) is missing or not visible; in a container, "
             "NVIDIA_DRIVER_CAPABILITIES must include graphics";
    }
  }
  return "";
}

bool surfaceless_available() { return has_word(client_extensions(), "EGL_MESA_platform_surfaceless"); }

DisplayCandidate surfaceless_candidate() {
  DisplayCandidate c;
  c.label = "Mesa surfaceless";
  c.kind = DisplayKind::surfaceless;
  c.platform = EGL_PLATFORM_SURFACELESS_MESA;
  c.native = EGL_DEFAULT_DISPLAY;
  return c;
}

EGLDisplay acquire_display(const DisplayCandidate& candidate, std::string& why) {
  const EGLDisplay display = eglGetPlatformDisplay(candidate.platform, candidate.native, nullptr);
  if (display == EGL_NO_DISPLAY) {
    why = candidate.label + ": eglGetPlatformDisplay failed with " + egl_error_name(eglGetError());
    return EGL_NO_DISPLAY;
  }
  std::lock_guard lock(registry_mutex());
  int& users = registry()[display];
  if (users == 0) {
    EGLint major = 0, minor = 0;
    if (!eglInitialize(display, &major, &minor)) {
      why = candidate.label + ": eglInitialize failed with " + egl_error_name(eglGetError());
      registry().erase(display);
      return EGL_NO_DISPLAY;
    }
  }
  ++users;
  return display;
}

void release_display(EGLDisplay display) {
  if (display == EGL_NO_DISPLAY) return;
  std::lock_guard lock(registry_mutex());
  auto it = registry().find(display);
  if (it == registry().end()) return;
  if (--it->second == 0) {
    eglTerminate(display);
    registry().erase(it);
  }
}

}  // namespace gtrack::gl
