// Video files, image folders and live cameras behind one interface.
#include "gtrack/frame_source.hpp"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdarg>
#include <cstdint>
#include <fstream>
#include <functional>
#include <limits>
#include <mutex>
#include <stdexcept>
#include <string_view>
#include <thread>
#include <unordered_set>
#include <fmt/format.h>
#include <chrono>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>
#include <tiffio.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

#include "captured_stderr.hpp"
#include "dicom.hpp"
#include "image_header.hpp"
#include "input_kind.hpp"
#include "video_backend.hpp"
#include "gtrack/error.hpp"
#include "gtrack/log.hpp"
#include "gtrack/text_file.hpp"

namespace gtrack {

namespace fs = std::filesystem;

FrameSource::~FrameSource() = default;

void FrameSource::set_image_bits(int bits) {
  if (bits < 8 || bits > 16) throw std::invalid_argument("FrameSource::set_image_bits: expected 8 to 16 bits");
  image_bits_ = bits;
}

namespace {

// Grey and alpha, or BGRA: the colour channels only.
cv::Mat without_alpha(const cv::Mat& image) {
  cv::Mat out = image;
  if (out.channels() == 2) {
    cv::extractChannel(out, out, 0);
  } else if (out.channels() == 4) {
    cv::cvtColor(out, out, cv::COLOR_BGRA2BGR);
  }
  return out;
}

}  // namespace

cv::Mat to_tracker_image(const cv::Mat& image, int image_bits, const std::string& name) {
  if (image.depth() != CV_8U && image.depth() != CV_16U) {
    const char* depth = image.depth() == CV_32F   ? "32-bit float"
                        : image.depth() == CV_64F ? "64-bit float"
                        : image.depth() == CV_8S || image.depth() == CV_16S || image.depth() == CV_32S
                            ? "signed integer"
                            : "unsupported";
    throw InputError(name + ": a " + std::string(depth) +
                     " image; expected 8 or 16 bits per sample (convert it to 8 or 16 bits first)");
  }
  if (image.channels() != 1 && image.channels() != 2 && image.channels() != 3 && image.channels() != 4) {
    throw InputError(name + ": an image of " + std::to_string(image.channels()) +
                     " channels; expected grey, grey and alpha, BGR or BGRA");
  }
  if (image_bits < 1 || image_bits > 16) {
    throw InputError(name + ": image_bits is " + std::to_string(image_bits) + "; expected 1 to 16");
  }
  cv::Mat out = without_alpha(image);
  if (out.depth() == CV_16U) out.convertTo(out, CV_8U, 255.0 / (std::ldexp(1.0, image_bits) - 1.0));
  if (out.channels() == 1) cv::cvtColor(out, out, cv::COLOR_GRAY2BGR);
  return out;
}

cv::Mat FrameSource::to_bgr(const cv::Mat& image, const std::string& name) {
  if (image.depth() == CV_16U && !checked_bits_ && !quiet_) {
    // The first 16-bit image: values that stay under a sixteenth of the
    // range are most likely a camera of fewer bits than said (12-bit data
    // in 16-bit files).
    checked_bits_ = true;
    const double top = std::ldexp(1.0, image_bits_) - 1.0;
    double max = 0;  // of the colour channels: an opaque alpha is 65535
    cv::minMaxLoc(without_alpha(image).reshape(1), nullptr, &max);
    if (max > 0 && max < (top + 1) / 16) {
      logger().warn("{}: a 16-bit image whose values reach only {} of {:.0f}, so it is dark at 8 bits; if the "
                    "camera gives fewer bits, say so with [tracker] image_bits (now {})",
                    name, max, top, image_bits_);
    } else if (max > top) {
      // Fewer bits said than the files hold: a camera that puts its 12
      // bits in the high bits of each sample needs no image_bits at all.
      logger().warn("{}: a 16-bit image with values up to {}, above the {:.0f} of [tracker] image_bits = {}, "
                    "which saturate; image_bits is for data in the low bits (data in the high bits needs the "
                    "default, 16)",
                    name, max, top, image_bits_);
    }
  }
  return to_tracker_image(image, image_bits_, name);
}

namespace {

std::string size_text(int w, int h) { return std::to_string(w) + "x" + std::to_string(h); }

void check_size(ImageSize got, ImageSize expected, const std::string& what) {
  if (got.width != expected.width || got.height != expected.height) {
    throw InputError(what + ": image is " + size_text(got.width, got.height) + " but the sensor expects " +
                     size_text(expected.width, expected.height) +
                     " (the size [sensor] gives: its width/height, or its calibration file's image size)");
  }
}

void check_size(const cv::Mat& img, ImageSize expected, const std::string& what) {
  check_size(ImageSize{img.cols, img.rows}, expected, what);
}

// ".TIF" -> ".tif": extensions are matched whatever their case.
std::string lowercase_extension(const fs::path& p) {
  std::string ext = p.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
  return ext;
}

// Decides which source indices are delivered, for every kind of source.
class RangeFilter {
 public:
  explicit RangeFilter(FrameRange r) : r_(r) {}
  bool done(int index) const { return r_.last >= 0 && index >= r_.last; }
  bool wanted(int index) const { return r_.contains(index); }

 private:
  FrameRange r_;
};

class VideoSource final : public FrameSource {
 public:
  // `seek`: the video is positioned at the range's first frame by seeking
  // instead of decoding every frame before it. Seeking is not exact in
  // every video (B-frames, a variable frame rate): only RecordedFrames,
  // which checks what it reads against the frames read in order, asks
  // for it.
  VideoSource(cv::VideoCapture cap, std::string name, ImageSize expected, FrameRange range, double fallback_fps,
              bool live, bool seek = false)
      : cap_(std::move(cap)), name_(std::move(name)), expected_(expected), filter_(range), live_(live) {
    fps_ = cap_.get(cv::CAP_PROP_FPS);
    rate_declared_ = fps_ > 0 && fps_ < 1e4;
    if (!rate_declared_) fps_ = fallback_fps;
    // A raw stream's count is whatever its duration gives (often nonsense).
    const double count = live ? -1 : cap_.get(cv::CAP_PROP_FRAME_COUNT);
    count_ = count >= 1 && count < 1e9 ? static_cast<int>(count) : -1;
    if (seek && !live && range.first > 0) {
      detail::CapturedStderr library;
      if (cap_.set(cv::CAP_PROP_POS_FRAMES, range.first)) {
        index_ = range.first;
        seeked_ = true;
      }
      const std::string said = library.take();
      if (!said.empty()) logger().debug("{}: seeking to frame {}, the decoder said: {}", name_, range.first, said);
    }
  }

  std::optional<Frame> next() override {
    for (;;) {
      if (filter_.done(index_)) return std::nullopt;
      // The decoder's complaints are taken aside: said once, on one line,
      // when the video ends before its declared frames. gtrack's own
      // messages wait until the capture has ended.
      std::string said;
      double stamp_ms = -1;
      bool grabbed = false;
      {
        // Not for a camera: its grab waits for the next frame, and fd 2 would
        // be taken aside from the whole process most of the time.
        std::optional<detail::CapturedStderr> decoder;
        if (!live_) decoder.emplace();
        grabbed = cap_.grab();
        if (grabbed) stamp_ms = cap_.get(cv::CAP_PROP_POS_MSEC);
        if (decoder) said = decoder->take();
      }
      if (!grabbed) return end_of_stream(said);
      follow_time_stamp(stamp_ms);
      if (filter_.done(index_)) return std::nullopt;
      if (!filter_.wanted(index_)) {  // grabbed, never decoded into an image
        note(said, false);
        ++index_;
        continue;
      }
      cv::Mat img;
      bool decoded = false;
      {
        std::optional<detail::CapturedStderr> decoder;
        if (!live_) decoder.emplace();
        decoded = cap_.retrieve(img) && !img.empty();
        if (const std::string more = decoder ? decoder->take() : std::string(); !more.empty()) {
          said += (said.empty() ? "" : "; ") + more;
        }
      }
      if (!decoded) return end_of_stream(said);
      note(said, true);
      Frame f;
      f.index = index_++;
      f.time_s = fps_ > 0 ? f.index / fps_ : 0.0;
      f.name = name_ + " frame " + std::to_string(f.index);
      f.image = to_bgr(img, f.name);
      check_size(f.image, expected_, f.name);
      ++delivered_;
      return f;
    }
  }
  double fps() const override { return fps_; }
  int frame_count() const override { return count_; }
  std::string description() const override { return name_; }
  std::string ended_early() const override { return ended_early_; }
  // Whether the source was positioned by seeking (`seek`, and the decoder took it).
  bool seeked() const { return seeked_; }
  // Whether the video gives its rate (else fps() is the fallback's).
  bool rate_declared() const { return rate_declared_; }
  // The frames grabbed so far (at the end: where the stream or the range stopped).
  int position() const { return index_; }

