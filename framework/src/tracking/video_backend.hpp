// Which OpenCV backend opens a recorded video.
#pragma once

#include <opencv2/videoio.hpp>
#include <opencv2/videoio/registry.hpp>

namespace gtrack::detail {

// FFmpeg alone when it is there: given an undecodable file, the other
// backends print pages of warnings, and the camera libraries among them
// list USB devices (leaking what they list).
inline int video_backend() {
  return cv::videoio_registry::hasBackend(cv::CAP_FFMPEG) ? cv::CAP_FFMPEG : cv::CAP_ANY;
}

}  // namespace gtrack::detail
