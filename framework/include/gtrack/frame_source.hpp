// Where frames come from: a video file, a folder of images, or a live camera.
//
// open_frame_source() decides by the string: "camera:N" opens device N, an
// existing folder is read as its image files sorted by name, anything else is
// opened as a video with cv::VideoCapture. Every frame must have the sensor's
// image size; a mismatch is an InputError naming the file (or frame) and both
// sizes. Frame indices count every frame of the source, including frames
// skipped by `every` or outside the range, so results line up with the input.
#pragma once

#include <atomic>
#include <filesystem>
#include <memory>
#include <opencv2/core.hpp>
#include <optional>
#include <string>

#include "gtrack/export.hpp"
#include "gtrack/sensor.hpp"

namespace gtrack {

struct Frame {
  int index = 0;      // position in the source (0-based)
  double time_s = 0;  // index / fps
  cv::Mat image;      // BGR, CV_8UC3
  std::string name;   // file name or "frame N", for messages
};

// A half-open range [first, last) of frame indices; last < 0 = to the end.
struct FrameRange {
  int first = 0;
  int last = -1;
  int every = 1;
};
// Parses "A:B", "A:", ":B" or "A" (A inclusive, B exclusive).
GTRACK_API FrameRange parse_frame_range(const std::string& text);

class GTRACK_API FrameSource {
 public:
  virtual ~FrameSource();
  // Next frame of the range, or nullopt at the end.
  virtual std::optional<Frame> next() = 0;
  // Frames per second of the source (0 if unknown: folders, some cameras).
  virtual double fps() const = 0;
  // Frames in the source, or -1 when unknown (live camera).
  virtual int frame_count() const = 0;
  virtual std::string description() const = 0;
};

// A folder that acquisition software is still writing images into: once
// the images there are tracked, the source waits for new ones (in name
// order, after the last one taken) and ends when none has come for idle_s
// seconds, or when *cancel is raised. An image that does not decode yet (it
// is still being written) is read again while its size changes and for two
// seconds after it last changed.
struct FollowOptions {
  double idle_s = 0;                          // 0: do not follow
  const std::atomic<bool>* cancel = nullptr;  // raised: stop waiting
};

// Throws InputError for a missing or unreadable video, an empty folder, a
// camera that does not open. `fallback_fps` times frames when the source has
// no rate of its own.
GTRACK_API std::unique_ptr<FrameSource> open_frame_source(const std::string& spec, ImageSize expected,
                                                          FrameRange range, double fallback_fps);
// The same; `follow` (idle_s > 0) follows a folder, and is refused for any
// other input.
GTRACK_API std::unique_ptr<FrameSource> open_frame_source(const std::string& spec, ImageSize expected,
                                                          FrameRange range, double fallback_fps,
                                                          const FollowOptions& follow);

}  // namespace gtrack
