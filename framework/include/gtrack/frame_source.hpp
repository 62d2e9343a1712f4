// Where frames come from: a video file, a folder of images, or a live camera.
//
// open_frame_source() decides by the string: "camera:N" opens device N, an
// existing folder is read as its image files sorted by name, a .tif/.tiff
// file as a stack whose pages are the frames (a single page: one frame), a
// DICOM file (.dcm, .dicom, or "DICM" at byte 128) as its frames, anything
// else is opened as a video with cv::VideoCapture. Every frame must have the sensor's
// image size; a mismatch is an InputError naming the file (or frame) and both
// sizes. Frame indices count every frame of the source, including frames
// skipped by `every` or outside the range, so results line up with the input.
#pragma once

#include <atomic>
#include <cstdint>
#include <filesystem>
#include <map>
#include <memory>
#include <opencv2/core.hpp>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "gtrack/export.hpp"
#include "gtrack/sensor.hpp"

namespace gtrack {

struct Frame {
  // Position in the source (0-based); for a video whose time stamps agree
  // with its rate, the stamp's (a dropped frame's number is skipped).
  int index = 0;
  double time_s = 0;  // index / fps
  cv::Mat image;      // BGR, CV_8UC3
  std::string name;   // file name or "frame N", for messages
  // Following a folder: the time spent waiting for the image to arrive and
  // to be written whole, which is the camera's, not reading.
  double waited_s = 0;
  // When it had been read, seconds since the Unix epoch (set by the reader
  // of gtrack track; 0 otherwise).
  double read_unix_s = 0;
  // An image file's modification time (seconds since the Unix epoch; 0 for
  // a video, a stack or a camera): in a followed folder, when the camera's
  // software finished writing it.
  double written_unix_s = 0;
};

// A half-open range [first, last) of frame indices; last < 0 = to the end.
struct FrameRange {
  int first = 0;
  int last = -1;
  int every = 1;

  // Whether source index `index` is one the range takes.
  bool contains(int index) const {
    return index >= first && (last < 0 || index < last) && (index - first) % (every > 1 ? every : 1) == 0;
  }
};
// Parses "A:B", "A:", ":B" or "A" (A inclusive, B exclusive).
GTRACK_API FrameRange parse_frame_range(const std::string& text);

// A frame as the tracker takes it (8-bit BGR), from what a camera or a
// file gives: grey, grey and alpha, BGR or BGRA, 8 or 16 bits per sample;
// 16-bit samples are scaled by 255 / (2^image_bits - 1), image_bits being
// how many low bits the camera fills ([tracker] image_bits; 16 for data in
// the high bits). What every FrameSource does to its frames, for frames
// grabbed by an application and given to Tracker::process. InputError
// (naming `name`) for other depths or channel counts.
GTRACK_API cv::Mat to_tracker_image(const cv::Mat& image, int image_bits = 16, const std::string& name = "frame");

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
  // Once next() has ended: why the source ended before the frames it
  // declared (a video the decoder gave up on part way), or "" when it did not.
  virtual std::string ended_early() const { return {}; }
  // Frames of the range left out, unread, for a newer one (a followed
  // folder with FollowOptions::newest).
  virtual int skipped() const { return 0; }
  // The size of a pixel (width, height, mm) when the input says it: a
  // DICOM file's ultrasound region. None otherwise.
  virtual std::optional<std::pair<double, double>> pixel_size_mm() const { return std::nullopt; }
  // Significant bits of 16-bit images, 8 to 16 (default 16): a 16-bit image
  // is scaled to 8 bits by 255 / (2^bits - 1), values above 2^bits - 1
  // saturating. The first 16-bit image is warned about when its values use
  // less than a sixteenth of that range.
  void set_image_bits(int bits);
  // Leaves out the warnings about what the input is (a stack's layout, dark
  // 16-bit images): for a source that reads again what another one has
  // read and warned about.
  void set_quiet() { quiet_ = true; }

 protected:
  // An image as delivered: 8-bit BGR.
  cv::Mat to_bgr(const cv::Mat& image, const std::string& name);
  bool quiet() const { return quiet_; }

 private:
  int image_bits_ = 16;
  bool checked_bits_ = false;
  bool quiet_ = false;
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
  // Each frame is the newest image listed when it is asked for; the images
  // listed before it are left out undecoded (FrameSource::skipped()).
  bool newest = false;
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

// The frames of a recording (a video file or a folder of images) read
// again, a block at a time and in any order (the backward pass of
// `--two-pass`). A folder's images are read by their place in name order,
// as open_frame_source numbers them (an image removed since shifts the
// ones after it; only frames past the folder's end are noticed). A video
// is decoded once, in order, the first time a block does not start at the
// video's first frame (that block is read so), and each frame's pixels
// fingerprinted; later such blocks are read by seeking to their first
// frame and decoding from there, and checked against those fingerprints.
// Seeking is not exact in every video (B-frames, a variable frame rate):
// once a block read so is not what reading in order gave, that block and
// every one after it are decoded from the video's start, with a warning.
class GTRACK_API RecordedFrames {
 public:
  // `frames`: the source indices that will be read again, ascending and a
  // multiple of `every` apart (the forward run's --frames and --every, less
  // any frame missing from a video; std::invalid_argument otherwise). InputError for a live camera.
  RecordedFrames(std::string spec, ImageSize expected, std::vector<int> frames, int every, double fallback_fps);
  // The images of frames[lo], ..., frames[hi - 1], by source index.
  // InputError naming the frame when one can no longer be read, or (a
  // video) is not the frame it was when this reader decoded it in order,
  // and for what open_frame_source refuses.
  std::map<int, cv::Mat> read(std::size_t lo, std::size_t hi);
  // False once seeking has been found not to give the frames read in order
  // (or for a folder, which has no need of it).
  bool seeks() const { return video_ && seeks_; }
  // Blocks read by seeking (the decoder took the seek and the frames were
  // the ones read in order).
  int seeked_blocks() const { return seeked_blocks_; }
  // As FrameSource::set_image_bits, for every frame read (without the
  // warning, which the first pass gave).
  void set_image_bits(int bits) { image_bits_ = bits; }

 private:
  std::map<int, cv::Mat> fingerprint_in_order(std::size_t lo, std::size_t hi);
  // Sets up a source this reader opened: its image bits, and quiet (the
  // first pass warned).
  void reading_again(FrameSource& source) const;

  std::string spec_;
  ImageSize expected_;
  std::vector<int> frames_;
  int every_;
  double fps_;
  bool video_ = false;
  bool seeks_ = true;
  int seeked_blocks_ = 0;
  int image_bits_ = 16;
  int stack_pages_ = 0;  // a TIFF stack's pages, once counted
  std::vector<std::uint64_t> prints_;  // per frame of frames_ (a video, once a block has needed them)
};

}  // namespace gtrack