 private:
  // What the decoder said while taking frame index_ (`taken`: into an
  // image to track, not only skipped over).
  void note(const std::string& said, bool taken) {
    if (said.empty()) return;
    if (taken && !warned_damage_ && !live_) {
      logger().warn("{} frame {}: the decoder reported damage and the frame is tracked as decoded (the decoder "
                    "said: {}); later such frames are logged at --log-level debug",
                    name_, index_, said);
      warned_damage_ = true;
    } else {
      logger().debug("{} frame {}: the decoder said: {}", name_, index_, said);
    }
    if (last_said_.empty()) last_said_ = said;
  }
  // A frame missing from a recording (capture software writes a dropped
  // frame as an empty chunk, which decoding skips) would shift the number
  // of every frame after it. The frame just taken, at `ms` (its time stamp,
  // from the stream's start), is numbered by its time stamp instead,
  // counted from the first frame's, and the first gap is warned about.
  //
  // Only while the stamps are those of the rate the video declares: the
  // first two frames one frame apart, every frame on that rate's grid,
  // never back, and a gap of at most kMaxGap frames. Otherwise (a
  // variable-rate recording, a rate the container does not give, a jump)
  // the frames are numbered by their order from there on, as before.
  void follow_time_stamp(double ms) {
    if (live_ || !rate_declared_ || stamps_disagree_ || !std::isfinite(ms) || ms < 0 || ms > 1e12) return;
    const double exact = ms * fps_ / 1000.0;
    const long long stamp = std::llround(exact);
    const auto disagree = [&](const char* why) {
      stamps_disagree_ = true;
      logger().debug("{}: frame {}: {}; frames are numbered by their order", name_, index_, why);
    };
    if (std::abs(exact - static_cast<double>(stamp)) > 0.1) return disagree("time stamp off the declared rate's grid");
    if (!stamp_base_) {
      stamp_base_ = stamp - index_;
      return;
    }
    const long long source = stamp - *stamp_base_;
    if (!stamps_checked_) {
      stamps_checked_ = true;
      if (source != index_) return disagree("the first two time stamps are not one frame apart");
    }
    if (source == index_) return;
    if (source < index_) return disagree("a time stamp goes back");
    if (source - index_ > kMaxGap) return disagree("time stamps jump too far");
    if (!warned_gap_) {
      logger().warn("{}: frame {} is missing (the time stamps go on at frame {}, {:.1f} ms): frames are numbered "
                    "by their time stamps, so that each keeps the source's number; later gaps are not warned about",
                    name_, index_, source, ms);
      warned_gap_ = true;
    }
    index_ = static_cast<int>(source);
  }
  static constexpr long long kMaxGap = 1000;  // frames: more is a jump in the stamps, not dropped frames
  std::optional<Frame> end_of_stream(const std::string& said) {
    // A video that opens but yields nothing is as unusable as one that does not open.
    if (index_ == 0 && delivered_ == 0 && !live_) {
      throw InputError(name_ + ": no frame could be decoded (corrupt or unsupported video" +
                       (said.empty() ? std::string(")") : "; the decoder said: " + said + ")"));
    }
    // A container's count can be an estimate (duration times rate): one
    // frame short with no word from the decoder is taken as that.
    const std::string why = !said.empty() ? said : last_said_;
    if (!live_ && count_ > 0 && index_ < count_ - (why.empty() ? 1 : 0) && ended_early_.empty()) {
      ended_early_ = "decoding stopped at frame " + std::to_string(index_) + " of the " + std::to_string(count_) +
                     " the video declares" + (why.empty() ? std::string() : " (the decoder said: " + why + ")");
      logger().warn("{}: {}; {}", name_, ended_early_,
                    delivered_ > 0 ? "the frames before it are tracked" : "no frame asked for comes before it");
    }
    return std::nullopt;
  }
  cv::VideoCapture cap_;
  std::string name_;
  ImageSize expected_;
  RangeFilter filter_;
  bool live_;
  double fps_ = 0;
  int count_ = -1;
  int index_ = 0;
  int delivered_ = 0;
  bool seeked_ = false;
  bool warned_damage_ = false, warned_gap_ = false;
  bool rate_declared_ = false, stamps_checked_ = false, stamps_disagree_ = false;
  std::optional<long long> stamp_base_;  // the first frame's time stamp in frames, less its number
  std::string last_said_;
  std::string ended_early_;
};

// Name order with runs of digits compared as numbers ("img2" < "img10");
// equal values with more leading zeros, and otherwise equal names, fall back
// to plain order so that the order is total.
bool natural_less(const std::string& a, const std::string& b) {
  size_t i = 0, j = 0;
  const auto digit = [](char c) { return c >= '0' && c <= '9'; };
  while (i < a.size() && j < b.size()) {
    if (digit(a[i]) && digit(b[j])) {
      size_t ie = i, je = j;
      while (ie < a.size() && digit(a[ie])) ++ie;
      while (je < b.size() && digit(b[je])) ++je;
      size_t is = i, js = j;
      while (is + 1 < ie && a[is] == '0') ++is;
      while (js + 1 < je && b[js] == '0') ++js;
      if (ie - is != je - js) return ie - is < je - js;
      const int c = a.compare(is, ie - is, b, js, je - js);
      if (c != 0) return c < 0;
      i = ie;
      j = je;
    } else {
      if (a[i] != b[j]) return a[i] < b[j];
      ++i;
      ++j;
    }
  }
  if ((i < a.size()) != (j < b.size())) return j < b.size();
  return a < b;
}

// A file name as its runs of digits (numbers; a run of more than 15 digits
// is text) and the text between them: "img_0041_Default_000.png" is
// {"img_", 41, "_Default_", 0, ".png"}.
struct NameRuns {
  std::vector<std::string> text;   // the text before each number, and after the last
  std::vector<long long> numbers;
};

NameRuns name_runs(const std::string& name) {
  NameRuns r;
  std::string text;
  for (size_t i = 0; i < name.size();) {
    size_t j = i;
    while (j < name.size() && name[j] >= '0' && name[j] <= '9') ++j;
    if (j > i && j - i <= 15) {
      r.text.push_back(text);
      r.numbers.push_back(std::stoll(name.substr(i, j - i)));
      text.clear();
      i = j;
    } else {
      text += name.substr(i, std::max<size_t>(j - i, 1));
      i = std::max(j, i + 1);
    }
  }
  r.text.push_back(text);
  return r;
}

// How image `b`'s number follows image `a`'s: 1 the next number, 0 a gap,
// -1 no numbering to check (names that differ in their text or in more
// than one number, such as time stamps, or carry no number). The number
// that counts is the one that changes: Micro-Manager's
// "img_000000011_Default_000.png" counts in its first.
int numbered_next(const fs::path& a, const fs::path& b) {
  const NameRuns x = name_runs(a.filename().string()), y = name_runs(b.filename().string());
  if (x.text != y.text) return -1;
  int changed = -1;
  for (size_t k = 0; k < x.numbers.size(); ++k) {
    if (x.numbers[k] == y.numbers[k]) continue;
    if (changed >= 0) return -1;
    changed = static_cast<int>(k);
  }
  if (changed < 0) return -1;
  return y.numbers[static_cast<size_t>(changed)] == x.numbers[static_cast<size_t>(changed)] + 1 ? 1 : 0;
}

// The stored bits of native samples, moved down to bit 0 and the bits
// outside them cleared (a file's own overlay or padding bits).
template <class T>
void keep_stored_bits(cv::Mat& image, int shift, int bits) {
  const T mask = static_cast<T>((1u << bits) - 1u);
  for (int y = 0; y < image.rows; ++y) {
    T* row = image.ptr<T>(y);
    for (int x = 0; x < image.cols * image.channels(); ++x) row[x] = static_cast<T>((row[x] >> shift) & mask);
  }
}

// Frame `k` of a DICOM file as an image OpenCV can take: 8 bits per sample
// (16-bit samples scaled by the bits the file says it stores), grey or BGR.
cv::Mat decode_dicom_frame(const detail::DicomLayout& layout, std::istream& in, int k, const std::string& name) {
  const std::string what = name + " frame " + std::to_string(k);
  std::vector<unsigned char> bytes;
  for (const auto& [offset, length] : layout.frame_spans(k)) {
    const std::size_t at = bytes.size();
    bytes.resize(at + length);
    in.clear();
    in.seekg(static_cast<std::streamoff>(offset));
    if (!in.read(reinterpret_cast<char*>(bytes.data() + at), static_cast<std::streamsize>(length))) {
      throw InputError(what + ": its bytes cannot be read (the file changed or was cut short since it was opened)");
    }
  }
  const std::string& pi = layout.photometric;
  cv::Mat image;
  if (layout.rle) bytes = detail::decode_rle_frame(bytes, layout, what);  // native bytes, planes one after another
  if (layout.encapsulated && !layout.rle) {
    // A JPEG of RGB samples that says so only in the DICOM header.
    const bool jpeg = layout.transfer_syntax == "1.2.840.10008.1.2.4.50" ||
                      layout.transfer_syntax == "1.2.840.10008.1.2.4.51";
    if (jpeg && pi == "RGB") bytes = detail::jpeg_marked_rgb(std::move(bytes));
    detail::CapturedStderr library;
    try {
      image = cv::imdecode(bytes, cv::IMREAD_ANYCOLOR | cv::IMREAD_ANYDEPTH);
    } catch (const cv::Exception&) {
      image.release();
    }
    const std::string said = library.take();
    if (image.empty()) {
      throw InputError(what + ": cannot decode its " + detail::transfer_syntax_name(layout.transfer_syntax) +
                       " data" + (said.empty() ? std::string() : " (the decoder said: " + said + ")") +
                       "; convert the file to native pixels, e.g. gdcmconv --raw in.dcm out.dcm");
    }
  } else {
    // The layout took only what these cases read.
    const int depth = layout.bits_allocated == 16 ? CV_16U : CV_8U;
    if (pi == "YBR_FULL_422") {
      // Each two pixels: Y0, Y1, Cb, Cr (8 bits, checked with the layout).
      image.create(layout.rows, layout.columns, CV_8UC3);  // Y, Cr, Cb, OpenCV's order
      const unsigned char* in_px = bytes.data();
      for (int y = 0; y < layout.rows; ++y) {
        auto* row = image.ptr<cv::Vec3b>(y);
        for (int x = 0; x < layout.columns; x += 2, in_px += 4) {
          row[x] = cv::Vec3b(in_px[0], in_px[3], in_px[2]);
          row[x + 1] = cv::Vec3b(in_px[1], in_px[3], in_px[2]);
        }
      }
      cv::cvtColor(image, image, cv::COLOR_YCrCb2BGR);
    } else {
      if (layout.samples == 1) {
        image = cv::Mat(layout.rows, layout.columns, CV_MAKETYPE(depth, 1), bytes.data()).clone();
      } else if (layout.planar == 1 || layout.rle) {
        const std::size_t plane = bytes.size() / 3;
        std::vector<cv::Mat> planes;
        for (int c = 0; c < 3; ++c) {
          planes.emplace_back(layout.rows, layout.columns, CV_MAKETYPE(depth, 1), bytes.data() + plane * c);
        }
        cv::merge(planes, image);
      } else {
        image = cv::Mat(layout.rows, layout.columns, CV_MAKETYPE(depth, 3), bytes.data()).clone();
      }
      const int allocated = layout.bits_allocated;
      const int stored = layout.bits_stored > 0 ? layout.bits_stored : allocated;
      const int shift = layout.high_bit >= 0 ? layout.high_bit + 1 - stored : 0;
      if (shift > 0 || stored < allocated) {
        if (depth == CV_16U) {
          keep_stored_bits<std::uint16_t>(image, shift, stored);
        } else {
          keep_stored_bits<std::uint8_t>(image, shift, stored);
        }
        if (depth == CV_8U) image.convertTo(image, CV_8U, 255.0 / (std::ldexp(1.0, stored) - 1.0));
      }
      if (pi == "RGB") {
        cv::cvtColor(image, image, cv::COLOR_RGB2BGR);
      } else if (pi == "YBR_FULL") {
        // Y, Cb, Cr; OpenCV's order is Y, Cr, Cb.
        std::vector<cv::Mat> ycc;
        cv::split(image, ycc);
        std::swap(ycc[1], ycc[2]);
        cv::merge(ycc, image);
        cv::cvtColor(image, image, cv::COLOR_YCrCb2BGR);
      }
    }
  }
  if (image.depth() == CV_16U) {
    const int stored = layout.bits_stored > 0 && layout.bits_stored <= 16 ? layout.bits_stored : 16;
    image.convertTo(image, CV_8U, 255.0 / (std::ldexp(1.0, stored) - 1.0));
  }
  // MONOCHROME1: the lowest value is white.
  if (pi == "MONOCHROME1" && image.channels() == 1) cv::bitwise_not(image, image);
  return image;
}

// A name a scanner may give a DICOM file, which only its content tells:
// no extension, as IM_0001, or a UID, whose last part reads as one of
// digits (1.2.840.113619.2.55.3.7).
bool dicom_by_content(const fs::path& p) {
  const std::string ext = p.extension().string();
  return ext.empty() || std::all_of(ext.begin() + 1, ext.end(), [](unsigned char c) { return std::isdigit(c); });
}

// A folder's image named .dcm or .dicom, or so that only its content tells
// (listed only when it is DICOM): a single-frame DICOM file (one file per
// frame, as scanners export), decoded as a DICOM file's frames are; what
// cannot be read (yet: a file still being written) is said in `said` and
// gives no image, what is refused for its header throws.
bool is_dicom_name(const fs::path& p) {
  // A folder lists no other file of such a name (dicom_by_content) unless it is DICOM.
  return detail::has_dicom_extension(p.string()) || dicom_by_content(p);
}

// An image whose header gives the sensor's size in neither orientation is
// refused before it is decoded (a JPEG's or TIFF's orientation tag may turn
// the decoded image: that one is judged once decoded).
// A folder's image (`in_folder`) is one frame: a TIFF stack among them,
// whose first page alone would be read, is refused too.
void check_header_size(const fs::path& file, ImageSize expected, bool in_folder) {
  if (is_dicom_name(file)) return;  // its preamble may hold another format's header
  std::ifstream in(file, std::ios::binary);
  const std::optional<ImageSize> header = in ? detail::image_header_size(in) : std::nullopt;
  if (header && !(header->width == expected.height && header->height == expected.width)) {
    check_size(*header, expected, file.string());
  }
  if (in_folder && in && detail::tiff_has_pages_after_first(in)) {
    throw InputError(file.string() + ": a TIFF stack of several pages in a folder of images, each of which is one "
                                     "frame; give the stack to --input by itself");
  }
}

cv::Mat read_dicom_image(const fs::path& p, std::string& said) {
  try {
    std::ifstream in(p, std::ios::binary);
    if (!in) throw InputError(p.string() + ": cannot open the file");
    const detail::DicomLayout layout = detail::read_dicom_layout(in, p.string());
    if (layout.frames != 1 || layout.video) {
      throw detail::DicomRefusal(p.string() + ": a DICOM file of " + std::to_string(layout.frames) + " frame" +
                                 (layout.frames == 1 ? "" : "s") + (layout.video ? " as a video stream" : "") +
                                 " in a folder of images; give the file itself as --input");
    }
    said.clear();
    return decode_dicom_frame(layout, in, 0, p.string());
  } catch (const detail::DicomRefusal&) {
    throw;  // final: a followed folder's writer is not waited on for it
  } catch (const InputError& e) {
    said = e.what();
    return cv::Mat();
  }
}

class FolderSource final : public FrameSource {
 public:
  FolderSource(const fs::path& dir, ImageSize expected, FrameRange range, double fps, FollowOptions follow)
      : dir_(dir), expected_(expected), filter_(range), fps_(fps), follow_(follow) {
    scan();
    if (files_.empty() && !following()) {
      throw InputError(dir.string() +
                       ": the folder holds no images (.png, .jpg, .bmp, .tif, .pgm, .ppm, .dcm, or DICOM files "
                       "without an extension or named by their UIDs)");
    }
  }

