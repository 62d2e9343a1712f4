// hardware_gpu_available(): whether "auto" should pick the gl backend.
#include <mutex>

#include "gl/egl_context.hpp"
#include "gtrack/log.hpp"
#include "gtrack/renderer.hpp"

namespace gtrack {

namespace {

bool probe() {
  // Software devices are never worth a context: only hardware ones are tried,
  // so on a machine without a GPU this is one device enumeration.
  const std::vector<gl::DisplayCandidate> devices = gl::list_devices();
  if (const std::string missing = gl::nvidia_without_egl(devices); !missing.empty()) {
    logger().warn("render backend auto: {}; rendering on the cpu backend", missing);
  }
  std::vector<gl::DisplayCandidate> hardware;
  for (const auto& d : devices) {
    if (d.kind == gl::DisplayKind::nvidia || d.kind == gl::DisplayKind::hardware) hardware.push_back(d);
  }
  for (const auto& d : hardware) {
    std::string why;
    gl::EglContext context = gl::EglContext::try_open({d}, why);
    if (context && !context.software()) return true;
  }
  return false;
}

}  // namespace

bool hardware_gpu_available() {
  static std::once_flag once;
  static bool available = false;
  std::call_once(once, [] {
    try {
      available = probe();
    } catch (...) {
      available = false;
    }
  });
  return available;
}

}  // namespace gtrack
