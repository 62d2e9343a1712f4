// What a library prints on stderr while gtrack calls it (libpng's "Read
// Error", FFmpeg's "moov atom not found"), taken aside instead of landing
// above gtrack's own one-line error: the caller puts it into that line when
// the call failed, or logs it at debug level when it did not.
#pragma once

#include <unistd.h>

#include <cstdio>
#include <mutex>
#include <string>

#include "console.hpp"
#include "gtrack/error.hpp"

namespace gtrack::detail {

class CapturedStderr {
 public:
  // One capture at a time in the process: fd 2 is the process's.
  CapturedStderr() : lock_(mutex()) {
    console();  // gtrack's own messages keep the stderr of before
    std::fflush(stderr);
    file_ = std::tmpfile();
    saved_ = file_ ? ::dup(STDERR_FILENO) : -1;
    if (saved_ < 0 || ::dup2(::fileno(file_), STDERR_FILENO) < 0) restore();
  }
  ~CapturedStderr() { take(); }
  CapturedStderr(const CapturedStderr&) = delete;
  CapturedStderr& operator=(const CapturedStderr&) = delete;

  // Ends the capture; what was printed, on one line ("" if nothing).
  std::string take() {
    if (!file_) return {};
    std::fflush(stderr);
    restore();
    std::string text;
    std::rewind(file_);
    char buf[512];
    size_t n;
    while ((n = std::fread(buf, 1, sizeof buf, file_)) > 0 && text.size() < 4096) text.append(buf, n);
    std::fclose(file_);
    file_ = nullptr;
    std::string line;
    for (const char c : text) {
      if (c == '\n' || c == '\r') {
        if (!line.empty() && line.back() != ' ') line += "; ";
      } else if (static_cast<unsigned char>(c) >= 0x20) {
        line += c;
      }
    }
    line = library_words(line);
    while (!line.empty() && (line.back() == ' ' || line.back() == ';')) line.pop_back();
    if (line.size() > 300) line = line.substr(0, 297) + "...";
    return line;
  }

 private:
  void restore() {
    if (saved_ >= 0) {
      ::dup2(saved_, STDERR_FILENO);
      ::close(saved_);
      saved_ = -1;
    }
  }
  static std::mutex& mutex() {
    static std::mutex m;
    return m;
  }
  std::lock_guard<std::mutex> lock_;
  std::FILE* file_ = nullptr;
  int saved_ = -1;
};

}  // namespace gtrack::detail