  std::optional<Frame> next() override {
    waited_s_ = 0;
    for (;;) {
      if (following() && follow_.newest) skip_to_newest();
      while (index_ < static_cast<int>(files_.size())) {
        if (filter_.done(index_)) return std::nullopt;
        const int i = index_++;
        if (!filter_.wanted(i)) continue;
        const fs::path& p = files_[static_cast<size_t>(i)];
        Frame f;
        f.index = i;
        f.time_s = fps_ > 0 ? i / fps_ : 0.0;
        f.name = p.string();
        const ReadImage got = read(p);
        if (got.vanished) {
          // One of the numbered images (a camera's ring buffer, a file moved
          // away): its frame is left out, the frames after it keep their
          // numbers. Any other name (a camera's software that writes under a
          // temporary name and renames): no frame, and its name stays known,
          // so that the temporary name used again is not listed again.
          const size_t at = static_cast<size_t>(i);
          const bool numbered = (at > 0 && numbered_next(files_[at - 1], p) >= 0) ||
                                (at + 1 < files_.size() && numbered_next(p, files_[at + 1]) >= 0);
          if (numbered) {
            logger().warn("{}: gone before it could be read (removed or moved away); frame {} is left out", p.string(),
                          i);
            continue;
          }
          logger().info("{}: gone before it could be read whole (renamed or removed); not a frame", p.string());
          files_.erase(files_.begin() + i);
          index_ = i;
          continue;
        }
        if (got.image.empty()) return std::nullopt;  // cancelled while the image was still being written
        f.image = to_bgr(got.image, f.name);
        check_size(f.image, expected_, p.string());
        f.waited_s = waited_s_;
        if (got.written) {
          f.written_unix_s = std::chrono::duration<double>(
                                 std::chrono::file_clock::to_sys(*got.written).time_since_epoch())
                                 .count();
        }
        return f;
      }
      // The range's last frame taken: nothing to wait for.
      if (!following() || filter_.done(index_) || !wait_for_more()) return std::nullopt;
    }
  }
  double fps() const override { return fps_; }
  int skipped() const override { return skipped_; }
  int frame_count() const override { return following() ? -1 : static_cast<int>(files_.size()); }
  std::string description() const override {
    return dir_.string() + (following() ? " (followed: new images are taken as they arrive)"
                                        : " (" + std::to_string(files_.size()) + " images)");
  }
  // A folder of single-frame DICOM files (a scanner's export): the pixel
  // size its first file gives, as a multi-frame file's.
  std::optional<std::pair<double, double>> pixel_size_mm() const override {
    if (files_.empty() || !is_dicom_name(files_.front())) return std::nullopt;
    try {
      std::ifstream in(files_.front(), std::ios::binary);
      return detail::read_dicom_layout(in, files_.front().string()).pixel_mm;
    } catch (const Error&) {
      // Its frame says what is wrong with it when it is read.
    }
    return std::nullopt;
  }

