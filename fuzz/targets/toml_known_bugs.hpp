// Inputs that hit a known defect of the TOML++ release that Debian 12 ships
// (3.3.0), skipped so that fuzzing goes on finding our own bugs.
//
// toml::impl::is_non_ascii_horizontal_whitespace() reaches TOML_UNREACHABLE
// (__builtin_unreachable: undefined behaviour) for code points in three
// blocks of its lookup table that have no case: U+00A1..U+0499,
// U+2CEE..U+30E7 (except U+3000) and U+FA06..U+FEFE. It is asked about such a
// code point when one stands where a bare key, a table name or a line-ending
// backslash continuation is parsed, e.g. `[grippér]` or `fµ = 1`.
// Upstream: marzer/tomlplusplus issue #190 and pull request #305 (default
// case returns false). fuzz/crashes/toml_unreachable_* keep the inputs;
// tests/regression_test.cpp checks what the g++ build does with them.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string_view>

namespace gtrack_fuzz {

inline bool hits_toml_unreachable(char32_t c) {
  return (c >= 0xA1 && c < 0x49A) || (c >= 0x2CEE && c < 0x30E8 && c != 0x3000) || (c >= 0xFA06 && c < 0xFEFF);
}

// True when the text holds any such code point (decoding UTF-8 leniently:
// malformed sequences are left to the parser, which rejects them).
inline bool has_toml_unreachable_code_point(std::string_view s) {
  for (size_t i = 0; i < s.size();) {
    const auto b = static_cast<unsigned char>(s[i]);
    int n = b < 0x80 ? 1 : (b >> 5) == 0x6 ? 2 : (b >> 4) == 0xE ? 3 : (b >> 3) == 0x1E ? 4 : 1;
    if (i + n > s.size()) return false;
    char32_t c = n == 1 ? b : n == 2 ? (b & 0x1F) : n == 3 ? (b & 0x0F) : (b & 0x07);
    for (int k = 1; k < n; ++k) c = (c << 6) | (static_cast<unsigned char>(s[i + k]) & 0x3F);
    if (n > 1 && hits_toml_unreachable(c)) return true;
    i += n;
  }
  return false;
}

}  // namespace gtrack_fuzz
