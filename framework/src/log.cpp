// The one logger of the process, shared with every plugin.
#include "gtrack/log.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <opencv2/core/utils/logger.hpp>
#include <spdlog/sinks/ansicolor_sink.h>

#include "console.hpp"
#include "gtrack/error.hpp"

namespace gtrack {

namespace detail {

std::FILE* console() {
  static std::FILE* const stream = [] {
    const int fd = ::fcntl(STDERR_FILENO, F_DUPFD_CLOEXEC, 3);
    std::FILE* f = fd >= 0 ? ::fdopen(fd, "w") : nullptr;
    if (!f) {
      if (fd >= 0) ::close(fd);
      return stderr;
    }
    std::setvbuf(f, nullptr, _IONBF, 0);  // as stderr: each message out as it is written
    return f;
  }();
  return stream;
}

}  // namespace detail

spdlog::logger& logger() {
  static std::shared_ptr<spdlog::logger> log = [] {
    auto sink = std::make_shared<spdlog::sinks::ansicolor_sink<spdlog::details::console_mutex>>(
        detail::console(), spdlog::color_mode::automatic);
    auto l = std::make_shared<spdlog::logger>("gtrack", std::move(sink));
    spdlog::register_logger(l);
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
