// GLSL programs assembled from the files in shaders/.
//
// Shaders are data files, found at run time: first in GTRACK_SHADER_DIR (when
// set), then in <data_dir()>/shaders (the build tree or install prefix). A
// stage is compiled from several source strings: a prelude made in C++
// (#version, #extension, #define of feature flags and sizes) followed by the
// files in order, so that shared code such as the posing math lives in one
// file. Each file is source string k (the prelude is 0) and starts with
// "#line 1 k", so driver logs count its lines from its own start; an error
// message names the file and line of the first error, and lists which number
// is which file.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "gl/gl_api.hpp"

namespace gtrack::gl {

struct ShaderStage {
  GLenum type = 0;                 // GL_VERTEX_SHADER, GL_FRAGMENT_SHADER, GL_COMPUTE_SHADER
  std::vector<std::string> files;  // names inside the shader folder, in order
  std::string prelude;             // lines for this stage only, after the program's prelude (#extension ...)
};

// The folders searched for shader files, in order.
std::vector<std::filesystem::path> shader_search_dirs();

// Compiles and links; returns the program name. Throws gtrack::Error naming
// the file and line of a compile error (the stage's files when the log's form
// is not known) and carrying the driver's log (on one line) on failure, or the
// folders searched when a file is missing.
GLuint build_program(const Api& gl, const std::string& prelude, const std::vector<ShaderStage>& stages);

}  // namespace gtrack::gl
