// The one logger of the process, shared with every plugin.
#include "gtrack/log.hpp"

#include <opencv2/core/utils/logger.hpp>
#include <spdlog/sinks/stdout_color_sinks.h>

#include "gtrack/error.hpp"

namespace gtrack {

spdlog::logger& logger() {
  static std::shared_ptr<spdlog::logger> log = [] {
    auto l = spdlog::stderr_color_mt("gtrack");
    l->set_pattern("[%l] %v");
    return l;
  }();
  return *log;
}

void set_log_level(std::string_view level) {
  auto lvl = spdlog::level::from_str(std::string(level));
  if (lvl == spdlog::level::off && level != "off") {
    throw Error("--log-level: unknown level '" + std::string(level) +
                "'; expected one of trace, debug, info, warn, error, critical, off");
  }
  logger().set_level(lvl);
  // OpenCV's own warnings (a camera backend probing, a codec) show only when
  // gtrack's are asked for at debug level or finer. Never its info lines:
  // OpenCV writes those to stdout, which holds results (--stream's JSON
  // lines, eval's report) and nothing else.
  namespace cvlog = cv::utils::logging;
  cvlog::setLogLevel(lvl <= spdlog::level::debug ? cvlog::LOG_LEVEL_WARNING
                     : lvl == spdlog::level::off ? cvlog::LOG_LEVEL_SILENT
                                                 : cvlog::LOG_LEVEL_ERROR);
}

}  // namespace gtrack