 private:
  bool following() const { return follow_.idle_s > 0; }

  // --newest on a followed folder: the next frame is the newest image of the
  // range listed now; those before it are left out without being decoded
  // (reading each would keep the tracker as far behind as tracking it).
  void skip_to_newest() {
    scan();
    int newest = -1;
    for (int i = static_cast<int>(files_.size()) - 1; i >= index_ && newest < 0; --i) {
      if (filter_.wanted(i) && !filter_.done(i)) newest = i;
    }
    if (newest < 0) return;
    for (int i = index_; i < newest; ++i) skipped_ += filter_.wanted(i) ? 1 : 0;
    index_ = newest;
  }

  // The folder's images in name order. Following, scan() runs once every
  // image listed so far was taken (with --newest, before every frame): an
  // image that arrives late, named before
  // the last one taken, is not tracked (the frame numbers of what was taken
  // never change) and is warned about.
  void scan() {
    static const std::vector<std::string> exts = {".png", ".jpg", ".jpeg", ".bmp", ".tif",
                                                  ".tiff", ".pgm", ".ppm", ".dcm", ".dicom"};
    // (A file that may yet turn out to be DICOM is looked at again even in
    // a folder that did not change: it is being written in place.)
    if (following() && !undecided_ && unchanged_since_last_listing()) return;
    undecided_ = false;
    std::error_code ec;  // of the listing itself
    std::vector<fs::path> found;
    std::vector<std::string> seen;  // names to skip from the next listing on, if this one completes
    for (fs::directory_iterator it(dir_, ec), end; !ec && it != end; it.increment(ec)) {
      // Names seen before are not looked at again: a followed folder of an
      // hour's frames is listed every 20 ms.
      const std::string name = it->path().filename().string();
      if (known_.count(name)) continue;
      std::error_code entry_ec;  // an entry that vanished or dangles is skipped, and looked at again
      if (!it->is_regular_file(entry_ec)) continue;
      seen.push_back(name);
      // Hidden files are no frames: a copy's metadata (macOS "._name.png")
      // or an image still being written under a temporary name.
      if (name.front() == '.') continue;
      const std::string ext = lowercase_extension(it->path());
      if (std::find(exts.begin(), exts.end(), ext) != exts.end()) {
        found.push_back(it->path());
      } else if (dicom_by_content(it->path())) {
        // A scanner's export names its DICOM files IM_0001, ..., or by
        // their UIDs: "DICM" at byte 128 says what they are. Following,
        // one that does not say so yet is looked at again until it has
        // been unchanged for 2 s (a writer may set the size first and fill
        // it in later).
        if (detail::is_dicom_file(it->path().string())) {
          found.push_back(it->path());
        } else if (following()) {
          const auto written = fs::last_write_time(it->path(), entry_ec);
          if (entry_ec || fs::file_time_type::clock::now() - written < std::chrono::seconds(2)) {
            seen.pop_back();
            undecided_ = true;
          }
        }
      }
    }
    if (ec) {
      // Following, a listing that fails is made again, whole, at the next poll.
      if (!following() || files_.empty()) {
        throw InputError(dir_.string() + ": cannot list the folder (" + ec.message() + ")");
      }
      listed_ = false;
      return;
    }
    known_.insert(seen.begin(), seen.end());
    const auto before = [](const fs::path& a, const fs::path& b) {
      return natural_less(a.filename().string(), b.filename().string());
    };
    // Numbers in names compare by value: frame9.png before frame10.png.
    std::sort(found.begin(), found.end(), before);
    // Frames are numbered by their order here, so a number missing from
    // the names (a dropped frame) shifts every frame after it: said once,
    // with the first gap, when most names do count up by one (names that
    // carry a time stamp do not).
    int gaps = 0;
    std::string first_gap;
    for (const auto& f : found) {
      if (!files_.empty() && !before(files_.back(), f)) {
        logger().warn("{}: arrived after {}, which comes after it in name order; a followed folder's images are "
                      "taken in name order as they arrive, so it is not tracked",
                      f.string(), files_.back().filename().string());
        continue;
      }
      const int step = files_.empty() ? -1 : numbered_next(files_.back(), f);
      if (step == 1) ++numbered_steps_;
      if (step == 0 && gaps++ == 0) first_gap = files_.back().filename().string() + " to " + f.filename().string();
      files_.push_back(f);
    }
    number_gaps_ += gaps;
    if (gaps > 0 && numbered_steps_ >= number_gaps_ && !warned_gap_) {
      warned_gap_ = true;
      logger().warn("{}: the images' numbers skip from {}{}; frames are numbered by their order in the folder (0, 1, "
                    "2, ...), not by their names, so after a gap a frame's number is not the one in its name",
                    dir_.string(), first_gap,
                    gaps == 1 ? "" : " and at " + std::to_string(gaps - 1) + (gaps == 2 ? " more place" : " more places"));
    }
  }

  // Following: whether the folder cannot have changed since it was last
  // listed. Its modification time changes with every entry added, removed
  // or renamed, in steps as coarse as the file system keeps (whole seconds
  // on some): a time is trusted once the folder was listed again more than
  // 2 s, by this machine's clock, after it was first seen.
  bool unchanged_since_last_listing() {
    std::error_code ec;
    const auto mtime = fs::last_write_time(dir_, ec);
    const auto now = std::chrono::steady_clock::now();
    if (ec || !listed_ || mtime != listed_mtime_) {
      listed_ = !ec;
      listed_mtime_ = mtime;
      mtime_seen_at_ = now;
      mtime_trusted_ = false;
      return false;
    }
    if (mtime_trusted_) return true;
    mtime_trusted_ = now - mtime_seen_at_ > std::chrono::seconds(2);  // after this listing
    return false;
  }

  // Following: polls the folder until a new image appears (true), or none
  // has for idle_s seconds or the run is cancelled (false).
  bool wait_for_more() {
    const auto start = std::chrono::steady_clock::now();
    const size_t known = files_.size();
    for (;;) {
      scan();
      if (files_.size() > known) return true;
      if (follow_.cancel && follow_.cancel->load()) return false;
      const double idle = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      if (idle >= follow_.idle_s) {
        logger().info("{}: no new image for {:g} s; the run ends", dir_.string(), follow_.idle_s);
        return false;
      }
      pause();
    }
  }

  // One poll's wait while following, counted in the frame's waited_s.
  void pause() const {
    const auto before = std::chrono::steady_clock::now();
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
    waited_s_ += std::chrono::duration<double>(std::chrono::steady_clock::now() - before).count();
  }

