// The framework owns the logger and shares it with plugins.
//
// Plugins log through gtrack::logger(), never through a logger of their own,
// so that --log-level and the sinks chosen by the front end apply to them too.
#pragma once

#include <spdlog/spdlog.h>

#include <string_view>

#include "gtrack/export.hpp"

namespace gtrack {

GTRACK_API spdlog::logger& logger();

// Sets the level from a name (trace, debug, info, warn, error, critical, off).
// Throws gtrack::Error naming the accepted values on an unknown name.
GTRACK_API void set_log_level(std::string_view level);

}  // namespace gtrack
