// `gtrack track` as a library call: source -> Tracker -> files.
#include <unistd.h>

#include <array>
#include <cctype>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <deque>
#include <fstream>
#include <limits>
#include <map>
#include <fmt/format.h>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/videoio.hpp>

#include "gtrack/error.hpp"
#include "gtrack/frame_source.hpp"
#include "gtrack/log.hpp"
#include "gtrack/results.hpp"
#include "gtrack/sequence_io.hpp"
#include "gtrack/stimulus_log.hpp"
#include "gtrack/text_file.hpp"
#include "gtrack/tracker.hpp"
#include "captured_stderr.hpp"
#include "dicom.hpp"
#include "input_kind.hpp"
#include "console.hpp"
#include "nearest_equivalent.hpp"
#include "overlay.hpp"
#include "pipeline.hpp"
#include "video_backend.hpp"
#include "replace_file.hpp"
#include "run_config.hpp"

namespace gtrack {

namespace fs = std::filesystem;

namespace {

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

// The estimates drawn on their frames (detail::draw_estimate), into mp4
// where the OpenCV build can write it, MJPG in AVI everywhere else. Frames
// are drawn and encoded on a thread of their own, two at most waiting.
class OverlayWriter {
 public:
  OverlayWriter(fs::path dir, double fps, std::string stem, const Sensor& sensor, const ArticulatedModel& model)
      : dir_(std::move(dir)), fps_(fps > 0 ? fps : 30), stem_(std::move(stem)), sensor_(sensor), model_(model) {}
  // `reading`: detail::reading_text, taken where the stimulus plugin is used.
  void write(cv::Mat frame, Estimate estimate, std::string reading) {
    encoder_.give(Job{std::move(frame), std::move(estimate), std::move(reading)});
  }
  // Waits for the frames given to be encoded; file() is then the video's.
  void close() {
    encoder_.finish();
    writer_.release();
  }
  const fs::path& file() const { return file_; }

 private:
  struct Job {
    cv::Mat frame;
    Estimate estimate;
    std::string reading;
  };
  void encode(const Job& job) {
    if (!writer_.isOpened() && !failed_) open(job.frame.size());
    if (writer_.isOpened()) writer_.write(detail::draw_estimate(job.frame, sensor_, model_, job.reading, job.estimate));
  }
  void open(cv::Size size) {
    const fs::path mp4 = dir_ / (stem_ + ".mp4");
    for (const char* cc : {"avc1", "mp4v"}) {
      if (writer_.open(mp4.string(), cv::VideoWriter::fourcc(cc[0], cc[1], cc[2], cc[3]), fps_, size)) {
        file_ = mp4;
        return;
      }
    }
    std::error_code ec;
    fs::remove(mp4, ec);
    const fs::path avi = dir_ / (stem_ + ".avi");
    if (writer_.open(avi.string(), cv::VideoWriter::fourcc('M', 'J', 'P', 'G'), fps_, size)) {
      file_ = avi;
      return;
    }
    failed_ = true;
    logger().warn("cannot open a video writer for the overlay (neither mp4 nor MJPG/AVI); no overlay is written");
  }
  fs::path dir_;
  double fps_;
  std::string stem_;
  cv::VideoWriter writer_;
  const Sensor& sensor_;
  const ArticulatedModel& model_;
  fs::path file_;
  bool failed_ = false;
  detail::Behind<Job> encoder_{2, [this](Job& job) { encode(job); }};  // last: its thread uses the rest
};

// The overlays of the runs before a resumed one: a video killed before it
// was closed (kill -9, a crash, a power loss) may not open at all (an mp4
// has no index until it is closed), which is said once: a folder resumed
// after many kills says how many, not a line for each. `own`: the file this
// run is about to write.
void check_earlier_overlays(const fs::path& dir, const std::string& own) {
  std::error_code ec;
  std::vector<std::string> unreadable;
  for (fs::directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec)) {
    const std::string name = it->path().filename().string();
    if (name.rfind("overlay", 0) != 0 || name.rfind(own + ".", 0) == 0 || !it->is_regular_file(ec)) continue;
    bool readable = false;
    {
      detail::CapturedStderr decoder;  // "moov atom not found"
      cv::VideoCapture video(it->path().string(), detail::video_backend());
      cv::Mat first;
      readable = video.isOpened() && video.read(first) && !first.empty();
    }
    if (!readable) unreadable.push_back(it->path().string());
  }
  if (unreadable.size() == 1) {
    logger().warn("{}: cannot be read (not closed by the run that wrote it, which was stopped by kill -9, a crash "
                  "or a power loss, or no decoder for it here); the frames it held have no overlay (a run without "
                  "--resume draws them all again)",
                  unreadable.front());
  } else if (unreadable.size() > 1) {
    std::sort(unreadable.begin(), unreadable.end());
    logger().warn("{} overlays of earlier runs cannot be read ({} to {}: not closed by the runs that wrote them, "
                  "which were stopped by kill -9, a crash or a power loss, or no decoder for them here); the frames "
                  "they held have no overlay (a run without --resume draws them all again)",
                  unreadable.size(), unreadable.front(), unreadable.back());
  }
}

class Progress {
 public:
  Progress(bool enabled, int total, int every) : enabled_(enabled), total_(total), every_(every) {
    tty_ = ::isatty(::fileno(detail::console())) != 0;
  }
  void update(int done, int frame, double elapsed_s) {
    if (!enabled_) return;
    const double fps = elapsed_s > 0 ? done / elapsed_s : 0;
    if (tty_) {
      if (done > 1 && seconds_since(last_) < 0.2) return;
      last_ = Clock::now();
    } else if (done % every_ != 0) {
      return;
    }
    char eta[32] = "?";
    if (total_ > 0 && fps > 0) {
      const int s = static_cast<int>((total_ - done) / fps);
      std::snprintf(eta, sizeof eta, "%d:%02d", s / 60, s % 60);
    }
    char line[160];
    if (total_ > 0) {
      std::snprintf(line, sizeof line, "frame %d (%d/%d)  %.1f fps  ETA %s", frame, done, total_, fps, eta);
    } else {
      std::snprintf(line, sizeof line, "frame %d (%d)  %.1f fps", frame, done, fps);
    }
    std::fprintf(detail::console(), tty_ ? "\r%-70s" : "%s\n", line);
    std::fflush(detail::console());
    printed_ = true;
  }
  void finish() {
    if (enabled_ && tty_ && printed_) std::fprintf(detail::console(), "\n");
  }