  // An image that does not decode is an error. Following, it may still be
  // being written: while its size keeps changing, and for --follow-input's
  // seconds (2 at least) after it last changed, it is read again (also
  // when it decodes but the decoder complains, as it does about a
  // half-written JPEG: it is taken once it has been unchanged for two
  // seconds, by its size or its file time,
  // with a warning naming it). A cancel while waiting returns an empty image.
  // The file is decoded again only once its size or file time has changed
  // (a poll costs a stat, not a decode). The file time returned is the one
  // of the poll that took the image.
  struct ReadImage {
    cv::Mat image;                              // empty: cancelled, or vanished
    bool vanished = false;                      // the file went away before it was whole
    std::optional<fs::file_time_type> written;  // its file time, when it could be read
  };
  ReadImage read(const fs::path& p) const {
    const auto decode = [&p](std::string& said) {
      if (is_dicom_name(p)) return read_dicom_image(p, said);
      detail::CapturedStderr library;
      cv::Mat img;
      std::string refused;
      try {
        img = cv::imread(p.string(), cv::IMREAD_ANYCOLOR | cv::IMREAD_ANYDEPTH);
      } catch (const cv::Exception& e) {
        // OpenCV asserts on a header it will not decode (a size above its
        // 2^30 pixels): that is this file's error, not the run's.
        img.release();
        refused = e.err.find("CV_IO_MAX_IMAGE_PIXELS") != std::string::npos
                      ? "its header gives a size above the 2^30 pixels OpenCV decodes"
                      : e.err;
      }
      said = library.take();
      if (!refused.empty()) said = refused + (said.empty() ? "" : "; " + said);
      return img;
    };
    std::string said;
    if (!following()) {
      check_header_size(p, expected_, true);
      ReadImage got;
      got.image = decode(said);
      if (got.image.empty()) fail_to_read(p, said);
      if (!said.empty()) logger().debug("{}: the decoder said: {}", p.string(), said);
      std::error_code ec;
      const fs::file_time_type written = fs::last_write_time(p, ec);
      if (!ec) got.written = written;
      return got;
    }
    auto changed = std::chrono::steady_clock::now();
    std::uintmax_t last_size = static_cast<std::uintmax_t>(-1);
    cv::Mat img;
    bool decoded = false;
    std::uintmax_t decoded_size = 0;
    fs::file_time_type decoded_time;
    auto decoded_at = std::chrono::steady_clock::now();
    for (;;) {
      std::error_code ec, ec_time, ec_exists;
      const std::uintmax_t size = fs::file_size(p, ec);
      const fs::file_time_type written = fs::last_write_time(p, ec_time);
      if (ec && !fs::exists(p, ec_exists) && !ec_exists) return {cv::Mat(), true, std::nullopt};
      // Also every 2 s: a writer that set the size first, on a file system
      // whose file times step by seconds, changes neither as it fills.
      if (!decoded || ec || ec_time || size != decoded_size || written != decoded_time ||
          std::chrono::steady_clock::now() - decoded_at > std::chrono::seconds(2)) {
        check_header_size(p, expected_, true);  // once whole, the header says what the image will be
        img = decode(said);
        decoded = true;
        decoded_size = size;
        decoded_time = written;
        decoded_at = std::chrono::steady_clock::now();
      }
      const auto now = std::chrono::steady_clock::now();
      const bool growing = !ec && size != last_size;
      if (growing) {
        changed = now;
        last_size = size;
      }
      // Settled: unchanged for 2 s as seen here. An image that decodes, with
      // a complaint, is also taken once its size held over a poll and its
      // file time is 2 s old (a finished file that always draws one); its
      // failure is judged here only, since a file server's clock may run
      // behind this one.
      const double unchanged_s = std::chrono::duration<double>(now - changed).count();
      const bool settled = unchanged_s > 2.0;
      const bool old =
          !growing && !ec_time && fs::file_time_type::clock::now() - written > std::chrono::seconds(2);
      if (!img.empty() && (said.empty() || settled || old)) {
        if (!said.empty()) logger().warn("{}: the decoder said: {}", p.string(), said);
        ReadImage got;
        got.image = img;
        if (!ec_time) got.written = written;
        return got;
      }
      // One that does not decode at all is waited on as long as a new image
      // would be (--follow-input's seconds, 2 s at least): a writer may pause
      // mid-file.
      if (img.empty() && unchanged_s > std::max(2.0, follow_.idle_s)) {
        fail_to_read(p, said + (said.empty() ? "" : "; ") + "unchanged for " +
                            fmt::format("{:g}", std::max(2.0, follow_.idle_s)) +
                            " s (--follow-input) and still not a whole image");
      }
      if (follow_.cancel && follow_.cancel->load()) return {};
      pause();
    }
  }

  [[noreturn]] static void fail_to_read(const fs::path& p, const std::string& said) {
    // A DICOM file's reader names the file and what it expected.
    if (is_dicom_name(p) && said.rfind(p.string() + ":", 0) == 0) throw InputError(said);
    throw InputError(p.string() + ": cannot read the image (corrupt or unsupported format" +
                     (said.empty() ? std::string() : "; the decoder said: " + said) + ")");
  }

