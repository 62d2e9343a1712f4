// Errors that reach the user.
//
// Every error gtrack reports is one line that says where (file, line, key or
// plugin) and what was expected. The command-line front end catches
// gtrack::Error, prints what(), and exits non-zero; nothing below it prints a
// stack trace or aborts on bad input.
#pragma once

#include <stdexcept>
#include <string>

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

}  // namespace gtrack