 private:
  bool enabled_, tty_ = false, printed_ = false;
  int total_, every_;
  Clock::time_point last_ = Clock::now();
};

// How many frames the range will deliver, when the source knows its length.
int expected_frames(const FrameSource& src, const FrameRange& r) {
  int n = src.frame_count();
  if (n < 0) return -1;
  if (r.last >= 0) n = std::min(n, r.last);
  if (n <= r.first) return 0;
  return (n - r.first + r.every - 1) / r.every;
}

// A time_s log whose times start more than a day after a frame's: seconds
// since 1970 (Unix time), say.
std::string another_clock(const StimulusLog& log, int frame, double time_s) {
  return fmt::format(
      "{}: its times start at t = {:.3f} s{}, more than a day after frame {} (t = {:.3f} s); expected seconds "
      "from the recording's first frame (a log in Unix time: --stimulus-offset with the first frame's time)",
      log.source(), log.first_key(), log.shift_note(), frame, time_s);
}

// A finished time_s log against the frames to track: one whose rows all come
// after the last of them is on another clock (a logger started before the
// camera), and every frame would take its first row's reading (a log that
// ends early, or one keyed by frame, is warned about as each frame outside
// it comes); a time_s log with a
// folder of images, a TIFF stack or a DICOM file that gives none, which
// have no frame rate of their own, runs on the 30 frames/s taken for them
// unless [tracker] fps says otherwise.
void check_log_covers_frames(const StimulusLog& log, const TrackOptions& options, const FrameRange& range,
                             int expected, double fps, double config_fps, double source_fps) {
  const bool by_time = log.key() == StimulusLog::Key::Time;
  std::error_code ec;
  const bool images = fs::is_directory(options.input, ec) || detail::is_tiff_file(options.input) ||
                      (detail::is_dicom_file(options.input) && !(source_fps > 0));
  if (by_time && images && config_fps <= 0) {
    logger().warn("{}: the images carry no frame rate, so {:g} frames/s is taken for the time_s log {} and the "
                  "material's response; if the camera ran at another rate, set [tracker] fps",
                  options.input, fps, log.source());
  }
  if (expected <= 0) return;  // a camera or a followed folder: the frames to come are not known
  const int first = range.first, last = range.first + (expected - 1) * std::max(1, range.every);
  const double slack = 0.5 / fps;
  const double from = first / fps, to = last / fps;
  if (!by_time) return;
  if (log.first_key() > from + 86400) throw InputError(another_clock(log, first, from));
  if (to < log.first_key() - slack) {
    throw InputError(fmt::format(
        "{}: its rows cover t = {:.3f} to {:.3f} s{}, after the frames to track (t = {:.3f} to {:.3f} s): none of "
        "them falls within the log; expected seconds from the recording's first frame (a logger started before "
        "the camera: --stimulus-offset with the log's time at the first frame)",
        log.source(), log.first_key(), log.last_key(), log.shift_note(), from, to));
  }
}

// A unit in one spelling per unit ("degC", "°C", "celsius" -> "C"; "mt" ->
// "mT"), whatever its case; "" for one the checks below do not know.
std::string known_unit(std::string token) {
  for (char& c : token) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  static const std::pair<const char*, const char*> spellings[] = {
      {"c", "C"},    {"degc", "C"},  {"\u00b0c", "C"}, {"celsius", "C"}, {"f", "F"}, {"degf", "F"},
      {"\u00b0f", "F"}, {"fahrenheit", "F"}, {"k", "K"}, {"kelvin", "K"},  {"t", "T"}, {"tesla", "T"},
      {"mt", "mT"},  {"ut", "uT"},   {"\u00b5t", "uT"}, {"g", "G"},       {"gauss", "G"}, {"mg", "mG"}};
  for (const auto& [spelled, unit] : spellings) {
    if (token == spelled) return unit;
  }
  return "";
}

// The unit a log's column name ends with ("T_F", "B_mT", "temp (degC)"):
// known_unit() of the bracketed or last part. A single letter after "_" or
// a space counts only as C, F or K: "probe T" or "sample_T" is a temperature
// named T, not tesla (which a name says as "B (T)" or "B_mT").
std::string unit_in_name(const std::string& name) {
  if (const size_t open = name.find_last_of("(["); open != std::string::npos && name.size() > open + 2 &&
                                                   (name.back() == ')' || name.back() == ']')) {
    return known_unit(name.substr(open + 1, name.size() - open - 2));
  }
  const size_t sep = name.find_last_of("_ ");
  if (sep == std::string::npos) return "";
  const std::string token = name.substr(sep + 1);
  if (token.size() == 1 && token != "C" && token != "F" && token != "K") return "";
  return known_unit(token);
}

// A log whose readings' column names its unit ("T_F") against a stimulus
// that reads another ("C"): the readings would be taken in the wrong unit,
// which their values alone cannot show (71 degrees Fahrenheit pass for a
// warm Celsius reading).
void check_log_unit(const StimulusLog& log, const Stimulus& stimulus, const std::string& plugin) {
  const std::string in_log = unit_in_name(log.value_name());
  const std::string read = known_unit(stimulus.reading_unit());
  if (in_log.empty() || read.empty() || in_log == read) return;
  throw InputError(fmt::format("{}: its readings' column '{}' says {}, but the stimulus plugin '{}' reads {}; "
                               "expected readings in {} (or, for a plugin that reads several units, [stimulus] set "
                               "to the log's: temperature_hysteresis's log_unit)",
                               log.source(), log.value_name(), in_log, plugin, read, read));
}

// A resume that finds every frame done: summary.json keeps the figures of
// the run that tracked them. One that says that run was cancelled with no
// error (a two-pass run interrupted in its backward pass, its forward
// frames all done) now says it is not, since the run is complete; one that
// names an error keeps it. A file that cannot be read is left alone.
void mend_cancelled_summary(const fs::path& summary) {
  std::string text;
  try {
    text = read_text_file(summary, 1 << 20, "a run's summary.json");
  } catch (const Error&) {
    return;
  }
  const std::string cancelled = "\n  \"cancelled\": true,\n";
  const auto at = text.find(cancelled);
  if (at == std::string::npos || text.find("\n  \"stopped_by\": null\n") == std::string::npos) return;
  text.replace(at, cancelled.size(), "\n  \"cancelled\": false,\n");
  detail::replace_file(summary, text);
}

// A pose table (--restart-from, --score-truth) for the gripper of this setup.
// `truth`: every cell must be finite (--score-truth); a track to restart
// from may hold lost rows, which are refused where they would be used.
PoseTable read_gripper_poses(const fs::path& file, const Setup& setup, bool truth) {
  std::error_code ec;
  const bool folder = fs::is_directory(file, ec);
  if (folder || !fs::exists(file, ec)) {
    throw InputError(file.string() + (folder ? ": is a folder; expected a pose table" : ": no such file") + " (" +
                     (truth ? "--score-truth" : "--restart-from") + ")");
  }
  PoseTable table = truth ? read_truth_table(file) : read_pose_table(file);
  if (table.fingers != setup.model().fingers()) {
    throw InputError(file.string() + ": has " + std::to_string(table.fingers) +
                     " joint columns, the gripper of this config has " + std::to_string(setup.model().fingers()));
  }
  if (table.rows.empty()) throw InputError(file.string() + ": a header and no rows; expected a row per frame");
  return table;
}

// What the [observation] bounds make of the recording, said once each
// instead of frames coming out lost, or tracked on the background, without
// a word:
// - a grey image (its three channels equal: a grayscale or 16-bit grey file
//   read as colour) has no saturation, so a colour segmentation that needs
//   some finds nothing in it: said at the first frame, or at the first
//   frame that finds nothing (a grey image among colour ones); a frame of
//   one value throughout (the lamp off, a blank frame) says nothing of the
//   recording and is passed over;
// - the first frame that observes nothing, while none before it did;
// - a first frame whose observation covers most of the image, or ten times
//   the estimate's outline: the bounds take the background for the gripper
//   (a bright-field recording segmented for bright pixels, an ultrasound
//   gain raised above the bounds).
class ObservationAdvice {
 public:
  explicit ObservationAdvice(const ObservationConfig& o) : o_(o) {}