  fs::path dir_;
  mutable double waited_s_ = 0;  // of the frame being taken
  std::vector<fs::path> files_;
  int numbered_steps_ = 0, number_gaps_ = 0;  // consecutive names and gaps so far, see scan()
  bool warned_gap_ = false;
  std::unordered_set<std::string> known_;  // names listed so far
  bool undecided_ = false;  // the last listing left a file (dicom_by_content) that may yet be DICOM
  // See unchanged_since_last_listing().
  bool listed_ = false, mtime_trusted_ = false;
  fs::file_time_type listed_mtime_;
  std::chrono::steady_clock::time_point mtime_seen_at_;
  ImageSize expected_;
  RangeFilter filter_;
  double fps_;
  FollowOptions follow_;
  int index_ = 0;
  int skipped_ = 0;  // see skip_to_newest()
};

// A multi-page TIFF (a stack as ImageJ/Fiji, Micro-Manager and most
// microscope software save a recording): each page is a frame. Pages are
// decoded a block at a time, in order; the pages before the range's first
// are skipped without decoding (TIFF directories only).

// What a stack's first page says of its layout: ImageJ writes "images=",
// "channels=", "slices=" and "frames=" lines into its description, OME-TIFF
// (Micro-Manager, Bio-Formats) an XML whose Pixels element has SizeC, SizeZ,
// SizeT and DimensionOrder.
struct StackLayout {
  std::string writer;      // "ImageJ" or "OME-TIFF"
  long long images = 0;    // pages the writer wrote
  long long channels = 1;  // channels per time point (a page's own samples, RGB, not counted)
  long long slices = 1;    // z-slices per time point
  long long times = 1;     // time points
  bool time_last = true;   // time points follow each other (ImageJ always; OME: DimensionOrder ...T)
  bool slices_are_times = false;  // no time points: the z-slices are taken as the frames
};

// What libtiff says is an error (not a warning about a private tag) while
// every directory of a stack is read: a directory past the file's end (a
// stack cut short) or a page it cannot take (ImageWidth 0) ends the pages
// there, which imcount does without a word. "" when the chain is whole.
std::string stack_directory_error(const std::string& file) {
  static std::mutex one_at_a_time;  // libtiff's error handler is the process's
  std::lock_guard lock(one_at_a_time);
  static std::string said;
  said.clear();
  const TIFFErrorHandler before = TIFFSetErrorHandler([](const char* module, const char* fmt, va_list args) {
    char text[512];
    std::vsnprintf(text, sizeof text, fmt, args);
    if (said.empty()) said = (module ? std::string(module) + ": " : std::string()) + text;
  });
  {
    detail::CapturedStderr library;  // the warnings, about private tags
    if (TIFF* tif = TIFFOpen(file.c_str(), "r")) {
      while (TIFFReadDirectory(tif)) {
      }
      TIFFClose(tif);
    }
  }
  TIFFSetErrorHandler(before);
  return said;
}

std::optional<StackLayout> stack_layout(const std::string& file) {
  std::string description;
  std::uint16_t samples = 1;
  {
    detail::CapturedStderr library;  // libtiff's warnings about private tags
    TIFF* tif = TIFFOpen(file.c_str(), "r");
    if (!tif) return std::nullopt;
    char* text = nullptr;
    if (TIFFGetField(tif, TIFFTAG_IMAGEDESCRIPTION, &text) == 1 && text) description = text;
    TIFFGetFieldDefaulted(tif, TIFFTAG_SAMPLESPERPIXEL, &samples);
    TIFFClose(tif);
  }
  // The digits after `key` (which starts a line, or follows white space,
  // in `text`), 0 when there are none.
  const auto number_after = [](std::string_view text, std::string_view key) -> long long {
    for (size_t at = text.find(key); at != std::string_view::npos; at = text.find(key, at + 1)) {
      if (at > 0 && !std::isspace(static_cast<unsigned char>(text[at - 1]))) continue;
      long long v = 0;
      const char* first = text.data() + at + key.size();
      const auto [end, ec] = std::from_chars(first, text.data() + text.size(), v);
      return ec == std::errc() && end != first && v <= 1'000'000'000 ? v : 0;
    }
    return 0;
  };
  StackLayout layout;
  std::string order = "XYCZT";  // ImageJ's, and OME's when it says none
  if (description.rfind("ImageJ=", 0) == 0) {
    // A plain stack says only images= and slices=: ImageJ takes unlabelled
    // pages for z-slices, and they are the recording's frames.
    layout.writer = "ImageJ";
    layout.images = number_after(description, "images=");
    layout.channels = std::max(1LL, number_after(description, "channels="));
    layout.slices = std::max(1LL, number_after(description, "slices="));
    layout.times = std::max(1LL, number_after(description, "frames="));
  } else if (const size_t pixels = description.find("<Pixels"); pixels != std::string::npos &&
                                                                 description.find("<OME") != std::string::npos) {
    layout.writer = "OME-TIFF";
    const std::string_view tag = std::string_view(description).substr(pixels, description.find('>', pixels) - pixels);
    // SizeC counts samples: an RGB page is 3 of them.
    layout.channels = std::max(1LL, number_after(tag, "SizeC=\"") / std::max<long long>(1, samples));
    layout.slices = std::max(1LL, number_after(tag, "SizeZ=\""));
    layout.times = std::max(1LL, number_after(tag, "SizeT=\""));
    if (const size_t at = tag.find("DimensionOrder=\""); at != std::string_view::npos) {
      order = std::string(tag.substr(at + 16, 5));
    }
    const double images = static_cast<double>(layout.channels) * static_cast<double>(layout.slices) *
                          static_cast<double>(layout.times);
    layout.images = static_cast<long long>(std::min(images, 1e15));
  } else {
    return std::nullopt;
  }
  // Without time points, the slices are taken as the time points: ImageJ
  // calls the pages of a plain stack slices.
  char time = 'T';
  if (layout.times == 1 && layout.slices > 1) {
    std::swap(layout.times, layout.slices);
    layout.slices_are_times = true;
    time = 'Z';
  }
  // Time runs last when every dimension after it has one element.
  const size_t t = order.find(time);
  for (size_t k = t == std::string::npos ? order.size() : t + 1; k < order.size(); ++k) {
    if ((order[k] == 'C' && layout.channels > 1) || (order[k] == 'Z' && time == 'T' && layout.slices > 1)) {
      layout.time_last = false;
    }
  }
  return layout;
}

class StackSource final : public FrameSource {
 public:
  // `pages`: the stack's page count when already known (a stack read again
  // a block at a time), which spares walking its directories again.
  StackSource(std::string spec, ImageSize expected, FrameRange range, double fps, int pages = 0)
      : spec_(std::move(spec)), expected_(expected), filter_(range), range_(range), fps_(fps) {
    index_ = std::max(0, range.first);
    if (pages > 0) {
      count_ = pages;
      return;
    }
    check_header_size(spec_, expected_, false);  // its first page's, before a block of pages is decoded
    std::string said;
    {
      detail::CapturedStderr library;  // libtiff's warnings about private tags (ImageJ's, OME's)
      count_ = static_cast<int>(cv::imcount(spec_, kFlags));
      said = library.take();
    }
    if (count_ <= 0) {
      throw InputError(spec_ + ": cannot read as a TIFF stack (corrupt or unsupported" +
                       (said.empty() ? std::string(")") : "; the decoder said: " + said + ")"));
    }
    if (!said.empty()) logger().debug("{}: the decoder said: {}", spec_, said);
    layout_ = stack_layout(spec_);
    // (A file named .tif that is another kind of image is one page, which
    // libtiff, not knowing it, would call a broken chain.)
    std::ifstream content(spec_, std::ios::binary);
    if (!detail::is_tiff_content(content)) return;
    if (const std::string broken = stack_directory_error(spec_); !broken.empty()) {
      ended_early_ = "its pages end after page " + std::to_string(count_ - 1) + " with an error (the decoder said: " +
                     library_words(broken) + ")";
      logger().warn("{}: {}; the pages before it are tracked", spec_, ended_early_);
    }
  }
  std::string ended_early() const override { return ended_early_; }

  std::optional<Frame> next() override {
    if (layout_ && !quiet()) check_layout(*layout_);
    layout_.reset();
    while (index_ < count_ && !filter_.done(index_) && !filter_.wanted(index_)) ++index_;
    if (index_ >= count_ || filter_.done(index_)) return std::nullopt;
    if (index_ < block_first_ || index_ >= block_first_ + static_cast<int>(block_.size())) read_block(index_);
    Frame f;
    f.index = index_;
    f.time_s = fps_ > 0 ? index_ / fps_ : 0.0;
    f.name = spec_ + " page " + std::to_string(index_);
    f.image = to_bgr(block_[static_cast<size_t>(index_ - block_first_)], f.name);
    check_size(f.image, expected_, f.name);
    ++index_;
    return f;
  }
  double fps() const override { return fps_; }
  int frame_count() const override { return count_; }
  std::string description() const override { return spec_ + " (a TIFF stack of " + std::to_string(count_) + " pages)"; }

 private:
  static constexpr int kFlags = cv::IMREAD_ANYCOLOR | cv::IMREAD_ANYDEPTH;

  // Every page is taken as the next frame: a stack with several channels or
  // z-slices per time point, unless --every steps over them, and a stack
  // that holds fewer pages than its writer says, are warned about.
  void check_layout(const StackLayout& layout) const {
    const long long per_time = layout.channels * layout.slices;
    if (per_time > 1 && layout.times > 1) {
      if (!layout.time_last) {
        logger().warn("{}: {} says its pages do not run through {} last ({} channel(s), {} z-slice(s), {} {}), "
                      "but every page is taken as the next frame; save it with that dimension last, or one channel "
                      "and slice per file",
                      spec_, layout.writer, layout.slices_are_times ? "z-slices (taken as frames)" : "time",
                      layout.channels, layout.slices, layout.times,
                      layout.slices_are_times ? "z-slices taken as frames" : "time points");
      } else if (std::max(1, range_.every) % per_time != 0) {
        logger().warn("{}: {} says it holds {} channel(s) and {} z-slice(s) per time point, but every page is "
                      "taken as the next frame; track one channel and slice with --every {} (--frames K: for the "
                      "K-th page of each time point), or split the stack first",
                      spec_, layout.writer, layout.channels, layout.slices, per_time);
      }
    }
    if (layout.images > count_) {
      logger().warn("{}: {} says it holds {} pages, the file has {}: a copy cut short, a recording split over "
                    "several files, or an ImageJ stack over 4 GB (whose pages after the first have no TIFF "
                    "directory; save it as an image sequence); the {} pages there are tracked",
                    spec_, layout.writer, layout.images, count_, count_);
    }
  }

  // The pages from `first` on, up to 64 and about 256 MB of them; with
  // --every above 16, the one page. Each read walks the TIFF's directories
  // from its first page, so one read per wanted page would cost the square
  // of the stack's length: a block decodes the pages between wanted ones
  // too, and is cheaper up to a stride of about 16.
  void read_block(int first) {
    int n = 1;
    if (range_.every <= 16) {
      const double page_bytes = std::max(1.0, 3.0 * expected_.width * expected_.height);
      n = static_cast<int>(std::clamp(256e6 / page_bytes, 1.0, 64.0));
      n = std::min(n, count_ - first);
      if (range_.last >= 0) n = std::min(n, range_.last - first);
      n = std::max(n, 1);
    }
    block_.clear();
    block_first_ = first;
    detail::CapturedStderr library;
    bool ok = false;
    try {
      ok = cv::imreadmulti(spec_, block_, first, n, kFlags);
    } catch (const cv::Exception&) {
      ok = false;
    }
    const std::string said = library.take();
    if (!ok || block_.empty() || std::any_of(block_.begin(), block_.end(), [](const cv::Mat& m) { return m.empty(); })) {
      block_.clear();
      throw InputError(spec_ + ": page " + std::to_string(first) + " of " + std::to_string(count_) +
                       " cannot be read (corrupt or unsupported" +
                       (said.empty() ? std::string(")") : "; the decoder said: " + said + ")"));
    }
    if (!said.empty()) logger().debug("{} page {}: the decoder said: {}", spec_, first, said);
  }

