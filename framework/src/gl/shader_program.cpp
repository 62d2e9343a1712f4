// Finding, reading, compiling and linking shader files.
#include "gl/shader_program.hpp"

#include <algorithm>
#include <cstdlib>
#include <fstream>
#include <sstream>

#include "gtrack/error.hpp"
#include "gtrack/plugin_loader.hpp"

namespace gtrack::gl {

namespace fs = std::filesystem;

namespace {

struct SourceFile {
  fs::path path;
  std::string text;
};

SourceFile read_shader(const std::string& name, const std::vector<fs::path>& dirs) {
  for (const fs::path& dir : dirs) {
    const fs::path p = dir / name;
    std::ifstream in(p, std::ios::binary);
    if (!in) continue;
    std::ostringstream text;
    text << in.rdbuf();
    return {p, text.str()};
  }
  std::string searched;
  for (const auto& d : dirs) searched += (searched.empty() ? "" : ", ") + d.string();
  throw Error("gl backend: shader file '" + name + "' not found (searched: " + searched +
              "); set GTRACK_SHADER_DIR to the folder holding gtrack's shaders");
}

// Driver logs span lines; gtrack errors are one line.
std::string one_line(std::string log) {
  while (!log.empty() && (log.back() == '\n' || log.back() == '\r' || log.back() == ' ' || log.back() == '\0')) {
    log.pop_back();
  }
  std::string out;
  for (char c : log) {
    if (c == '\n') {
      out += " | ";
    } else if (c != '\r') {
      out += c;
    }
  }
  return out;
}

const char* stage_name(GLenum type) {
  switch (type) {
    case GL_VERTEX_SHADER: return "vertex";
    case GL_FRAGMENT_SHADER: return "fragment";
    case GL_COMPUTE_SHADER: return "compute";
    default: return "shader";
  }
}

}  // namespace

std::vector<fs::path> shader_search_dirs() {
  std::vector<fs::path> dirs;
  if (const char* env = std::getenv("GTRACK_SHADER_DIR"); env && *env) dirs.emplace_back(env);
  dirs.push_back(data_dir() / "shaders");
  return dirs;
}

GLuint build_program(const Api& gl, const std::string& prelude, const std::vector<ShaderStage>& stages) {
  const std::vector<fs::path> dirs = shader_search_dirs();
  std::vector<GLuint> shaders;
  auto cleanup = [&](GLuint program) {
    for (GLuint s : shaders) gl.DeleteShader(s);
    if (program != 0) gl.DeleteProgram(program);
  };

  std::string all_files;
  for (const ShaderStage& stage : stages) {
    std::vector<SourceFile> files;
    try {
      for (const std::string& name : stage.files) files.push_back(read_shader(name, dirs));
    } catch (...) {
      cleanup(0);
      throw;
    }
    std::vector<const GLchar*> strings{prelude.c_str()};
    std::string legend = "source strings: 0 = prelude";
    for (size_t i = 0; i < files.size(); ++i) {
      strings.push_back(files[i].text.c_str());
      legend += ", " + std::to_string(i + 1) + " = " + files[i].path.filename().string();
    }
    const fs::path& main_file = files.back().path;
    all_files += (all_files.empty() ? "" : ", ") + main_file.string();

    const GLuint shader = gl.CreateShader(stage.type);
    shaders.push_back(shader);
    gl.ShaderSource(shader, static_cast<GLsizei>(strings.size()), strings.data(), nullptr);
    gl.CompileShader(shader);
    GLint ok = GL_FALSE, length = 0;
    gl.GetShaderiv(shader, GL_COMPILE_STATUS, &ok);
    if (!ok) {
      gl.GetShaderiv(shader, GL_INFO_LOG_LENGTH, &length);
      std::string log(static_cast<size_t>(std::max(length, 1)), '\0');
      gl.GetShaderInfoLog(shader, length, nullptr, log.data());
      cleanup(0);
      throw Error("gl backend: cannot compile " + std::string(stage_name(stage.type)) + " shader " +
                  main_file.string() + ": " + one_line(log) + " (" + legend + ")");
    }
  }

  const GLuint program = gl.CreateProgram();
  for (GLuint s : shaders) gl.AttachShader(program, s);
  gl.LinkProgram(program);
  GLint ok = GL_FALSE, length = 0;
  gl.GetProgramiv(program, GL_LINK_STATUS, &ok);
  if (!ok) {
    gl.GetProgramiv(program, GL_INFO_LOG_LENGTH, &length);
    std::string log(static_cast<size_t>(std::max(length, 1)), '\0');
    gl.GetProgramInfoLog(program, length, nullptr, log.data());
    cleanup(program);
    throw Error("gl backend: cannot link the program of " + all_files + ": " + one_line(log));
  }
  // Linked programs keep their code; the shader objects are no longer needed.
  cleanup(0);
  return program;
}

}  // namespace gtrack::gl
