// The logger's lines while a piece of a test runs.
#pragma once

#include <memory>
#include <spdlog/sinks/ostream_sink.h>
#include <sstream>
#include <string>

#include "gtrack/log.hpp"

namespace gtrack::testing {

// What the logger wrote while `f` ran (its sink removed again on a throw).
template <class F>
std::string logged(F&& f) {
  std::ostringstream log;
  logger().sinks().push_back(std::make_shared<spdlog::sinks::ostream_sink_mt>(log));
  try {
    f();
  } catch (...) {
    logger().sinks().pop_back();
    throw;
  }
  logger().sinks().pop_back();
  return log.str();
}

}  // namespace gtrack::testing