  void after(const Frame& frame, const Estimate& e, const Observation& observation, bool first) {
    if (!said_grey_ && (first || e.observed_pixels == 0)) said_grey_ = grey_for_colour(frame, first);
    if (!said_empty_ && !seen_any_ && e.observed_pixels == 0 && !said_grey_ && !uniform(frame.image)) {
      said_empty_ = true;
      logger().warn("{}: no pixel within the [observation] bounds ({}){}: the frame is lost, as every frame will be "
                    "until the gripper shows; if it is in view, check the bounds on this recording with gtrack segment",
                    frame.name, bounds(), excluded(frame.image.size()));
    }
    seen_any_ = seen_any_ || e.observed_pixels > 0;
    const double share = observation.mask.empty() ? 0.0 : double(e.observed_pixels) / observation.mask.total();
    const double times_model = e.terms.rendered > 0 ? double(e.observed_pixels) / e.terms.rendered : 0.0;
    if (first && (share > 0.5 || times_model > 10)) {
      logger().warn("{}: {:.0f} % of the image, {:.0f} times the gripper's outline, is within the [observation] "
                    "bounds ({}): they take the background for the gripper, and the track follows it; {} (check "
                    "with gtrack segment)",
                    frame.name, 100 * share, times_model, bounds(),
                    o_.color_space != "luminance" ? "narrow them to the gripper's colour"
                    : o_.luminance_min <= 0
                        ? "lower luminance_max below the background's darkest brightness, or leave its dark "
                          "parts (a vignette's corners) out with exclude_px"
                        : "raise luminance_min above the background's brightness (a dark gripper on a light "
                          "background needs luminance_min = 0 and luminance_max below the background's)");
    }
    poor_fit(frame, e);
  }

 private:
  static bool uniform(const cv::Mat& image) {
    double lo = 0, hi = 0;
    cv::minMaxLoc(image.reshape(1), &lo, &hi);
    return lo == hi;
  }

  std::string bounds() const {
    if (o_.color_space == "luminance") {
      return fmt::format("luminance {:g} to {:g}", o_.luminance_min, o_.luminance_max);
    }
    return fmt::format("hue {:g} to {:g}, saturation {:g} to {:g}, value {:g} to {:g}", o_.hue_min, o_.hue_max,
                       o_.saturation_min, o_.saturation_max, o_.value_min, o_.value_max);
  }

  // ", outside [observation] exclude_px's 2 rectangles (98 % of the image)",
  // when rectangles are excluded: they may be what hides everything.
  std::string excluded(const cv::Size& image) const {
    if (o_.exclude_px.empty()) return "";
    cv::Mat covered = cv::Mat::zeros(image, CV_8U);
    for (const cv::Rect& r : o_.exclude_px) covered(r & cv::Rect({}, image)).setTo(1);
    const size_t n = o_.exclude_px.size();
    return fmt::format(", outside [observation] exclude_px's {} rectangle{} ({:.0f} % of the image)", n,
                       n == 1 ? "" : "s", 100.0 * cv::countNonZero(covered) / covered.total());
  }

  bool grey_for_colour(const Frame& frame, bool first) const {
    if (o_.color_space != "hsv" || !(o_.saturation_min > 0) || frame.image.channels() != 3) return false;
    if (uniform(frame.image)) return false;
    // Grey within a few levels: a grey video decoded from 4:2:0 chroma
    // (H.264, MPEG-4) has channels a level or two apart, enough to give its
    // near-black pixels (a time stamp's text) a saturation above the bound.
    // The largest difference between any two channels of a pixel, over all
    // but the 0.1 % of pixels most apart (a stray coloured pixel, a
    // decoder's ringing at an edge).
    cv::Mat channels[3], apart, diff;
    cv::split(frame.image, channels);
    cv::absdiff(channels[0], channels[1], apart);
    for (const auto& [a, b] : {std::pair{0, 2}, std::pair{1, 2}}) {
      cv::absdiff(channels[a], channels[b], diff);
      apart = cv::max(apart, diff);
    }
    std::array<int, 256> counts{};
    for (auto it = apart.begin<std::uint8_t>(); it != apart.end<std::uint8_t>(); ++it) ++counts[*it];
    int most = 0;
    for (size_t seen = 0; most < 255; ++most) {
      seen += static_cast<size_t>(counts[static_cast<size_t>(most)]);
      if (seen >= apart.total() - apart.total() / 1000) break;
    }
    if (most > kGreyLevels) return false;
    logger().warn("{}: a grey image (its channels within {} levels of each other on 99.9 % of its pixels), but "
                  "[observation] color_space = "
                  "\"hsv\" with saturation_min = {} needs colour: what passes it is noise, of dark pixels or of "
                  "the compression; {} (for grey images use color_space = \"luminance\")",
                  frame.name, most, o_.saturation_min,
                  first ? "every frame will be lost or tracked on that noise"
                        : "it is lost or tracked on noise, and every grey image after it");
    return true;
  }

