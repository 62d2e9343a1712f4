// Errors that reach the user.
//
// Every error gtrack reports is one line that says where (file, line, key or
// plugin) and what was expected. The command-line front end catches
// gtrack::Error, prints what(), and exits non-zero; nothing below it prints a
// stack trace or aborts on bad input.
#pragma once

#include <cstddef>
#include <stdexcept>
#include <string>
#include <string_view>

#include "gtrack/export.hpp"

namespace gtrack {

class GTRACK_API Error : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// A config file, or a plugin's table in it, is malformed.
class GTRACK_API ConfigError : public Error {
 public:
  using Error::Error;
};

// A plugin could not be found, loaded, checked or constructed.
class GTRACK_API PluginError : public Error {
 public:
  using Error::Error;
};

// An input (video, image folder, stimulus log, parameter vector) is unusable.
class GTRACK_API InputError : public Error {
 public:
  using Error::Error;
};

// Text from an input as a message quotes it, so that the message stays one
// short line: control bytes (and, with `ascii`, every byte outside printable
// ASCII) as \xNN, and at most `max` bytes of it, followed by
// "... (N characters)" when cut.
GTRACK_API std::string shown(std::string_view text, std::size_t max = std::string_view::npos, bool ascii = false);

// A library's own words, as a message quotes them: OpenCV's "OpenCV(4.6.0)
// ./modules/core/src/alloc.cpp:73: error: (-4:Insufficient memory) Failed
// to allocate ... in function 'f'" becomes "Insufficient memory: Failed to
// allocate ...", and
// FFmpeg's "[h264 @ 0x55d0c0a1b2c0] error while decoding" becomes "h264:
// error while decoding"; trailing line ends go.
GTRACK_API std::string library_words(std::string text);

}  // namespace gtrack
