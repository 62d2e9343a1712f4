// Quoting input text in messages.
#include "gtrack/error.hpp"

#include <cstdio>

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

}  // namespace gtrack
