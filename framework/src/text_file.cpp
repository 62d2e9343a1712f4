#include "gtrack/text_file.hpp"

#include <cerrno>
#include <cstring>
#include <fstream>
#include <system_error>

#include "gtrack/error.hpp"

namespace gtrack {
namespace {

// 16777216 -> "16 MiB", 65536 -> "64 KiB", 1000 -> "1000 bytes".
std::string byte_count(std::size_t n) {
  if (n >= (1u << 20) && n % (1u << 20) == 0) return std::to_string(n >> 20) + " MiB";
  if (n >= (1u << 10) && n % (1u << 10) == 0) return std::to_string(n >> 10) + " KiB";
  return std::to_string(n) + " bytes";
}

}  // namespace

bool read_bounded_line(std::istream& in, std::string& line, std::size_t max_chars, const std::string& source,
                       int line_no, const std::string& expected) {
  line.clear();
  for (int c; (c = in.get()) != std::char_traits<char>::eof();) {
    if (c == '\n') return true;
    if (line.size() >= max_chars) {
      throw InputError(source + ":" + std::to_string(line_no) + ": a line of more than " + std::to_string(max_chars) +
                       " characters; expected " + expected);
    }
    line.push_back(static_cast<char>(c));
  }
  return !line.empty();
}

std::string read_text_file(const std::filesystem::path& file, std::size_t max_bytes, const std::string& expected) {
  std::error_code ec;
  if (std::filesystem::is_directory(file, ec)) throw InputError(file.string() + ": is a folder; expected " + expected);
  std::ifstream in(file, std::ios::binary);
  if (!in) throw InputError(file.string() + ": cannot open (does it exist and is it readable?); expected " + expected);
  std::string text;
  char buf[1 << 16];
  while (in.read(buf, sizeof buf) || in.gcount() > 0) {
    text.append(buf, static_cast<std::size_t>(in.gcount()));
    if (text.size() > max_bytes) {
      throw InputError(file.string() + ": more than " + byte_count(max_bytes) + "; expected " + expected);
    }
  }
  if (in.bad()) throw InputError(file.string() + ": cannot read; expected " + expected);
  return text;
}

void write_text_file(const std::filesystem::path& file, const std::string& text) {
  errno = 0;
  std::ofstream out(file, std::ios::trunc | std::ios::binary);
  if (!out) throw InputError(file.string() + ": cannot open for writing (" + write_failure_reason() + ")");
  out << text;
  out.flush();  // a full disk shows when the buffer goes out
  if (!out) throw InputError(file.string() + ": write failed (" + write_failure_reason() + ")");
}

std::string write_failure_reason() {
  // std::error_code's message, not strerror: synth's threads write frames.
  return errno != 0 ? std::error_code(errno, std::generic_category()).message() : "disk full?";
}

}  // namespace gtrack
