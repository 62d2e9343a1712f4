// Replacing a file whole: its new text goes to FILE.tmp, which is then
// renamed over FILE, so a reader (or a resumed run) never sees it half
// written. Durable: FILE.tmp's data reach the disk before the rename, and the
// rename before the call returns, so a power loss leaves the old or the new
// text, not an empty file.
#pragma once

#include <fcntl.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <system_error>

#include "gtrack/error.hpp"
#include "gtrack/text_file.hpp"

namespace gtrack::detail {

// Flushes a file's (or a folder's) data from the page cache to the disk.
inline void sync_to_disk(const std::filesystem::path& path) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) throw InputError(path.string() + ": cannot open to sync to the disk");
  const int rc = ::fsync(fd);
  ::close(fd);
  if (rc != 0) throw InputError(path.string() + ": syncing to the disk failed");
}

inline void replace_file(const std::filesystem::path& file, const std::string& text, bool durable = false) {
  const std::filesystem::path tmp = file.string() + ".tmp";
  try {
    write_text_file(tmp, text);
  } catch (const InputError& e) {
    std::error_code ec;
    std::filesystem::remove(tmp, ec);  // no half-written file is left behind
    // Said of the file the run writes, not of its stand-in.
    std::string what = e.what();
    if (what.rfind(tmp.string(), 0) == 0) what.replace(0, tmp.string().size(), file.string());
    throw InputError(what);
  }
  if (durable) sync_to_disk(tmp);
  std::error_code ec;
  std::filesystem::rename(tmp, file, ec);
  if (ec) throw InputError(file.string() + ": cannot replace (" + ec.message() + ")");
  if (durable) sync_to_disk(file.has_parent_path() ? file.parent_path() : std::filesystem::path("."));
}

}  // namespace gtrack::detail
