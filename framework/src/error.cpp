// Quoting input text in messages.
#include "gtrack/error.hpp"

#include <cstdio>
#include <regex>

namespace gtrack {

std::string shown(std::string_view text, std::size_t max, bool ascii) {
  std::string out;
  for (std::size_t i = 0; i < text.size() && i < max; ++i) {
    const unsigned char c = static_cast<unsigned char>(text[i]);
    if (c < 0x20 || c == 0x7f || (ascii && c > 0x7f)) {
      char buf[8];
      std::snprintf(buf, sizeof buf, "\\x%02X", c);
      out += buf;
    } else {
      out += static_cast<char>(c);
    }
  }
  if (text.size() > max) out += "... (" + std::to_string(text.size()) + " characters)";
  return out;
}

std::string library_words(std::string text) {
  static const std::regex opencv(R"(OpenCV\([0-9.]+[^)]*\) \S+:[0-9]+: error: \(-?[0-9]+:([^)]*)\) )");
  static const std::regex function(R"( in function '[^']*')");
  static const std::regex ffmpeg(R"(\[([^\]@]+?) @ 0x[0-9a-fA-F]+\] )");
  text = std::regex_replace(text, opencv, "$1: ");
  text = std::regex_replace(text, function, "");
  text = std::regex_replace(text, ffmpeg, "$1: ");
  while (!text.empty() && (text.back() == '\n' || text.back() == '\r' || text.back() == ' ')) text.pop_back();
  return text;
}

}  // namespace gtrack