  // A track whose model fits what is observed poorly, frame after frame:
  // the bounds take something else for the gripper (a reflector, the
  // background, a scale bar), or the sensor's scale or the gripper's size
  // is wrong, and the frames come out "ok" all the same. Said once, when
  // the median D of kFitFrames consecutive tracked frames exceeds kPoorFit
  // (a tracked gripper stays under about 0.2, under occluders too).
  void poor_fit(const Frame& frame, const Estimate& e) {
    if (said_fit_) return;
    if (e.status == TrackStatus::Lost) {
      fit_.clear();
      return;
    }
    fit_.emplace_back(frame.index, e.terms.dice);
    if (static_cast<int>(fit_.size()) < kFitFrames) return;
    std::vector<double> d;
    for (const auto& [index, dice] : fit_) d.push_back(dice);
    std::nth_element(d.begin(), d.begin() + kFitFrames / 2, d.end());
    const double median = d[kFitFrames / 2];
    if (median > kPoorFit) {
      said_fit_ = true;
      logger().warn("frames {} to {}: the model fits what is observed poorly (D, 0 for a perfect fit and 1 for none, "
                    "has a median of {:.2f} over them; a tracked gripper stays under about 0.2): the [observation] "
                    "bounds may take something else for the gripper (a reflector, the background, text burned into "
                    "the frames: exclude_px), or the sensor's scale or the gripper's size is wrong; check with "
                    "gtrack segment and the overlay video",
                    fit_.front().first, frame.index, median);
    }
    fit_.pop_front();
  }

  static constexpr int kGreyLevels = 4;  // channels this far apart are grey (4:2:0 chroma noise of +-2)
  static constexpr int kFitFrames = 10;
  static constexpr double kPoorFit = 0.35;
  std::deque<std::pair<int, double>> fit_;  // frame, D: the last tracked frames
  bool said_fit_ = false;
  const ObservationConfig& o_;
  bool said_grey_ = false, said_empty_ = false, seen_any_ = false;
};

}  // namespace

namespace {

// Resuming a folder: its images are numbered by their place in name order,
// so images removed, added or renamed before the frames done would give the
// resumed frames other images under the numbers the run goes on with. The
// last frame done must still be the image its row names.
void check_resumed_folder(const TrackOptions& options, ImageSize size, double fps, int frame) {
  std::error_code ec;
  if (!fs::is_directory(options.input, ec)) return;  // a video or a stack: its frames are its own
  std::ifstream in(options.out_dir / "estimates.jsonl", std::ios::binary);
  const std::string head = "{\"frame\":" + std::to_string(frame) + ",";
  std::string line, row;
  while (std::getline(in, line)) {
    if (line.rfind(head, 0) == 0) row = line;
  }
  const std::string key = ",\"image\":";
  const size_t at = row.find(key);
  if (at == std::string::npos) return;  // a row written before rows named their image
  // The row's name as written: a JSON string, to its closing quote.
  size_t close = at + key.size() + 1;
  while (close < row.size() && row[close] != '"') close += row[close] == '\\' ? 2 : 1;
  const std::string was = row.substr(at + key.size(), close + 1 - (at + key.size()));
  FrameRange one;
  one.first = frame;
  one.last = frame + 1;
  auto probe = open_frame_source(options.input, size, one, fps);
  probe->set_quiet();
  const std::optional<Frame> now = probe->next();
  if (now) {
    // By file name: the folder itself may be given another way (relative,
    // absolute) on resuming.
    // The row's name ends in this one's, after the folder's '/' or the opening quote.
    const std::string name = json_string(fs::path(now->name).filename().string()).substr(1);  // name"
    if (was.size() > name.size() && was.compare(was.size() - name.size(), name.size(), name) == 0) {
      const char before = was[was.size() - name.size() - 1];
      if (before == '/' || before == '"') return;
    }
  }
  throw InputError(options.input + ": frame " + std::to_string(frame) + " was " + was + " in the run being resumed, " +
                   (now ? "is now " + json_string(now->name) : std::string("is now past the folder's last image")) +
                   " (images removed, added or renamed before it); cannot resume, the frames would be numbered "
                   "otherwise (put the images back as they were, or start a new run with another --out)");
}

}  // namespace