  std::string spec_;
  ImageSize expected_;
  RangeFilter filter_;
  FrameRange range_;
  double fps_;
  int count_ = 0;
  int index_ = 0;
  std::vector<cv::Mat> block_;
  int block_first_ = 0;
  std::optional<StackLayout> layout_;  // checked at the first frame
  std::string ended_early_;             // the directories end in an error
};

std::unique_ptr<VideoSource> open_video(const std::string& spec, ImageSize expected, FrameRange range,
                                        double fallback_fps, bool seek, const std::string& name = {});

// A file of this process's own in the temporary folder ($TMPDIR, else
// /tmp), removed with it (or before: whoever opened it keeps reading it).
class TemporaryFile {
 public:
  // Holds what `write` gives it; InputError naming `what` when it cannot
  // be made or written (nothing is left behind then).
  TemporaryFile(const std::string& stem, const std::function<void(std::ostream&)>& write, const std::string& what) {
    std::error_code ec;
    const fs::path dir = fs::temp_directory_path(ec);
    if (ec) {
      throw InputError(what + ": no temporary folder to copy its stream to (TMPDIR: " + ec.message() +
                       "); expected TMPDIR to name a writable folder");
    }
    std::string pattern = (dir / (stem + "_XXXXXX")).string();
    const int fd = ::mkstemp(pattern.data());
    if (fd < 0) {
      throw InputError(what + ": cannot make a file in " + dir.string() + " (" + std::strerror(errno) +
                       "); expected TMPDIR to name a writable folder");
    }
    ::close(fd);
    path_ = pattern;
    try {
      std::ofstream out(path_, std::ios::binary | std::ios::trunc);
      write(out);
      out.flush();
      if (!out) throw InputError(what + ": cannot write " + path_.string() + " (" + write_failure_reason() + ")");
    } catch (...) {
      remove();
      throw;
    }
  }
  ~TemporaryFile() { remove(); }
  TemporaryFile(const TemporaryFile&) = delete;
  TemporaryFile& operator=(const TemporaryFile&) = delete;
  const fs::path& path() const { return path_; }

 private:
  void remove() {
    std::error_code ec;
    fs::remove(path_, ec);
  }
  fs::path path_;
};

// A DICOM file: its frames in order (a B-mode cine loop exported by a
// scanner, or a single image), at the frame rate it gives.
class DicomSource final : public FrameSource {
 public:
  DicomSource(std::string spec, ImageSize expected, FrameRange range, double fallback_fps)
      : spec_(std::move(spec)), expected_(expected), filter_(range), in_(spec_, std::ios::binary) {
    if (!in_) throw InputError(spec_ + ": cannot open the file");
    layout_ = detail::read_dicom_layout(in_, spec_);
    if (layout_.rows > 0 && layout_.columns > 0) check_size(ImageSize{layout_.columns, layout_.rows}, expected, spec_);
    // The frames' times at the fallback rate when the file gives none; its
    // fps() says 0 then, as a folder's does.
    time_fps_ = layout_.fps > 0 ? layout_.fps : fallback_fps;
    index_ = std::max(0, range.first);
    logger().debug("{}: DICOM, {} frame(s) of {}x{}, {} sample(s) of {} bits, {}, {}, {} frames/s", spec_,
                   layout_.frames, layout_.columns, layout_.rows, layout_.samples, layout_.bits_allocated,
                   layout_.photometric, detail::transfer_syntax_name(layout_.transfer_syntax), layout_.fps);
    if (layout_.video) {
      // The stream, as the scanner encoded it, in a file of its own for the
      // video decoder (which finds its container, or none, by its content).
      // Removed once the decoder has opened it (it reads on from its own
      // descriptor): nothing is left behind, however the run ends.
      TemporaryFile stream(
          "gtrack_dicom_video",
          [&](std::ostream& out) {
            std::vector<char> buffer(std::size_t(1) << 20);
            for (const auto& [offset, length] : layout_.frame_spans(0)) {
              in_.clear();
              in_.seekg(static_cast<std::streamoff>(offset));
              for (std::uint64_t done = 0; done < length;) {
                const auto n = static_cast<std::streamsize>(std::min<std::uint64_t>(buffer.size(), length - done));
                if (!in_.read(buffer.data(), n)) {
                  throw InputError(spec_ + ": its video stream cannot be read (the file changed since it was opened)");
                }
                out.write(buffer.data(), n);
                done += static_cast<std::uint64_t>(n);
              }
            }
          },
          spec_);
      video_ = open_video(stream.path().string(), expected, range, time_fps_, false, spec_);
    }
  }

  std::optional<Frame> next() override {
    if (!warned_ && !quiet() && !layout_.cut_short.empty()) logger().warn("{}: {}", spec_, layout_.cut_short);
    warned_ = true;
    if (video_) {
      auto f = video_->next();
      // The file's rate, when it gives one, over the stream's.
      if (f && layout_.fps > 0) f->time_s = f->index / layout_.fps;
      // The stream ended, not the range, before the file's count of frames.
      const int at = video_->position();
      if (!f && ended_early_.empty() && video_->ended_early().empty() && layout_.cut_short.empty() &&
          layout_.frames > 1 && at < layout_.frames && !filter_.done(at)) {
        ended_early_ = "its video stream holds " + std::to_string(at) + " frame" + (at == 1 ? "" : "s") +
                       "; the file says " + std::to_string(layout_.frames) + " (0028,0008)";
        if (!quiet()) logger().warn("{}: {}", spec_, ended_early_);
      }
      return f;
    }
    while (index_ < layout_.frames && !filter_.done(index_) && !filter_.wanted(index_)) ++index_;
    if (index_ >= layout_.frames || filter_.done(index_)) return std::nullopt;
    Frame f;
    f.index = index_;
    f.time_s = time_fps_ > 0 ? index_ / time_fps_ : 0.0;
    f.name = spec_ + " frame " + std::to_string(index_);
    f.image = to_bgr(decode_dicom_frame(layout_, in_, index_, spec_), f.name);
    check_size(f.image, expected_, f.name);
    ++index_;
    return f;
  }
  // A video's rate when the file gives none: the stream's, when it gives one.
  double fps() const override {
    return layout_.fps > 0 || !video_ || !video_->rate_declared() ? layout_.fps : video_->fps();
  }
  int frame_count() const override {
    // A video without its number of frames (0028,0008): the stream's count.
    return video_ && layout_.frames == 1 ? video_->frame_count() : layout_.frames;
  }
  // The file cut short, else the decoder's stop, else a stream short of the
  // file's count.
  std::string ended_early() const override {
    if (!layout_.cut_short.empty()) return layout_.cut_short;
    if (video_ && !video_->ended_early().empty()) return video_->ended_early();
    return ended_early_;
  }
  std::optional<std::pair<double, double>> pixel_size_mm() const override {
    return layout_.pixel_mm;
  }
  std::string description() const override {
    return spec_ + " (a DICOM file of " + std::to_string(layout_.frames) + " frame" +
           (layout_.frames == 1 ? "" : "s") + ", " + detail::transfer_syntax_name(layout_.transfer_syntax) + ")";
  }

