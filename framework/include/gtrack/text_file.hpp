// Text files in and out, with the two checks every reader and writer of
// outside files needs: a line has a bound (a device or a binary file given by
// mistake, /dev/zero, is one line of error, not all of memory), and a written
// file is flushed before it is checked (a full disk shows when the buffer
// goes out, not before).
#pragma once

#include <cstddef>
#include <filesystem>
#include <istream>
#include <string>

#include "gtrack/export.hpp"

namespace gtrack {

// std::getline with a bound: the next line of `in` without its '\n', false
// at the end of the input (a last line without '\n' is still a line). A line
// of more than `max_chars` characters is an InputError
// "<source>:<line_no>: a line of more than <max_chars> characters; expected <expected>".
GTRACK_API bool read_bounded_line(std::istream& in, std::string& line, std::size_t max_chars, const std::string& source,
                                  int line_no, const std::string& expected);

// The whole of a file (a pipe too) of at most `max_bytes`, which is `expected`
// ("a TOML config file"): a folder, a file that cannot be opened and one that
// never ends (/dev/zero) are InputErrors naming the file.
GTRACK_API std::string read_text_file(const std::filesystem::path& file, std::size_t max_bytes,
                                      const std::string& expected);

// `text` as the whole of `file`, flushed and checked: a file that cannot be
// opened or written (a missing folder, a full disk) is an InputError naming it
// and the system's reason (write_failure_reason).
GTRACK_API void write_text_file(const std::filesystem::path& file, const std::string& text);

// Why the write that just failed did: errno's text ("No space left on
// device"), or "disk full?" when the stream left errno unset.
GTRACK_API std::string write_failure_reason();

}  // namespace gtrack