TrackSummary track_sequence(const Setup& setup, const EngineConfig& config, const TrackOptions& options) {
  const auto start = Clock::now();
  // Inputs are checked before anything is written.
  {
    std::error_code ec;
    if (fs::exists(options.out_dir, ec) && !fs::is_directory(options.out_dir, ec)) {
      throw InputError(options.out_dir.string() + ": is a file; expected an output folder (--out)");
    }
  }
  std::optional<StimulusLog> log;
  if (options.follow_stimulus && !options.stimulus_csv) {
    throw InputError("following the stimulus log needs a log (--stimulus FILE)");
  }
  if (options.follow_stimulus && options.resume) {
    throw InputError(
        "a run that follows its stimulus log cannot be resumed: its frames took the log's last row as it was "
        "written, which the finished log no longer tells apart");
  }
  std::map<int, Eigen::VectorXd> restart_rows;
  if (options.restart_from) {
    const PoseTable table = read_gripper_poses(*options.restart_from, setup, false);
    for (const auto& row : table.rows) {
      if (!row.h.allFinite()) {
        throw InputError(options.restart_from->string() + ": frame " + std::to_string(row.frame) +
                         ": a configuration that is not finite cannot be a start (nan or inf in the row)");
      }
      restart_rows[row.frame] = row.h;
    }
  }
  std::map<int, Eigen::VectorXd> reference_rows;
  if (options.score_truth) {
    const PoseTable table = read_gripper_poses(*options.score_truth, setup, true);
    for (const auto& row : table.rows) reference_rows[row.frame] = row.h;
  }
  int restarts_used = 0, references_used = 0;
  // Resuming: the saved state says which frame was done last; the source
  // starts at the next frame of the range.
  const fs::path state_file = options.out_dir / "tracker_state.txt";
  std::optional<TrackerState> resumed;
  FrameRange range = options.range;
  if (options.newest && options.input.rfind("camera:", 0) != 0 && !(options.follow_input_s > 0)) {
    throw InputError("--newest is for a live source (camera:N, or a folder followed with --follow-input), not " +
                     options.input + ", whose frames are all there to be tracked");
  }
  if (options.resume && options.input.rfind("camera:", 0) == 0) {
    throw InputError("--resume continues a video or a folder of images, not a live camera (" + options.input + ")");
  }
  // What this run tracks, kept in its state: a resumed run must go on
  // with the same frames and readings.
  const auto absolute = [](const std::string& path) {
    std::error_code ec;
    const fs::path p = fs::weakly_canonical(fs::absolute(path, ec), ec);
    return ec ? path : p.string();
  };
  // (Control characters escaped, so that any path fits on the state's line.)
  const std::string run =
      shown("input=" + (options.input.rfind("camera:", 0) == 0 ? options.input : absolute(options.input)) +
                " from=" + std::to_string(range.first) + " every=" + std::to_string(std::max(1, range.every)) + " stimulus=" +
                (options.stimulus_csv ? absolute(options.stimulus_csv->string()) : std::string("none")) +
                (options.stimulus_column.empty() ? std::string() : " column=" + options.stimulus_column) +
                (options.stimulus_offset_s != 0 ? fmt::format(" offset={}", options.stimulus_offset_s)
                                                : std::string()) +
                (options.follow_stimulus ? " followed" : ""),
            1 << 16);
  // Beside the config and the files it names, what the results come from:
  // the stimulus log (a followed one cannot be resumed), the framework's
  // library and the plugins'. run_config.toml keeps their fingerprints, and
  // a resumed run refuses to go on once one has changed.
  std::vector<NamedFile> used;
  std::optional<std::uintmax_t> log_bytes;  // of a grown log, the bytes the run being resumed read
  if (options.stimulus_csv && !options.follow_stimulus) used.push_back({"", "--stimulus", *options.stimulus_csv});
  used.push_back({"", "gtrack library", framework_library_file()});
  if (setup.loader) {
    for (const PluginRecord& p : setup.loader->loaded()) {
      used.push_back({"", std::string(to_string(p.kind)) + " plugin " + p.name, p.file});
    }
  }
  if (options.resume && fs::exists(state_file)) {
    resumed = read_tracker_state(state_file);
    // A state written before the run line named its first frame started
    // at frame 0.
    std::string ran = resumed->run;
    if (!ran.empty() && ran.find(" from=") == std::string::npos && ran.find(" every=") != std::string::npos) {
      ran.insert(ran.find(" every="), " from=0");
    }
    if (!ran.empty() && ran != run) {
      throw InputError(state_file.string() + ": the run being resumed tracked " + shown(ran, 300) +
                       "; this one " + shown(run, 300) +
                       "; cannot resume (give the same --input, first frame of --frames, --every, --stimulus, "
                       "--stimulus-column and --stimulus-offset, or another --out; a run that followed its stimulus "
                       "log cannot be resumed)");
    }
    // A stimulus log may have grown since (a logger still writing): the
    // run read it once at its start, and the resumed one reads those bytes
    // only, so that its frames take the readings the run would have.
    const auto grown = detail::check_same_config(options.out_dir / detail::kRunConfigName, setup.root, used,
                                                 {"--stimulus"});
    if (const auto it = grown.find("--stimulus"); it != grown.end()) log_bytes = it->second;
    const int every = std::max(1, range.every);
    if (resumed->frame >= range.first) range.first += ((resumed->frame - range.first) / every + 1) * every;
  } else if (options.resume) {
    // Estimates without the state they end with cannot be continued, and
    // starting over would replace them.
    if (holds_estimates(options.out_dir)) {
      throw InputError((options.out_dir / "estimates.csv").string() + ": holds tracked frames but " +
                       state_file.filename().string() +
                       " is missing; cannot resume (a new run would replace them: choose another --out, or run "
                       "without --resume)");
    }
    logger().info("{}: no tracker state to resume from; starting from the first frame", state_file.string());
  }
  // Raised to stop a followed folder's wait: at a cancel, or when the run
  // stops reading.
  std::atomic<bool> halt_reading{false};
  auto source = open_frame_source(options.input, setup.sensor->image_size(), range,
                                  config.tracker.fps > 0 ? config.tracker.fps : 30.0,
                                  FollowOptions{options.follow_input_s, &halt_reading, options.newest});
  source->set_image_bits(config.tracker.image_bits);
  const double fps = config.tracker.fps > 0 ? config.tracker.fps : (source->fps() > 0 ? source->fps() : 30.0);
  if (resumed) check_resumed_folder(options, setup.sensor->image_size(), fps, resumed->frame);
  if (config.tracker.fps > 0 && source->fps() > 0 && std::abs(source->fps() / config.tracker.fps - 1) > 0.01) {
    // A video's own rate set aside: its frame times, a time_s log and the
    // stimulus's response run on the config's.
    logger().warn("{}: the {} says {:g} frames/s, [tracker] fps = {:g} is taken; its frame times, a time_s "
                  "stimulus log and the material's response run on {:g} (remove fps to take the file's)",
                  options.input, detail::is_dicom_file(options.input) ? "DICOM file" : "video", source->fps(),
                  config.tracker.fps, config.tracker.fps);
  }
  // A pixel size the input gives (a scanner's DICOM export) that is not the
  // sensor's (pixel_size_mm): positions would be scaled wrong.
  if (const auto pixel = source->pixel_size_mm(); pixel && setup.sensor->mm_per_pixel() > 0) {
    const Eigen::Vector2d sensor_pixel = pixel_size_mm(*setup.sensor);
    const double w = sensor_pixel.x(), h = sensor_pixel.y();
    const auto off = [](double file, double sensor) { return !(std::abs(file / sensor - 1) <= 0.02); };
    if (off(pixel->first, w) || off(pixel->second, h)) {
      logger().warn("{}: its pixels are {:.4g} x {:.4g} mm (width x height, as the file says), the sensor's {:.4g} x "
                    "{:.4g} mm: positions and the gripper's size in the image are taken at the sensor's; set [sensor] "
                    "to the file's (an ultrasound_slice: mm_per_pixel = {:.4g}, mm_per_pixel_depth = {:.4g})",
                    options.input, pixel->first, pixel->second, w, h, pixel->first, pixel->second);
    } else {
      logger().debug("{}: its pixels are {:.4g} x {:.4g} mm, as the sensor's", options.input, pixel->first,
                     pixel->second);
    }
  }
  // The readings are checked before a frame is tracked, each by an instance
  // of the stimulus plugin of its own: the configured default, and each log
  // row as it is read, at its frame's time, so that one the plugin refuses
  // (a temperature in kelvin, a change faster than it allows) is an error
  // naming its key or its line.
  if (!setup.stimulus && options.stimulus_csv) {
    throw ConfigError(options.stimulus_csv->string() + ": a stimulus log, but the config has no [stimulus] table "
                      "naming the plugin that reads it; expected one (temperature_hysteresis, threshold_hysteresis, "
                      "a plugin of the lab's), or no --stimulus");
  }
  if (!setup.stimulus && config.tracker.default_stimulus) {
    throw ConfigError(setup.root.table("tracker").where("default_stimulus") +
                      ": a default reading, but the config has no [stimulus] table naming the plugin that reads it");
  }
  const bool can_probe = setup.loader && setup.stimulus;
  const auto make_probe = [&] { return setup.loader->make_stimulus(setup.root.table("stimulus")); };
  if (can_probe && config.tracker.default_stimulus) {
    try {
      make_probe()->update(*config.tracker.default_stimulus, 0);
    } catch (const std::exception& e) {
      throw ConfigError(setup.root.table("tracker").where("default_stimulus") + ": " + e.what());
    }
  }
  if (options.stimulus_csv) {
    // The readings' unit once the header is read, before any row: a log in
    // another unit would otherwise be refused for its first reading past
    // the plugin's range, pointing at the range instead of the unit.
    StimulusLog::HeaderCheck unit;
    if (setup.stimulus) {
      unit = [&setup](const StimulusLog& header) {
        check_log_unit(header, *setup.stimulus,
                       setup.root.has("stimulus") ? setup.root.table("stimulus").string_or("plugin", "") : "");
      };
    }
    StimulusLog::ReadingCheck check;
    if (can_probe) {
      check = [probe = make_probe(), fps](double value, StimulusLog::Key key, double at) {
        probe->update(value, key == StimulusLog::Key::Time ? at : at / fps);
      };
    }
    log = options.follow_stimulus
              ? StimulusLog::follow(*options.stimulus_csv, std::move(check), options.stimulus_column, std::move(unit))
              : StimulusLog::load(*options.stimulus_csv, std::move(check), options.stimulus_column, std::move(unit),
                                  log_bytes);
    if (log_bytes) {
      std::error_code ec;
      const auto now = fs::file_size(*options.stimulus_csv, ec);
      logger().info("{}: has grown from {} to {} bytes since the run being resumed began; only its first {}, "
                    "unchanged, are read, as that run read them (a new run, without --resume, reads the rows added)",
                    options.stimulus_csv->string(), *log_bytes, ec ? std::string("?") : std::to_string(now),
                    *log_bytes);
    }
    if (options.stimulus_offset_s != 0) log->shift_time(options.stimulus_offset_s);
  }
  const int expected = expected_frames(*source, range);
  const std::string described = source->description();
  if (!resumed && expected == 0) {
    throw InputError(options.input + ": holds " + std::to_string(source->frame_count()) +
                     " frames, none of them in --frames " + std::to_string(range.first) + ":" +
                     (range.last >= 0 ? std::to_string(range.last) : std::string()));
  }
  if (log && !options.follow_stimulus) check_log_covers_frames(*log, options, range, expected, fps, config.tracker.fps,
                                                                  source->fps());

  // The reading of a frame: the log's, or its nearest past the log's ends.
  bool warned_range = false;
  // A followed log that stops growing (a logger that hung): said once
  // while it stays so, the frames holding its last reading. Stale: no row
  // for 5 s, or for three times the logger's usual interval if longer (one
  // that writes every 10 s is not stale between its rows).
  constexpr double kStaleLogS = 5;
  bool said_stale = false;
  // A frame's reading, and for a followed log its age when read.
  struct Reading {
    std::optional<double> value;
    std::optional<double> age_s;
  };
  const auto reading_at = [&](int index, double time_s) -> Reading {
    if (!log) return {};
    if (options.follow_stimulus) {
      log->poll();
      const std::optional<double> reading_age = log->latest_age_s();
      const double stale_after = std::max(kStaleLogS, 3 * log->typical_row_gap_s().value_or(0));
      if (reading_age && *reading_age > stale_after && !said_stale) {
        logger().warn("{}: the followed stimulus log has had no new row for {:.1f} s (frame {}); the frames hold its "
                      "last reading, {:g}, and estimates.jsonl gives its age (stimulus_age_s)",
                      log->source(), *reading_age, index, *log->latest());
        said_stale = true;
      } else if (reading_age && *reading_age <= stale_after && said_stale) {
        logger().info("{}: the followed stimulus log has new rows again (frame {})", log->source(), index);
        said_stale = false;
      }
      return {log->latest(), reading_age};
    }
    std::optional<double> reading = log->value_at(index, time_s);
    if (!reading) {
      const bool by_time = log->key() == StimulusLog::Key::Time;
      if (by_time && log->first_key() > time_s + 86400) {
        // Another clock: seconds since 1970 (Unix time), say.
        throw InputError(another_clock(*log, index, time_s));
      }
      // A time written with few decimals (59 / 15 s as 3.9333) is the
      // frame's own row: within half a frame of the log's ends, no warning.
      const bool rounded = by_time && time_s > log->first_key() - 0.5 / fps && time_s < log->last_key() + 0.5 / fps;
      if (!warned_range && !rounded) {
        logger().warn("{}: frame {} (t = {:.3f} s) is outside the stimulus log, whose rows cover {} {:.{}f} to "
                      "{:.{}f}{}; holding its nearest reading",
                      log->source(), index, time_s, by_time ? "t =" : "frames", log->first_key(), by_time ? 3 : 0,
                      log->last_key(), by_time ? 3 : 0, log->shift_note());
        warned_range = true;
      }
      reading = log->nearest(index, time_s);
    }
    return {reading, std::nullopt};
  };

  // The tracker and its renderer are made before the first frame is waited
  // for: a renderer that cannot start (a gl backend without its device or
  // shaders) says so at once, not when a followed folder's first image
  // comes.
  Tracker tracker(setup, config);
  // The first frame is read before an earlier run in the folder is
  // replaced: an input that fails at once (another image size, a video
  // that does not decode) leaves that run as it was, and so does a
  // followed folder that never gets an image.
  detail::ReadAhead reader(*source, halt_reading, options.cancel, options.newest);
  std::optional<Frame> pending;
  double pending_read_s = 0;
  if (!resumed) {
    pending = reader.next(pending_read_s);
    if (!pending) {
      reader.stop();
      // A damaged video that stops before the range's first frame.
      if (const std::string ended = source->ended_early(); !ended.empty()) {
        throw InputError(options.input + ": " + ended + ", before the first frame of --frames " +
                         std::to_string(range.first) + ":" + (range.last >= 0 ? std::to_string(range.last) : "") +
                         "; nothing was tracked");
      }
      logger().warn("{}: no frame to track; {} is left as it was", options.input, options.out_dir.string());
      TrackSummary none;
      none.cancelled = options.cancel && options.cancel->load();
      none.mean_cost = std::numeric_limits<double>::quiet_NaN();
      return none;
    }
  }
  bool pending_taken = !pending.has_value();
  // One run at a time in a folder: two would write each other's rows into
  // the same files. The lock goes with the process, however it ends.
  const OutputLock lock(options.out_dir);
  if (resumed) {
    // Refused (a state of another setup) before any file is touched.
    try {
      tracker.restore(*resumed);
    } catch (const Error& e) {
      throw InputError(state_file.string() + ": " + e.what() + "; cannot resume");
    }
  }
  // The files are cut back to the frame the saved state records.
  std::vector<int> done;
  if (resumed) {
    done = resume_results(options.out_dir, setup.model().fingers(), resumed->frame);
  } else {
    // A fresh run replaces whatever an earlier one left in the folder,
    // and nothing else.
    const fs::path kept = options.out_dir / detail::kRunConfigName;
    if (fs::exists(kept) && !detail::written_by_a_run(kept)) {
      throw InputError(kept.string() + ": exists and was not written by gtrack track, which keeps a run's config "
                       "there; move it, or choose another --out");
    }
    const bool earlier = fs::exists(options.out_dir / "estimates.csv");
    if (clear_previous_run(options.out_dir) > 0 || earlier) {
      logger().warn("{} holds an earlier run{}: it is replaced{}", options.out_dir.string(),
                    options.resume ? " with no finished frame" : "",
                    options.resume ? "" : " (--resume would have gone on with it)");
    }
  }
  ResultWriter results(options.out_dir, setup.model().fingers(), resumed.has_value());
  if (!resumed) {
    detail::write_run_config(options.out_dir / detail::kRunConfigName, setup.root, options.durable, used);
  }
  if (options.save_masks) {
    std::error_code ec;
    fs::create_directories(options.out_dir / "masks", ec);
    if (ec) throw InputError((options.out_dir / "masks").string() + ": cannot create (" + ec.message() + ")");
  }
  // The stimulus plugin's state (a latch that has closed, a fold under way)
  // holds what the log said before each tracked frame: the readings of the
  // frames not tracked, before --frames A:B's first and between --every's,
  // are fed to it as well, in order (those the log has; a followed log has
  // only its last).
  int fed = 0;  // the frames before this one have been fed
  const auto feed_untracked = [&](int index) {
    if (log && !options.follow_stimulus && options.feed_untracked_readings) {
      for (; fed < index; ++fed) {
        if (const auto r = log->value_at(fed, fed / fps)) tracker.replay_stimulus(r, fed / fps);
      }
    }
    fed = std::max(fed, index + 1);
  };
  if (resumed) {
    // The stimulus plugin's state is rebuilt by replaying the readings of
    // the frames already done, in order.
    for (const int index : done) {
      feed_untracked(index);
      tracker.replay_stimulus(reading_at(index, index / fps).value, index / fps);
    }
    logger().info("resuming after frame {} ({} frames already in {})", resumed->frame, done.size(),
                  options.out_dir.string());
  }
  const bool want_overlay = options.overlay.value_or(config.tracker.overlay);
  char overlay_stem[48] = "overlay";
  if (resumed) std::snprintf(overlay_stem, sizeof overlay_stem, "overlay_from_%06d", range.first);
  if (resumed && want_overlay) check_earlier_overlays(options.out_dir, overlay_stem);
  OverlayWriter overlay(options.out_dir, fps / std::max(1, options.range.every), overlay_stem, *setup.sensor,
                        setup.model());
  Progress progress(options.progress, expected, config.tracker.progress_every);

  if (!log && !config.tracker.default_stimulus) {
    logger().info("no stimulus log and no [tracker] default_stimulus: S(H) and the biased initialisation are off");
  } else if (!log) {
    logger().info("no stimulus log: the stimulus is held at [tracker] default_stimulus = {}",
                  *config.tracker.default_stimulus);
  }
  logger().info("tracking {} with the {} renderer ({}x{} render size), N={} G={}", described,
                tracker.renderer().name(), tracker.renderer().render_size().width,
                tracker.renderer().render_size().height, config.pso.particles, config.pso.generations);

  TrackSummary summary;
  summary.renderer = tracker.renderer().name();
  if (resumed) {
    summary.resumed_after = resumed->frame;
    summary.frames_before = static_cast<int>(done.size());
  }
  double cost_sum = 0, ms_sum = 0;
  StageTimes sums;
  int previous_index = -1;  // the last frame tracked by this run
  ObservationAdvice advice(config.observation);
  // The summary's figures taken and the files closed, once, at the end or
  // at an error that stops the run: the figures first, so that an error
  // closing a file (the overlay's encoder) still leaves them to the summary.
  bool finished = false;
  const auto finish = [&] {
    if (finished) return;
    finished = true;
    progress.finish();
    reader.stop();
    const int n = std::max(1, summary.frames);
    const int found = summary.frames - summary.lost_frames;
    summary.mean_cost = found > 0 ? cost_sum / found : std::numeric_limits<double>::quiet_NaN();
    summary.input_ended_early = source->ended_early();
    summary.skipped_frames = reader.skipped() + source->skipped();
    if (log) summary.skipped_stimulus_rows = log->skipped_rows();
    summary.mean_ms = ms_sum / n;
    summary.mean_times = {sums.segment_ms / n, sums.pso_ms / n, sums.io_ms / n};
    summary.wall_s = seconds_since(start);
    results.close();
    overlay.close();
    summary.overlay_file = overlay.file();
  };
  try {
    for (;;) {
      if (options.cancel && options.cancel->load()) {
        summary.cancelled = true;
        break;
      }
      std::optional<Frame> frame;
      double read_s = pending_read_s;
      if (!pending_taken) {
        frame = std::move(pending);
        pending_taken = true;
      } else {
        frame = reader.next(read_s);
      }
      if (!frame) {
        // A followed folder's wait ends at a cancel as at its idle limit; any
        // other source has simply ended.
        summary.cancelled = options.follow_input_s > 0 && options.cancel && options.cancel->load();
        break;
      }
      // Reading as far as the tracker waited for it, less the camera's time.
      double io_ms = std::max(0.0, read_s - frame->waited_s) * 1e3;
      const double time_s = frame->index / fps;
      feed_untracked(frame->index);
      const Reading reading = reading_at(frame->index, time_s);

      if (!restart_rows.empty()) {
        const auto row = restart_rows.find(previous_index >= 0 ? previous_index : frame->index - range.every);
        if (row != restart_rows.end()) {
          tracker.set_estimate(row->second);
          ++restarts_used;
        }
      }
      Estimate e = tracker.process(frame->image, frame->index, time_s, reading.value);
      e.stimulus_age_s = reading.age_s;
      advice.after(*frame, e, tracker.last_observation(), summary.frames == 0);
      previous_index = frame->index;
      if (const auto row = reference_rows.find(frame->index); row != reference_rows.end()) {
        // Of the reference's symmetric equivalents, the one nearest the estimate.
        const Eigen::VectorXd reference = detail::nearest_equivalent(setup.model(), row->second, e.hypothesis);
        e.reference_terms = tracker.score(reference);
        ++references_used;
      }

      // The row first (and the stream's line with it): a controller gets the
      // estimate before the overlay is drawn and encoded. The state, which
      // says the frame is done, comes last.
      const auto t_write = Clock::now();
      e.times.io_ms = io_ms;
      e.image = frame->name;
      e.read_unix_s = frame->read_unix_s;
      e.written_unix_s = frame->written_unix_s;
      e.unix_time_s =
          std::chrono::duration<double>(std::chrono::system_clock::now().time_since_epoch()).count();
      results.write(e);
      if (options.durable) results.sync();  // the rows before the state that says they are done
      if (options.on_frame) options.on_frame(e);
      if (options.save_masks) {
        char name[32];
        std::snprintf(name, sizeof name, "%06d.png", frame->index);
        const fs::path p = options.out_dir / "masks" / name;
        if (!cv::imwrite(p.string(), tracker.last_observation().mask)) throw InputError(p.string() + ": cannot write");
      }
      if (want_overlay) overlay.write(frame->image, e, detail::reading_text(setup.stimulus.get(), e));
      TrackerState state = tracker.state();
      state.run = run;
      write_tracker_state(state_file, state, options.durable);
      io_ms += seconds_since(t_write) * 1e3;

      ++summary.frames;
      if (e.status == TrackStatus::Lost) ++summary.lost_frames;
      else cost_sum += e.terms.total;
      ms_sum += e.ms;
      sums.segment_ms += e.times.segment_ms;
      sums.pso_ms += e.times.pso_ms;
      sums.io_ms += io_ms;
      progress.update(summary.frames, frame->index, seconds_since(start));
    }
    finish();
  } catch (const std::exception& e) {
    // An error part way (an unreadable image, a log that shrank): the
    // frames done stay, the summary says what stopped the run, and the
    // error, still one line, says where they are.
    if (summary.frames_before + summary.frames == 0) throw;
    std::string kept;
    try {
      summary.stopped_by = e.what();
      try {
        finish();
      } catch (const std::exception&) {
        // A second error closing the files: the first is the one to report.
      }
      const int done = summary.frames_before + summary.frames;
      const bool resumable = !options.follow_stimulus && options.input.rfind("camera:", 0) != 0;
      kept = fmt::format("; the {} frame{} before it {} kept in {}{}", done, done == 1 ? "" : "s",
                         done == 1 ? "is" : "are", options.out_dir.string(),
                         resumable ? " (--resume goes on once the cause is mended; a changed config or plugin "
                                     "needs a new run)"
                                   : "");
      // A resumed run that stops at its first frame leaves the earlier
      // run's summary as it was. (On a full disk the summary cannot be
      // written either; the rows are what is kept.)
      if (summary.frames > 0) write_summary(options.out_dir / "summary.json", summary);
    } catch (const std::exception&) {
      // The error that stopped the run is the one to report.
    }
    // gtrack's own errors say what was kept, as the kind they are.
    if (!kept.empty() && dynamic_cast<const Error*>(&e)) {
      const std::string what = e.what() + kept;
      if (dynamic_cast<const InputError*>(&e)) throw InputError(what);
      if (dynamic_cast<const PluginError*>(&e)) throw PluginError(what);
      if (dynamic_cast<const ConfigError*>(&e)) throw ConfigError(what);
      throw Error(what);
    }
    throw;
  }
  // A table of other frames (renumbered, another sequence's) changes nothing: said.
  const auto warn_unused = [&](const std::optional<std::filesystem::path>& file, const std::map<int, Eigen::VectorXd>& rows,
                               int used, const char* option, const char* matched) {
    if (file && !rows.empty() && used == 0 && summary.frames > 1 && !summary.cancelled) {
      logger().warn("{}: none of its rows (frames {} to {}) is {} (the last tracked: {}); {} changed nothing",
                    file->string(), rows.begin()->first, rows.rbegin()->first, matched, previous_index, option);
    }
  };
  // A frame restarts from the row of the frame before it.
  warn_unused(options.restart_from, restart_rows, restarts_used, "--restart-from", "the frame before a tracked one");
  warn_unused(options.score_truth, reference_rows, references_used, "--score-truth", "a tracked frame");
  // Resuming a finished run tracks nothing: its summary stays, said done.
  const fs::path summary_file = options.out_dir / "summary.json";
  if (resumed && summary.frames == 0) {
    mend_cancelled_summary(summary_file);
  } else {
    write_summary(summary_file, summary);
  }
  return summary;
}

}  // namespace gtrack
