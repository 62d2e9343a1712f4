// Choosing a render backend by name.
#include <string>

#include "gtrack/error.hpp"
#include "gtrack/log.hpp"
#include "gtrack/renderer.hpp"

namespace gtrack {

Renderer::~Renderer() = default;

std::unique_ptr<Renderer> make_renderer(const RenderOptions& options) {
  const std::string& b = options.backend;
  if (b == "cpu") return make_cpu_renderer(options);
  if (b == "gl") return make_gl_renderer(options);
  if (b == "auto") {
    if (!hardware_gpu_available()) return make_cpu_renderer(options);
    // A GPU that is there but unusable (driver, permissions) must not stop
    // a run that asked for nothing in particular.
    try {
      return make_gl_renderer(options);
    } catch (const Error& e) {
      logger().warn("render backend auto: gl failed ({}); using cpu", e.what());
      return make_cpu_renderer(options);
    }
  }
  throw Error("unknown render backend '" + b + "'; valid backends are: auto, gl, cpu");
}

#ifndef GTRACK_WITH_GL
std::unique_ptr<Renderer> make_gl_renderer(const RenderOptions&) {
  throw Error("gl backend not built (configure with -DGTRACK_WITH_GL=ON); use the cpu backend");
}

bool hardware_gpu_available() { return false; }
#endif

}  // namespace gtrack
