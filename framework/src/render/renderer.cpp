// Choosing a render backend by name.
#include <string>

#include "gtrack/error.hpp"
#include "gtrack/renderer.hpp"

namespace gtrack {

Renderer::~Renderer() = default;

std::unique_ptr<Renderer> make_renderer(const RenderOptions& options) {
  const std::string& b = options.backend;
  if (b == "cpu") return make_cpu_renderer(options);
  if (b == "gl") return make_gl_renderer(options);
  if (b == "auto") return hardware_gpu_available() ? make_gl_renderer(options) : make_cpu_renderer(options);
  throw Error("unknown render backend '" + b + "'; valid backends are: auto, gl, cpu");
}

#ifndef GTRACK_WITH_GL
std::unique_ptr<Renderer> make_gl_renderer(const RenderOptions&) {
  throw Error("gl backend not built (configure with -DGTRACK_WITH_GL=ON); use the cpu backend");
}

bool hardware_gpu_available() { return false; }
#endif

}  // namespace gtrack