 private:
  std::string spec_;
  ImageSize expected_;
  RangeFilter filter_;
  std::ifstream in_;
  detail::DicomLayout layout_;
  double time_fps_ = 30;
  int index_ = 0;
  bool warned_ = false;  // of a file cut short, at the first frame
  std::unique_ptr<VideoSource> video_;  // a video's stream
  std::string ended_early_;             // a video's frames short of the file's count
};

// `name`: the file named in messages and frame names (a DICOM file whose
// stream is in `spec`); "" for `spec` itself.
std::unique_ptr<VideoSource> open_video(const std::string& spec, ImageSize expected, FrameRange range,
                                        double fallback_fps, bool seek, const std::string& name) {
  std::error_code ec;
  if (!fs::exists(spec, ec)) throw InputError(spec + ": no such file or folder");
  const std::string& shown = name.empty() ? spec : name;
  cv::VideoCapture cap;
  // The error below says in a line what the decoder says.
  bool opened = false;
  std::string said;
  {
    detail::CapturedStderr library;  // released before the source seeks, which captures its own
    opened = cap.open(spec, detail::video_backend()) && cap.isOpened();
    said = library.take();
  }
  if (!opened) {
    if (fs::is_regular_file(spec, ec) && fs::file_size(spec, ec) == 0) {
      throw InputError(shown + (name.empty() ? ": an empty file (0 bytes); expected a video, a folder of images or a "
                                               "TIFF stack"
                                             : ": its video stream holds no bytes; expected a video"));
    }
    throw InputError(shown + ": cannot open " + (name.empty() ? "as a video" : "its video stream") +
                     " (corrupt, unsupported, or holding no frame" +
                     (said.empty() ? std::string() : "; the decoder said: " + said) + ")");
  }
  if (!said.empty()) logger().debug("{}: the decoder said: {}", shown, said);
  return std::make_unique<VideoSource>(std::move(cap), shown, expected, range, fallback_fps, false, seek);
}

// What a frame's pixels were, to tell whether a frame read again is the same.
std::uint64_t fingerprint(const cv::Mat& image) {
  std::uint64_t h = 1469598103934665603ull;
  for (int r = 0; r < image.rows; ++r) {
    const std::string_view row(reinterpret_cast<const char*>(image.ptr(r)), image.cols * image.elemSize());
    h = (h ^ std::hash<std::string_view>{}(row)) * 1099511628211ull;
  }
  return h;
}

}  // namespace

bool detail::is_tiff_file(const std::string& spec) {
  std::error_code ec;
  if (!fs::is_regular_file(spec, ec)) return false;
  const std::string ext = lowercase_extension(spec);
  return ext == ".tif" || ext == ".tiff";
}

RecordedFrames::RecordedFrames(std::string spec, ImageSize expected, std::vector<int> frames, int every,
                               double fallback_fps)
    : spec_(std::move(spec)), expected_(expected), frames_(std::move(frames)), every_(std::max(1, every)),
      fps_(fallback_fps) {
  if (spec_.rfind("camera:", 0) == 0) throw InputError(spec_ + ": a live camera cannot be read again");
  // Every `every`-th frame, some of them missing (a frame dropped from a
  // video keeps its number and has no row).
  for (std::size_t k = 1; k < frames_.size(); ++k) {
    const int step = frames_[k] - frames_[k - 1];
    if (step <= 0 || step % every_ != 0) {
      throw std::invalid_argument("RecordedFrames: frames " + std::to_string(frames_[k - 1]) + " and " +
                                  std::to_string(frames_[k]) + " are not a multiple of " + std::to_string(every_) +
                                  " apart");
    }
  }
  std::error_code ec;
  video_ = !fs::is_directory(spec_, ec) && !detail::is_tiff_file(spec_) && !detail::is_dicom_file(spec_);
}

void RecordedFrames::reading_again(FrameSource& source) const {
  source.set_image_bits(image_bits_);
  source.set_quiet();
}

std::map<int, cv::Mat> RecordedFrames::fingerprint_in_order(std::size_t lo, std::size_t hi) {
  auto source = open_video(spec_, expected_, {frames_.front(), frames_.back() + 1, every_}, fps_, false);
  reading_again(*source);
  std::vector<std::uint64_t> prints(frames_.size(), 0);
  std::map<int, cv::Mat> block;
  while (auto f = source->next()) {
    if (f->index > frames_.back()) break;
    const auto at = std::lower_bound(frames_.begin(), frames_.end(), f->index);
    if (*at != f->index) continue;
    const auto k = static_cast<std::size_t>(at - frames_.begin());
    prints[k] = fingerprint(f->image);
    if (k >= lo && k < hi) block[f->index] = std::move(f->image);
  }
  prints_ = std::move(prints);
  return block;
}

std::map<int, cv::Mat> RecordedFrames::read(std::size_t lo, std::size_t hi) {
  hi = std::min(hi, frames_.size());
  if (lo >= hi) return {};
  const FrameRange range{frames_[lo], frames_[hi - 1] + 1, every_};
  // The first of [lo, hi) that is missing or not what it was, or hi.
  const auto first_wrong = [&](const std::map<int, cv::Mat>& images) {
    for (std::size_t k = lo; k < hi; ++k) {
      const auto it = images.find(frames_[k]);
      if (it == images.end() || (!prints_.empty() && fingerprint(it->second) != prints_[k])) return k;
    }
    return hi;
  };
  const auto collect = [](FrameSource& source) {
    std::map<int, cv::Mat> images;
    while (auto f = source.next()) images[f->index] = std::move(f->image);
    return images;
  };
  bool seek_failed = false;
  if (video_ && seeks_ && range.first > 0) {
    // The first time a block does not start at the video's first frame,
    // the video is decoded once in order: that block is read so, and every
    // frame fingerprinted for the blocks after it.
    if (prints_.empty()) {
      auto images = fingerprint_in_order(lo, hi);
      if (first_wrong(images) == hi) return images;
    } else {
      auto source = open_video(spec_, expected_, range, fps_, true);
      reading_again(*source);
      auto images = collect(*source);
      if (first_wrong(images) == hi) {
        if (source->seeked()) ++seeked_blocks_;
        return images;
      }
      seek_failed = true;
    }
  }
  std::unique_ptr<FrameSource> source;
  if (stack_pages_ > 0) {
    source = std::make_unique<StackSource>(spec_, expected_, range, fps_, stack_pages_);
  } else {
    source = open_frame_source(spec_, expected_, range, fps_);
    if (detail::is_tiff_file(spec_)) stack_pages_ = source->frame_count();
  }
  reading_again(*source);
  auto images = collect(*source);
  const std::size_t k = first_wrong(images);
  if (k < hi) {
    const bool missing = images.find(frames_[k]) == images.end();
    throw InputError(spec_ + ": frame " + std::to_string(frames_[k]) +
                     (missing ? " can no longer be read" : " is no longer what it was when this pass first read it") +
                     "; the same input is needed again");
  }
  if (seek_failed) {
    seeks_ = false;
    logger().warn("{}: seeking in the video does not give the frames that reading it in order does; each block is "
                  "decoded from the video's start (slower)",
                  spec_);
  }
  return images;
}

FrameRange parse_frame_range(const std::string& text) {
  FrameRange r;
  const auto parse_int = [&](const std::string& s, int& out) {
    auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), out);
    if (s.empty() || ec != std::errc() || end != s.data() + s.size() || out < 0) {
      throw InputError("--frames '" + text + "': expected A:B with non-negative frame indices (A inclusive, B exclusive)");
    }
  };
  const auto colon = text.find(':');
  if (colon == std::string::npos) {
    parse_int(text, r.first);
    if (r.first == std::numeric_limits<int>::max()) {
      throw InputError("--frames '" + text + "': expected a frame index below " + std::to_string(r.first));
    }
    r.last = r.first + 1;
    return r;
  }
  const std::string a = text.substr(0, colon), b = text.substr(colon + 1);
  if (!a.empty()) parse_int(a, r.first);
  if (!b.empty()) parse_int(b, r.last);
  if (r.last >= 0 && r.last <= r.first) {
    throw InputError("--frames '" + text + "': the end (exclusive) must be after the start");
  }
  return r;
}

std::unique_ptr<FrameSource> open_frame_source(const std::string& spec, ImageSize expected, FrameRange range,
                                               double fallback_fps) {
  return open_frame_source(spec, expected, range, fallback_fps, FollowOptions{});
}

std::unique_ptr<FrameSource> open_frame_source(const std::string& spec, ImageSize expected, FrameRange range,
                                               double fallback_fps, const FollowOptions& follow) {
  if (follow.idle_s > 0) {
    std::error_code ec;
    if (!fs::exists(spec, ec) && spec.rfind("camera:", 0) != 0) {
      throw InputError(spec + ": no such folder; expected the folder of images to follow (create it before the run)");
    }
    if (!fs::is_directory(spec, ec)) {
      throw InputError(spec + ": only a folder of images can be followed (a camera is live already; a video file is "
                              "read to its end)");
    }
  }
  if (range.every < 1) throw InputError("--every must be at least 1");
  if (spec.rfind("camera:", 0) == 0) {
    int dev = -1;
    const std::string n = spec.substr(7);
    auto [end, ec] = std::from_chars(n.data(), n.data() + n.size(), dev);
    if (n.empty() || ec != std::errc() || end != n.data() + n.size() || dev < 0) {
      throw InputError("'" + spec + "': expected camera:N with N a device number");
    }
    detail::CapturedStderr library;
    cv::VideoCapture cap(dev);
    const std::string said = library.take();
    if (!said.empty()) logger().debug("'{}': the capture backends said: {}", spec, said);
    if (!cap.isOpened()) throw InputError("'" + spec + "': cannot open camera device " + n);
    cap.set(cv::CAP_PROP_FRAME_WIDTH, expected.width);
    cap.set(cv::CAP_PROP_FRAME_HEIGHT, expected.height);
    return std::make_unique<VideoSource>(std::move(cap), spec, expected, range, fallback_fps, true);
  }
  const fs::path p(spec);
  std::error_code ec;
  if (fs::is_directory(p, ec)) return std::make_unique<FolderSource>(p, expected, range, fallback_fps, follow);
  if (detail::is_tiff_file(spec)) return std::make_unique<StackSource>(spec, expected, range, fallback_fps);
  if (detail::is_dicom_file(spec)) return std::make_unique<DicomSource>(spec, expected, range, fallback_fps);
  if (p.filename() == "DICOMDIR" && fs::is_regular_file(p, ec)) {
    throw InputError(spec + ": a DICOMDIR, the index of a scanner's export, holds no frames; give the folder of the "
                            "images it lists, or a multi-frame DICOM file among them, as --input");
  }
  return open_video(spec, expected, range, fallback_fps, false);  // a missing path: "no such file or folder"
}

}  // namespace gtrack
