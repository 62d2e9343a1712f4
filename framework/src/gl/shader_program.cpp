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

// Where the first error of a driver's log is: the source string's number and
// the line in it, as Mesa ("2:13(5): error: ..."), NVIDIA ("2(13) : error
// C0000: ...") and others ("ERROR: 2:13: ...") write them. Warnings are
// skipped. False when no error line has one of these forms.
bool first_error_place(const std::string& log, int& string_number, int& line) {
  std::istringstream lines(log);
  for (std::string l; std::getline(lines, l);) {
    if (l.find("error") == std::string::npos && l.find("ERROR") == std::string::npos) continue;
    const size_t prefix = l.rfind("ERROR: ", 0) == 0 ? 7 : 0;
    const char* p = l.c_str() + prefix;
    while (*p == ' ') ++p;
    char* end = nullptr;
    const long k = std::strtol(p, &end, 10);
    if (end == p || k < 0) continue;
    const char* q = end;
    if (*q != ':' && *q != '(') continue;
    const long n = std::strtol(q + 1, &end, 10);
    if (end == q + 1 || n < 0) continue;
    if (*q == '(' && *end != ')') continue;
    if (*q == ':' && *end != '(' && *end != ':') continue;
    string_number = static_cast<int>(k);
    line = static_cast<int>(n);
    return true;
  }
  return false;
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
    // File k is source string k, its lines counted from 1: drivers count on
    // from the start of string 0 otherwise (Mesa does), and report that. The
    // #line directive comes after the prelude's #version, which must be first;
    // the newline before it ends a file whose last line has none.
    std::vector<std::string> texts;
    std::string legend = "source strings: 0 = prelude";
    std::string stage_files;
    for (size_t i = 0; i < files.size(); ++i) {
      texts.push_back("\n#line 1 " + std::to_string(i + 1) + "\n" + files[i].text);
      legend += ", " + std::to_string(i + 1) + " = " + files[i].path.filename().string();
      stage_files += (stage_files.empty() ? "" : ", ") + files[i].path.string();
    }
    all_files += (all_files.empty() ? "" : ", ") + stage_files;
    const std::string stage_prelude = prelude + stage.prelude;
    std::vector<const GLchar*> strings{stage_prelude.c_str()};
    for (const std::string& t : texts) strings.push_back(t.c_str());

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
      // The file and line of the first error, when the log says which they
      // are; the stage's files otherwise.
      std::string where = "of " + stage_files;
      int string_number = -1, line = 0;
      if (first_error_place(log, string_number, line)) {
        if (string_number >= 1 && static_cast<size_t>(string_number) <= files.size()) {
          where = files[static_cast<size_t>(string_number - 1)].path.string() + ":" + std::to_string(line);
        } else if (string_number == 0) {
          where = "prelude:" + std::to_string(line);
        }
      }
      throw Error("gl backend: cannot compile " + std::string(stage_name(stage.type)) + " shader " + where +
                  ": " + one_line(log) + " (" + legend + ")");
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
