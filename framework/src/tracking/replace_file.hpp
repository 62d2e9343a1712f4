// Replacing a file whole: its new text goes to FILE.tmp, which is then
// renamed over FILE, so a reader (or a resumed run) never sees it half
// written.
#pragma once

#include <filesystem>
#include <fstream>
#include <string>
#include <system_error>

#include "gtrack/error.hpp"

namespace gtrack::detail {

inline void replace_file(const std::filesystem::path& file, const std::string& text) {
  const std::filesystem::path tmp = file.string() + ".tmp";
  {
    std::ofstream out(tmp, std::ios::trunc | std::ios::binary);
    out << text;
    out.flush();
    if (!out) throw InputError(tmp.string() + ": write failed");
  }
  std::error_code ec;
  std::filesystem::rename(tmp, file, ec);
  if (ec) throw InputError(file.string() + ": cannot replace (" + ec.message() + ")");
}

}  // namespace gtrack::detail
