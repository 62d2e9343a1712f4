// Faults in the middle of a run: what the user sees and what data survives.
//
// Each case drives `track_sequence` (the library form of `gtrack track`) or
// the gtrack executable into one fault and checks the promise made in
// docs/reliability.md: one line saying what went wrong, and every frame
// finished before the fault present and well-formed in estimates.csv.
// Runs are tiny (128x128 frames, N=8, G=2) so the whole file takes seconds.
#include <gtest/gtest.h>
#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>
#include <gtrack/results.hpp>
#include <algorithm>
#include <chrono>
#include <numeric>
#include <thread>
#include <sys/wait.h>
#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <array>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>
#include <spdlog/sinks/ostream_sink.h>
#include <sstream>
#include <string>
#include <vector>

#include "gtrack/config.hpp"
#include "gtrack/engine_config.hpp"
#include "gtrack/error.hpp"
#include "gtrack/log.hpp"
#include "gtrack/two_pass.hpp"
#include "support/logged.hpp"
#include "gtrack/setup.hpp"
#include "gtrack/text_file.hpp"
#include "gtrack/tracker.hpp"

namespace fs = std::filesystem;

namespace {

constexpr int kSide = 128;
constexpr int kFrames = 8;

std::string read_text(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

// tests/data/microscope_128.toml (shared with scripts/soak.sh) and a tiny swarm.
const std::string kConfig = read_text(fs::path(GTRACK_TEST_SOURCE_DIR) / "tests" / "data" / "microscope_128.toml") + R"(
[pso]
particles = 8
generations = 2
[render]
backend = "cpu"
[tracker]
overlay = false
initial_pose = [0, 0, 100, 0, 0, 0, 0, 0, 0, 0, 0, 0]
)";

// Per process (two checkouts' suites may run on one machine at once), and
// removed when the process ends.
const fs::path& fault_root() {
  struct Root {
    fs::path path = fs::temp_directory_path() / ("gtrack_fault_test_" + std::to_string(::getpid()));
    ~Root() {
      std::error_code ec;
      fs::remove_all(path, ec);
    }
  };
  static const Root root;
  return root.path;
}

fs::path fresh_dir(const std::string& name) {
  const fs::path d = fault_root() / name;
  fs::remove_all(d);
  fs::create_directories(d);
  return d;
}

// A saturated disc that moves a little: the segmentation finds something in
// every frame, so each frame runs the whole pipeline.
cv::Mat frame_image(int i) {
  cv::Mat img(kSide, kSide, CV_8UC3, cv::Scalar(40, 40, 40));
  cv::circle(img, {60 + i % 5, 64}, 20, cv::Scalar(0, 200, 0), cv::FILLED);
  return img;
}

fs::path write_frames(const fs::path& dir, int n) {
  fs::create_directories(dir);
  for (int i = 0; i < n; ++i) {
    char name[32];
    std::snprintf(name, sizeof name, "%06d.png", i);
    cv::imwrite((dir / name).string(), frame_image(i));
  }
  return dir;
}

// Options for tracking n frames of write_frames into dir/out, quietly.
gtrack::TrackOptions folder_run(const fs::path& dir, int n) {
  gtrack::TrackOptions o;
  o.input = write_frames(dir / "frames", n).string();
  o.out_dir = dir / "out";
  o.progress = false;
  return o;
}

// Options for following the folder `live` (--follow-input idle_s) into
// dir/out, quietly.
gtrack::TrackOptions followed_run(const fs::path& live, const fs::path& dir, double idle_s) {
  gtrack::TrackOptions o;
  o.input = live.string();
  o.out_dir = dir / "out";
  o.progress = false;
  o.follow_input_s = idle_s;
  return o;
}

struct TrackRun {
  gtrack::Setup setup;
  gtrack::EngineConfig config;
};

TrackRun make_run(const std::string& extra = "") {
  TrackRun r{gtrack::load_setup(gtrack::ConfigTable::parse(kConfig + extra, "fault.toml"), {}), {}};
  r.config = gtrack::engine_config(r.setup);
  gtrack::check_root_keys(r.setup);
  return r;
}

std::vector<std::string> read_lines(const fs::path& p) {
  std::ifstream in(p);
  std::vector<std::string> out;
  for (std::string l; std::getline(in, l);) out.push_back(l);
  return out;
}

// estimates.csv: a header and then rows of exactly as many fields, the
// frame indices increasing; returns the frame indices.
std::vector<int> valid_rows(const fs::path& csv) {
  const auto lines = read_lines(csv);
  EXPECT_FALSE(lines.empty()) << csv;
  if (lines.empty()) return {};
  const auto fields = [](const std::string& s) { return std::count(s.begin(), s.end(), ',') + 1; };
  const auto n = fields(lines[0]);
  EXPECT_EQ(lines[0].rfind("frame,x_mm", 0), 0u) << lines[0];
  std::vector<int> frames;
  for (size_t i = 1; i < lines.size(); ++i) {
    EXPECT_EQ(fields(lines[i]), n) << "row " << i << ": " << lines[i];
    frames.push_back(std::stoi(lines[i]));
    if (frames.size() > 1) EXPECT_GT(frames.back(), frames[frames.size() - 2]);
  }
  return frames;
}

bool one_line(const std::string& s) { return !s.empty() && s.find('\n') == std::string::npos; }

// The message of the InputError a run stops with ("" when it runs through).
std::string track_error(const TrackRun& r, const gtrack::TrackOptions& o) {
  try {
    gtrack::track_sequence(r.setup, r.config, o);
  } catch (const gtrack::InputError& e) {
    return e.what();
  }
  return {};
}

// A refusal is one line that names `what`.
void expect_refusal_naming(const std::string& message, const std::string& what) {
  EXPECT_TRUE(one_line(message)) << (message.empty() ? "not refused" : message);
  EXPECT_NE(message.find(what), std::string::npos) << message;
}

struct CliRun {
  int code;
  std::string output;
};

CliRun gtrack_cli(const std::string& args, const std::string& redirect = "2>&1") {
  const std::string cmd = std::string(GTRACK_TEST_BINARY_DIR) + "/bin/gtrack " + args + " " + redirect;
  FILE* p = ::popen(cmd.c_str(), "r");
  std::string out;
  std::array<char, 4096> buf;
  while (p && std::fgets(buf.data(), buf.size(), p)) out += buf.data();
  const int status = p ? ::pclose(p) : -1;
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, out};
}

}  // namespace

// The reference: the same inputs without a fault give one row per frame.
TEST(Fault, NoFaultTracksEveryFrame) {
  const fs::path dir = fresh_dir("reference");
  const TrackRun r = make_run();
  gtrack::TrackOptions o = folder_run(dir, kFrames);
  const auto s = gtrack::track_sequence(r.setup, r.config, o);
  EXPECT_EQ(s.frames, kFrames);
  EXPECT_EQ(valid_rows(o.out_dir / "estimates.csv").size(), static_cast<size_t>(kFrames));
  EXPECT_TRUE(fs::exists(o.out_dir / "summary.json"));
}

// A video cut short (a recording interrupted, a partial copy): the frames
// that decode are tracked, the run ends normally with them. A frame rate
// in the config over the video's own is said.
TEST(Fault, TruncatedVideoKeepsTheFramesThatDecode) {
  const fs::path dir = fresh_dir("truncated_video");
  const fs::path avi = dir / "clip.avi";
  {
    cv::VideoWriter w(avi.string(), cv::VideoWriter::fourcc('M', 'J', 'P', 'G'), 10, {kSide, kSide});
    ASSERT_TRUE(w.isOpened()) << "no MJPG writer in this OpenCV build";
    for (int i = 0; i < 20; ++i) w.write(frame_image(i));
  }
  fs::resize_file(avi, fs::file_size(avi) * 6 / 10);

  const TrackRun r = make_run();
  gtrack::TrackOptions o;
  o.input = avi.string();
  o.out_dir = dir / "out";
  o.progress = false;
  const auto s = gtrack::track_sequence(r.setup, r.config, o);
  const auto rows = valid_rows(o.out_dir / "estimates.csv");
  EXPECT_GT(s.frames, 0);
  EXPECT_LT(s.frames, 20);
  EXPECT_EQ(rows.size(), static_cast<size_t>(s.frames));
  // The run says that the video ended before the frames it declares, in
  // the summary as well, so that a short video and a failed decode differ.
  const std::string said = "decoding stopped at frame " + std::to_string(s.frames) + " of the 20 the video declares";
  EXPECT_EQ(s.input_ended_early.rfind(said, 0), 0u) << s.input_ended_early;
  EXPECT_NE(read_text(o.out_dir / "summary.json").find("\"input_ended_early\": \"" + said), std::string::npos);
  // A range that starts past where decoding stops gives nothing: an error
  // that says so, not a run of no frames.
  gtrack::TrackOptions late = o;
  late.out_dir = dir / "late";
  late.range.first = 15;
  try {
    gtrack::track_sequence(r.setup, r.config, late);
    ADD_FAILURE() << "a range past the damage was tracked";
  } catch (const gtrack::InputError& e) {
    EXPECT_NE(std::string(e.what()).find(said), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("before the first frame of --frames 15:; nothing was tracked"),
              std::string::npos)
        << e.what();
  }
  // A whole video ends where it says.
  fs::remove(avi);
  {
    cv::VideoWriter w(avi.string(), cv::VideoWriter::fourcc('M', 'J', 'P', 'G'), 10, {kSide, kSide});
    for (int i = 0; i < 6; ++i) w.write(frame_image(i));
  }
  const auto whole = gtrack::track_sequence(r.setup, r.config, o);
  EXPECT_EQ(whole.frames, 6);
  EXPECT_EQ(whole.input_ended_early, "");
  EXPECT_NE(read_text(o.out_dir / "summary.json").find("\"input_ended_early\": null"), std::string::npos);
  // A config's frame rate set over the video's own is said.
  TrackRun at_30 = make_run();
  at_30.config.tracker.fps = 30;
  const std::string log = gtrack::testing::logged([&] { gtrack::track_sequence(at_30.setup, at_30.config, o); });
  EXPECT_NE(log.find("clip.avi: the video says 10 frames/s, [tracker] fps = 30 is taken"), std::string::npos) << log;
}

// Grey images for a segmentation by colour: every frame would be lost
// without a word, so the first frame says why, once; a blank frame (one
// value throughout: the lamp off) says nothing of the recording. Bounds that
// find nothing, or take most of the image, are said too.
TEST(Fault, WhatTheObservationMakesOfTheRecordingIsSaidOnce) {
  TrackRun r = make_run();
  const auto warnings_of = [&](const fs::path& frames, const fs::path& out) {
    gtrack::TrackOptions o;
    o.input = frames.string();
    o.out_dir = out;
    o.progress = false;
    std::string error;
    const std::string log = gtrack::testing::logged([&] {
      try {
        gtrack::track_sequence(r.setup, r.config, o);
      } catch (const std::exception& e) {
        error = e.what();
      }
    });
    EXPECT_EQ(error, "");
    return log;
  };
  const fs::path dir = fresh_dir("grey");
  const fs::path colour = write_frames(dir / "colour", 3);
  fs::create_directories(dir / "grey");
  for (int i = 0; i < 3; ++i) {
    cv::Mat grey;
    cv::cvtColor(frame_image(i), grey, cv::COLOR_BGR2GRAY);
    char name[32];
    std::snprintf(name, sizeof name, "%06d.png", i);
    cv::imwrite((dir / "grey" / name).string(), grey);
  }
  const std::string said = "a grey image (its channels within 0 levels of each other on 99.9 % of its pixels), but "
                           "[observation] color_space = \"hsv\" with saturation_min";
  const std::string grey_log = warnings_of(dir / "grey", dir / "out_grey");
  EXPECT_NE(grey_log.find("000000.png: " + said), std::string::npos) << grey_log;
  EXPECT_EQ(grey_log.find(said), grey_log.rfind(said)) << "said once: " << grey_log;
  EXPECT_EQ(warnings_of(colour, dir / "out_colour").find("a grey image"), std::string::npos);
  // A grey video decoded from 4:2:0 chroma: channels a level or two apart.
  fs::create_directories(dir / "near_grey");
  for (int i = 0; i < 3; ++i) {
    cv::Mat grey, bgr;
    cv::cvtColor(frame_image(i), grey, cv::COLOR_BGR2GRAY);
    cv::cvtColor(grey, bgr, cv::COLOR_GRAY2BGR);
    bgr.forEach<cv::Vec3b>([](cv::Vec3b& p, const int* at) { p[0] = cv::saturate_cast<uchar>(p[0] + (at[1] % 3)); });
    char name[32];
    std::snprintf(name, sizeof name, "%06d.png", i);
    cv::imwrite((dir / "near_grey" / name).string(), bgr);
  }
  const std::string near_log = warnings_of(dir / "near_grey", dir / "out_near_grey");
  EXPECT_NE(near_log.find("000000.png: a grey image (its channels within 2 levels of each other"), std::string::npos)
      << near_log;
  // One grey image among colour ones is said at that image.
  cv::Mat grey;
  cv::cvtColor(frame_image(1), grey, cv::COLOR_BGR2GRAY);
  cv::imwrite((colour / "000001.png").string(), grey);
  const std::string mixed_log = warnings_of(colour, dir / "out_mixed");
  EXPECT_NE(mixed_log.find("000001.png: " + said), std::string::npos) << mixed_log;
  EXPECT_EQ(mixed_log.find(said), mixed_log.rfind(said)) << "said once: " << mixed_log;
  // A black first frame before grey ones: said at the first grey one.
  cv::imwrite((dir / "grey" / "000000.png").string(), cv::Mat(kSide, kSide, CV_8UC1, cv::Scalar(0)));
  const std::string blank_log = warnings_of(dir / "grey", dir / "out_blank");
  EXPECT_EQ(blank_log.find("000000.png: " + said), std::string::npos) << blank_log;
  EXPECT_NE(blank_log.find("000001.png: " + said), std::string::npos) << blank_log;
  EXPECT_EQ(blank_log.find("no pixel within"), std::string::npos) << blank_log;
  // Colour frames whose colour the bounds exclude: every frame is lost.
  const fs::path plain = write_frames(dir / "plain", 3);
  r.config.observation.hue_min = 100;  // blue; the gripper is green
  r.config.observation.hue_max = 130;
  const std::string empty_log = warnings_of(plain, dir / "out_empty");
  const std::string nothing = "000000.png: no pixel within the [observation] bounds (hue 100 to 130, saturation 60 "
                              "to 255, value 0 to 255): the frame is lost";
  EXPECT_NE(empty_log.find(nothing), std::string::npos) << empty_log;
  EXPECT_EQ(empty_log.find("no pixel"), empty_log.rfind("no pixel")) << "said once: " << empty_log;
  // Bounds that would find it, but exclude_px over the whole image: said.
  r.config.observation.hue_min = 0;
  r.config.observation.hue_max = 180;
  r.config.observation.exclude_px = {cv::Rect(0, 0, kSide, kSide)};
  const std::string excluded_log = warnings_of(plain, dir / "out_excluded");
  EXPECT_NE(excluded_log.find("value 0 to 255), outside [observation] exclude_px's 1 rectangle (100 % of the "
                              "image): the frame is lost"),
            std::string::npos)
      << excluded_log;
  r.config.observation.exclude_px.clear();
  r.config.observation.hue_min = 100;
  r.config.observation.hue_max = 130;
  // A dark gripper on a light background, segmented for bright pixels.
  r.config.observation.color_space = "luminance";
  fs::create_directories(dir / "bright_field");
  for (int i = 0; i < 2; ++i) {
    cv::Mat inverted = cv::Scalar::all(255) - frame_image(i);
    cv::imwrite((dir / "bright_field" / ("00000" + std::to_string(i) + ".png")).string(), inverted);
  }
  const std::string bright_log = warnings_of(dir / "bright_field", dir / "out_bright");
  EXPECT_NE(bright_log.find("times the gripper's outline, is within the [observation] bounds (luminance 128 to "
                            "255): they take the background for the gripper"),
            std::string::npos)
      << bright_log;
  EXPECT_NE(bright_log.find("needs luminance_min = 0"), std::string::npos) << bright_log;
  // Bounds for a dark gripper that take in the background: luminance_max is
  // the bound to move.
  r.config.observation.luminance_min = 0;
  r.config.observation.luminance_max = 250;
  const std::string dark_log = warnings_of(dir / "bright_field", dir / "out_dark_bounds");
  EXPECT_NE(dark_log.find("lower luminance_max below the background's darkest brightness"), std::string::npos)
      << dark_log;
  r.config.observation.luminance_min = 128;
  r.config.observation.luminance_max = 255;
  EXPECT_EQ(warnings_of(plain, dir / "out_dark_field").find("is within the [observation] bounds"), std::string::npos);
}

// A folder whose image becomes unreadable part way: the run stops at that
// frame with one line naming the file; the frames before it are in the CSV,
// and the summary says what stopped it.
TEST(Fault, CorruptImageInFolderStopsWithTheFramesBefore) {
  const fs::path dir = fresh_dir("corrupt_image");
  const fs::path frames = write_frames(dir / "frames", kFrames);
  std::ofstream(frames / "000005.png", std::ios::trunc) << "not a png";

  const TrackRun r = make_run();
  gtrack::TrackOptions o;
  o.input = frames.string();
  o.out_dir = dir / "out";
  o.progress = false;
  expect_refusal_naming(track_error(r, o), "000005.png");
  EXPECT_EQ(valid_rows(o.out_dir / "estimates.csv"), (std::vector<int>{0, 1, 2, 3, 4}));
  // The summary says what stopped the run, with the frames done.
  const std::string summary = read_text(o.out_dir / "summary.json");
  EXPECT_NE(summary.find("\"frames\": 5,"), std::string::npos) << summary;
  EXPECT_NE(summary.find("\"stopped_by\": \""), std::string::npos) << summary;
  EXPECT_NE(summary.find("000005.png: cannot read the image"), std::string::npos) << summary;
  // Resumed before the image is mended, the run stops at once, and says
  // the earlier frames are still there.
  gtrack::TrackOptions again = o;
  again.resume = true;
  const std::string e = track_error(r, again);
  EXPECT_NE(e.find("; the 5 frames before it are kept in"), std::string::npos) << e;
  EXPECT_EQ(read_text(o.out_dir / "summary.json"), summary);
}

// A run whose input fails at its first frame (another image size) leaves
// the earlier run in its folder as it was; so does a followed folder that
// never gets an image.
TEST(Fault, AnInputThatFailsAtOnceLeavesTheEarlierRun) {
  const fs::path dir = fresh_dir("fails_at_once");
  const TrackRun r = make_run();
  gtrack::TrackOptions o = folder_run(dir, kFrames);
  gtrack::track_sequence(r.setup, r.config, o);
  const std::string rows = read_text(o.out_dir / "estimates.csv"), summary = read_text(o.out_dir / "summary.json");
  fs::create_directories(dir / "other");
  cv::imwrite((dir / "other" / "000000.png").string(), cv::Mat(kSide / 2, kSide, CV_8UC3, cv::Scalar::all(40)));
  gtrack::TrackOptions other = o;
  other.input = (dir / "other").string();
  EXPECT_THROW(gtrack::track_sequence(r.setup, r.config, other), gtrack::InputError);
  fs::create_directories(dir / "empty");
  other.input = (dir / "empty").string();
  other.follow_input_s = 0.2;
  EXPECT_EQ(gtrack::track_sequence(r.setup, r.config, other).frames, 0);
  EXPECT_EQ(read_text(o.out_dir / "estimates.csv"), rows);
  EXPECT_EQ(read_text(o.out_dir / "summary.json"), summary);
}

// A resume that finds every frame done keeps a finished run's summary; one
// that says the run was cancelled (a two-pass run interrupted in its
// backward pass has its forward frames all done) keeps its figures and
// says it is not (it had gone on saying cancelled after the resume
// completed the run); one that names an error keeps it.
TEST(Fault, AResumeWithNothingLeftKeepsAFinishedSummaryAndMendsAStoppedOne) {
  const fs::path dir = fresh_dir("resume_nothing_left");
  const TrackRun r = make_run();
  gtrack::TrackOptions o = folder_run(dir, kFrames);
  gtrack::track_sequence(r.setup, r.config, o);
  const fs::path file = o.out_dir / "summary.json";
  const std::string finished = read_text(file);
  gtrack::TrackOptions again = o;
  again.resume = true;
  EXPECT_EQ(gtrack::track_sequence(r.setup, r.config, again).frames, 0);
  EXPECT_EQ(read_text(file), finished);
  std::string stopped = finished;
  const std::string no = "\"cancelled\": false", yes = "\"cancelled\": true";
  ASSERT_NE(stopped.find(no), std::string::npos) << stopped;
  stopped.replace(stopped.find(no), no.size(), yes);
  std::ofstream(file, std::ios::trunc) << stopped;
  EXPECT_EQ(gtrack::track_sequence(r.setup, r.config, again).frames, 0);
  EXPECT_EQ(read_text(file), finished);
  std::string failed = stopped;
  const std::string none = "\"stopped_by\": null";
  ASSERT_NE(failed.find(none), std::string::npos) << failed;
  failed.replace(failed.find(none), none.size(), "\"stopped_by\": \"overlay.mp4: cannot be closed\"");
  std::ofstream(file, std::ios::trunc) << failed;
  EXPECT_EQ(gtrack::track_sequence(r.setup, r.config, again).frames, 0);
  EXPECT_EQ(read_text(file), failed);
}

// A file the run cannot write is named as the run's file, not its
// stand-in (FILE.tmp, renamed over it), with the system's reason; the
// frames before are kept.
TEST(Fault, AStateThatCannotBeWrittenIsNamedWithTheReason) {
  const fs::path dir = fresh_dir("state_unwritable");
  const TrackRun r = make_run();
  gtrack::TrackOptions o = folder_run(dir, 3);
  fs::create_directories(o.out_dir / "tracker_state.txt.tmp");  // in the way, as a full disk would be
  try {
    gtrack::track_sequence(r.setup, r.config, o);
    ADD_FAILURE() << "the run went on without its state";
  } catch (const gtrack::InputError& e) {
    const std::string what = e.what();
    EXPECT_EQ(what.rfind((o.out_dir / "tracker_state.txt").string() + ": cannot open for writing (Is a directory)", 0),
              0u)
        << what;
  }
}

// A second run into a folder another run is writing is refused, naming the
// other's pid: two runs had written each other's rows into the same files.
TEST(Fault, ASecondRunIntoABusyFolderIsRefused) {
  const fs::path dir = fresh_dir("busy");
  const TrackRun r = make_run();
  gtrack::TrackOptions o = folder_run(dir, 2);
  fs::create_directories(o.out_dir);
  // The other run's lock, as it holds it.
  const int fd = ::open((o.out_dir / ".gtrack_lock").c_str(), O_RDWR | O_CREAT, 0644);
  ASSERT_GE(fd, 0);
  ASSERT_EQ(::write(fd, "4242", 4), 4);
  ASSERT_EQ(::flock(fd, LOCK_EX | LOCK_NB), 0);
  try {
    gtrack::track_sequence(r.setup, r.config, o);
    ADD_FAILURE() << "a second run wrote into a busy folder";
  } catch (const gtrack::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("another gtrack track run is writing there (pid 4242)"), std::string::npos)
        << e.what();
  }
  EXPECT_FALSE(fs::exists(o.out_dir / "estimates.csv"));
  ::close(fd);  // the other run ends: the folder is free
  EXPECT_EQ(gtrack::track_sequence(r.setup, r.config, o).frames, 2);
}

// One process takes its folder's lock again (gtrack track --two-pass holds
// it from the forward run through the backward pass): the run goes on, and
// the folder stays locked to other processes until the last holder ends.
TEST(Fault, AnOutputLockIsTakenAgainWithinAProcessAndHeldUntilTheLastRelease) {
  const fs::path dir = fresh_dir("relocked");
  const TrackRun r = make_run();
  const gtrack::TrackOptions o = folder_run(dir, 2);
  const auto others_can_lock = [&] {
    const int fd = ::open((o.out_dir / ".gtrack_lock").c_str(), O_RDWR);
    const bool free = fd >= 0 && ::flock(fd, LOCK_EX | LOCK_NB) == 0;
    if (fd >= 0) ::close(fd);
    return free;
  };
  {
    const gtrack::OutputLock outer(o.out_dir);
    EXPECT_EQ(gtrack::track_sequence(r.setup, r.config, o).frames, 2);
    EXPECT_FALSE(others_can_lock()) << "the run's end released the lock its caller holds";
    // Another thread of the process is another run: refused.
    std::string refused;
    std::thread([&] {
      try {
        const gtrack::OutputLock other(o.out_dir);
      } catch (const gtrack::InputError& e) {
        refused = e.what();
      }
    }).join();
    EXPECT_NE(refused.find("another gtrack track run is writing there (pid " + std::to_string(::getpid()) +
                           ", this process, another thread)"),
              std::string::npos)
        << refused;
    std::ifstream pid(o.out_dir / ".gtrack_lock");
    EXPECT_EQ(std::string(std::istreambuf_iterator<char>(pid), {}), std::to_string(::getpid()));
  }
  EXPECT_TRUE(others_can_lock());
}

// The stimulus log's rows are checked before any frame is tracked by an
// instance of the plugin fed each row at its frame's time (it had been fed
// the row's number as seconds, so a plugin's rate limit let a spike
// through and stopped the run part way, naming no file).
TEST(Fault, AStimulusLogRowThePluginRefusesAtItsTimeStopsTheRunBeforeAnyFrame) {
  const fs::path dir = fresh_dir("rate_limited");
  std::string config = kConfig;
  const size_t at = config.find("[stimulus]");
  const size_t end = config.find("\n[", at + 1);
  ASSERT_NE(at, std::string::npos);
  config.replace(at, end - at, "[stimulus]\nplugin = \"fixture_wrong_stimulus\"\nwrong = \"max_rate\"");
  auto root = gtrack::ConfigTable::parse(config, "fault.toml");
  gtrack::SetupOptions so;
  so.plugin_paths = {GTRACK_TEST_FIXTURE_DIR};
  TrackRun r{gtrack::load_setup(root, so), {}};
  r.config = gtrack::engine_config(r.setup);
  gtrack::TrackOptions o = folder_run(dir, 3);
  // 30 frames/s: 0.5 a frame is 15 a second; 3 in one frame is 90 (taken),
  // 5 is 150 (refused). As rows one second apart, both were taken.
  std::ofstream(dir / "ok.csv") << "frame,value\n0,20\n1,20.5\n2,23.5\n";
  std::ofstream(dir / "spike.csv") << "frame,value\n0,20\n1,20.5\n2,25.5\n";
  o.stimulus_csv = dir / "ok.csv";
  EXPECT_EQ(gtrack::track_sequence(r.setup, r.config, o).frames, 3);
  o.stimulus_csv = dir / "spike.csv";
  o.out_dir = dir / "spiked";
  try {
    gtrack::track_sequence(r.setup, r.config, o);
    ADD_FAILURE() << "a reading the plugin refuses was tracked";
  } catch (const gtrack::InputError& e) {
    EXPECT_EQ(std::string(e.what()).rfind((dir / "spike.csv").string() + ":4: a change of 150", 0), 0u) << e.what();
  }
  EXPECT_FALSE(fs::exists(o.out_dir / "estimates.csv"));
}

// A plugin is someone else's code. What it prints to stdout (a debugging
// line when made and at each reading) does not reach a controller reading
// --stream, whose stdout holds the estimates' lines only; what it throws
// that is not a std::exception is one line naming the plugin and the call,
// not an abort without a word.
TEST(Fault, APluginsPrintingAndOddThrowsStayOffTheControllersPipe) {
  const fs::path dir = fresh_dir("chatty_plugin");
  const auto config_with = [&](const std::string& wrong) {
    std::string config = kConfig;
    const size_t at = config.find("[stimulus]");
    const size_t end = config.find("\n[", at + 1);
    config.replace(at, end - at, "[stimulus]\nplugin = \"fixture_wrong_stimulus\"\nwrong = \"" + wrong + "\"");
    const fs::path file = dir / (wrong + ".toml");
    std::ofstream(file) << config;
    return file;
  };
  const fs::path frames = write_frames(dir / "frames", 3);
  std::ofstream(dir / "log.csv") << "frame,value\n0,20\n1,21\n2,22\n";
  const auto track = [&](const std::string& wrong) {
    return "track --plugin-path " + std::string(GTRACK_TEST_FIXTURE_DIR) + " --config " +
           config_with(wrong).string() + " --input " + frames.string() + " --stimulus " +
           (dir / "log.csv").string() + " --no-overlay --out " + (dir / wrong).string();
  };
  const CliRun streamed = gtrack_cli(track("prints") + " --stream", "2>" + (dir / "stderr.txt").string());
  ASSERT_EQ(streamed.code, 0) << read_text(dir / "stderr.txt");
  EXPECT_EQ(streamed.output, read_text(dir / "prints" / "estimates.jsonl"));
  EXPECT_EQ(std::count(streamed.output.begin(), streamed.output.end(), '\n'), 3) << streamed.output;
  // The plugin's lines went to stderr instead.
  EXPECT_NE(read_text(dir / "stderr.txt").find("wrong_stimulus: made"), std::string::npos);
  EXPECT_NE(read_text(dir / "stderr.txt").find("wrong_stimulus: reading 21"), std::string::npos);

  const CliRun odd = gtrack_cli(track("throws_other"));
  EXPECT_EQ(odd.code, 1) << odd.output;
  EXPECT_NE(odd.output.find("stimulus plugin 'fixture_wrong_stimulus' ("), std::string::npos) << odd.output;
  EXPECT_NE(odd.output.find("penalty() threw something that is not a std::exception"), std::string::npos)
      << odd.output;
  EXPECT_EQ(odd.output.find("terminate"), std::string::npos) << odd.output;
}

// A stimulus log shorter than the video: every frame is tracked, the frames
// past the log hold its last reading (and the tracker warns once).
TEST(Fault, StimulusLogEndingEarlyHoldsTheLastReading) {
  const fs::path dir = fresh_dir("short_stimulus");
  const fs::path csv = dir / "stimulus.csv";
  std::ofstream(csv) << "frame,value\n0,22.0\n1,23.0\n2,28.5\n";

  const TrackRun r = make_run();
  gtrack::TrackOptions o;
  o.input = write_frames(dir / "frames", kFrames).string();
  o.stimulus_csv = csv;
  o.out_dir = dir / "out";
  o.progress = false;
  std::vector<std::optional<double>> readings;
  o.on_frame = [&](const gtrack::Estimate& e) { readings.push_back(e.stimulus); };
  gtrack::TrackSummary s;
  const std::string log = gtrack::testing::logged([&] { s = gtrack::track_sequence(r.setup, r.config, o); });
  const std::string said = "stimulus.csv: frame 3 (t = 0.100 s) is outside the stimulus log, whose rows cover frames 0 to 2";
  EXPECT_NE(log.find(said), std::string::npos) << log;
  EXPECT_EQ(log.find("is outside the stimulus log"), log.rfind("is outside the stimulus log")) << log;
  EXPECT_EQ(s.frames, kFrames);
  EXPECT_EQ(valid_rows(o.out_dir / "estimates.csv").size(), static_cast<size_t>(kFrames));
  ASSERT_EQ(readings.size(), static_cast<size_t>(kFrames));
  for (int i = 3; i < kFrames; ++i) {
    ASSERT_TRUE(readings[i]) << "frame " << i;
    EXPECT_DOUBLE_EQ(*readings[i], 28.5) << "frame " << i;
  }
}

// A time_s log written with four decimals ends at the last frame's time
// rounded down (7 / 30 s as 0.2333): that frame is within the log, and no
// warning is given; a log that ends a frame earlier is warned about.
TEST(Fault, ATimeLogRoundedToFewDecimalsCoversItsLastFrame) {
  const fs::path dir = fresh_dir("rounded_stimulus");
  const TrackRun r = make_run();
  const auto warned = [&](const std::string& last_row) {
    const fs::path csv = dir / "stimulus.csv";
    std::ofstream(csv) << "time_s,value\n0.0000,22.0\n0.1000,22.5\n" << last_row << ",23.0\n";
    gtrack::TrackOptions o = folder_run(dir, kFrames);
    o.stimulus_csv = csv;
    const std::string log = gtrack::testing::logged([&] { gtrack::track_sequence(r.setup, r.config, o); });
    return log.find("is outside the stimulus log") != std::string::npos;
  };
  EXPECT_FALSE(warned("0.2333"));
  EXPECT_TRUE(warned("0.2000"));
}

// A live run follows a log that a temperature logger is still writing: each
// frame takes the latest whole row, and a row half written waits for its end.
TEST(Fault, FollowedStimulusLogGivesEachFrameTheLatestReading) {
  const fs::path dir = fresh_dir("follow_stimulus");
  const fs::path csv = dir / "stimulus.csv";
  std::ofstream(csv) << "time_s,value\n0.0,22.0\n";
  const TrackRun r = make_run();
  gtrack::TrackOptions o = folder_run(dir, kFrames);
  o.stimulus_csv = csv;
  o.follow_stimulus = true;
  std::vector<std::optional<double>> readings;
  o.on_frame = [&](const gtrack::Estimate& e) {
    readings.push_back(e.stimulus);
    // Each reading with the age of its row, which a run takes a frame at a time.
    EXPECT_TRUE(e.stimulus_age_s && *e.stimulus_age_s >= 0 && *e.stimulus_age_s < 60) << "frame " << e.frame;
    // After frame k the logger ends the row it had begun ("...5\n") and
    // begins the next one, 23.5 + k, half written ("0.1,23.").
    const int k = static_cast<int>(readings.size()) - 1;
    std::ofstream(csv, std::ios::app) << (k == 0 ? "" : "5\n") << 0.1 * (k + 1) << "," << 23 + k << ".";
  };
  const auto s = gtrack::track_sequence(r.setup, r.config, o);
  EXPECT_EQ(s.frames, kFrames);
  ASSERT_EQ(readings.size(), static_cast<size_t>(kFrames));
  ASSERT_TRUE(readings[0]);
  EXPECT_DOUBLE_EQ(*readings[0], 22.0);
  ASSERT_TRUE(readings[1]);
  EXPECT_DOUBLE_EQ(*readings[1], 22.0);  // "0.1,23." is not a whole row yet
  for (int i = 2; i < kFrames; ++i) {
    ASSERT_TRUE(readings[i]) << "frame " << i;
    EXPECT_DOUBLE_EQ(*readings[i], 23.5 + (i - 2)) << "frame " << i;
  }
  EXPECT_NE(read_text(o.out_dir / "estimates.jsonl").find("\"stimulus_age_s\":"), std::string::npos);
}

// A folder that acquisition software is still writing (--follow-input):
// images arrive while the run goes on, each first half written, with names
// whose numbers are not padded. Every one is tracked, once, in the order of
// its number, and the run ends on its own once no image has come for the
// idle time.
TEST(Fault, FollowedFolderTracksImagesAsTheyArriveAndEndsWhenTheyStop) {
  const fs::path dir = fresh_dir("follow_input");
  // Eleven images: img9 must come before img10, which plain name order would
  // put second.
  constexpr int kFollowed = 11;
  const fs::path staged = write_frames(dir / "staged", kFollowed), live = dir / "live";
  fs::create_directories(live);
  const TrackRun r = make_run();
  // Generous against a loaded machine (the writer pauses 120 ms per image):
  // the run then waits 3 s after the last one.
  gtrack::TrackOptions o = followed_run(live, dir, 3.0);
  // A jthread: joined even when track_sequence throws, so a failure fails
  // this test instead of ending the whole test program.
  std::jthread writer([&] {
    for (int i = 0; i < kFollowed; ++i) {
      char name[32];
      std::snprintf(name, sizeof name, "%06d.png", i);
      const std::string bytes = read_text(staged / name);
      const fs::path to = live / ("img" + std::to_string(i) + ".png");
      std::ofstream(to, std::ios::binary) << bytes.substr(0, bytes.size() / 2);
      std::this_thread::sleep_for(std::chrono::milliseconds(60));
      std::ofstream(to, std::ios::binary | std::ios::trunc) << bytes;
      std::this_thread::sleep_for(std::chrono::milliseconds(60));
    }
  });
  const auto s = gtrack::track_sequence(r.setup, r.config, o);
  writer.join();
  EXPECT_EQ(s.frames, kFollowed);
  std::vector<int> want(kFollowed);
  std::iota(want.begin(), want.end(), 0);
  EXPECT_EQ(valid_rows(o.out_dir / "estimates.csv"), want);
}

// Acquisition software that writes each image under one temporary name
// and renames it when done: the temporary file, listed and then gone, is
// no frame and stops nothing; every renamed image is tracked, in order.
TEST(Fault, AFollowedFolderWrittenUnderATemporaryNameTracksEveryImage) {
  const fs::path dir = fresh_dir("follow_rename");
  constexpr int kFollowed = 5;
  const fs::path staged = write_frames(dir / "staged", kFollowed), live = dir / "live";
  fs::create_directories(live);
  const TrackRun r = make_run();
  gtrack::TrackOptions o = followed_run(live, dir, 3.0);
  const fs::path temporary = live / "incoming.png";
  // The first image is half written when the run starts, so that the
  // listing sees its temporary name.
  const std::string first = read_text(staged / "000000.png");
  std::ofstream(temporary, std::ios::binary) << first.substr(0, first.size() / 2);
  std::jthread writer([&] {
    for (int i = 0; i < kFollowed; ++i) {
      char name[32];
      std::snprintf(name, sizeof name, "%06d.png", i);
      const std::string bytes = read_text(staged / name);
      if (i > 0) std::ofstream(temporary, std::ios::binary) << bytes.substr(0, bytes.size() / 2);
      std::this_thread::sleep_for(std::chrono::milliseconds(i == 0 ? 500 : 150));
      std::ofstream(temporary, std::ios::binary | std::ios::trunc) << bytes;
      fs::rename(temporary, live / name);
      std::this_thread::sleep_for(std::chrono::milliseconds(60));
    }
  });
  std::string said;
  gtrack::TrackSummary s;
  said = gtrack::testing::logged([&] { s = gtrack::track_sequence(r.setup, r.config, o); });
  writer.join();
  EXPECT_EQ(s.frames, kFollowed) << said;
  std::vector<int> want(kFollowed);
  std::iota(want.begin(), want.end(), 0);
  EXPECT_EQ(valid_rows(o.out_dir / "estimates.csv"), want);
  EXPECT_NE(said.find("incoming.png: gone before it could be read whole"), std::string::npos) << said;
}

// One of a followed folder's numbered images removed before it was read
// (a camera's ring buffer): its frame is left out, with a warning, and the
// frames after it keep their numbers. (The reader holds at most two frames
// ahead of the tracker: frame 4 is not read while frame 1 is tracked.)
TEST(Fault, ANumberedImageGoneBeforeItWasReadLeavesItsFrameOut) {
  const fs::path dir = fresh_dir("follow_vanished");
  const TrackRun r = make_run();
  const fs::path live = write_frames(dir / "live", 7);
  gtrack::TrackOptions o = followed_run(live, dir, 0.5);
  o.on_frame = [&](const gtrack::Estimate& e) {
    if (e.frame == 1) fs::remove(live / "000004.png");
  };
  gtrack::TrackSummary s;
  const std::string said = gtrack::testing::logged([&] { s = gtrack::track_sequence(r.setup, r.config, o); });
  EXPECT_EQ(valid_rows(o.out_dir / "estimates.csv"), (std::vector<int>{0, 1, 2, 3, 5, 6}));
  EXPECT_NE(said.find("000004.png: gone before it could be read (removed or moved away); frame 4 is left out"),
            std::string::npos)
      << said;
}

// Following a folder with --frames A:B: once frame B - 1 is taken there is
// nothing left to wait for, and the run ends then, not --follow-input's
// seconds later.
TEST(Fault, AFollowedFolderEndsWithTheLastFrameOfTheRange) {
  const fs::path dir = fresh_dir("follow_range");
  const TrackRun r = make_run();
  gtrack::TrackOptions o = followed_run(write_frames(dir / "live", 6), dir, 120.0);
  o.range = gtrack::parse_frame_range("0:6");
  const auto start = std::chrono::steady_clock::now();
  const auto s = gtrack::track_sequence(r.setup, r.config, o);
  EXPECT_EQ(s.frames, 6);
  EXPECT_FALSE(s.cancelled);
  // Far below the 120 s it would otherwise wait, however loaded the machine.
  EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(), 60.0);
}

// A live source faster than the tracker (here a followed folder that holds
// twelve images at once, and a tracker slowed to 50 ms a frame): with
// --newest each frame tracked is the newest listed, the frames between are
// left out and counted, and the last image is tracked; without it every
// frame is, in order. A recording is refused.
TEST(Fault, NewestTracksTheLatestFrameOfALiveSourceAndCountsTheRest) {
  constexpr int kImages = 12;
  const TrackRun r = make_run();
  for (const bool newest : {true, false}) {
    SCOPED_TRACE(newest ? "--newest" : "every frame");
    const fs::path dir = fresh_dir(newest ? "newest" : "newest_off");
    gtrack::TrackOptions o = followed_run(write_frames(dir / "live", kImages), dir, 0.5);
    o.newest = newest;
    o.on_frame = [](const gtrack::Estimate&) { std::this_thread::sleep_for(std::chrono::milliseconds(50)); };
    const auto s = gtrack::track_sequence(r.setup, r.config, o);
    const std::vector<int> rows = valid_rows(o.out_dir / "estimates.csv");
    ASSERT_FALSE(rows.empty());
    EXPECT_EQ(rows.back(), kImages - 1);
    EXPECT_EQ(s.frames + s.skipped_frames, kImages);
    EXPECT_EQ(static_cast<int>(rows.size()), s.frames);
    if (newest) {
      // The folder held them all when the run began: the newest is the
      // first frame, the others are left out without being read.
      EXPECT_EQ(s.frames, 1);
    } else {
      EXPECT_EQ(s.skipped_frames, 0);
    }
    EXPECT_NE(read_text(o.out_dir / "summary.json").find("\"skipped_frames\": " + std::to_string(s.skipped_frames)),
              std::string::npos);
  }
  gtrack::TrackOptions recording = folder_run(fresh_dir("newest_recording"), 3);
  recording.newest = true;
  expect_refusal_naming(track_error(r, recording), "--newest is for a live source");
}

// A followed folder as a camera's software writes JPEGs: one written in two
// steps, with a pause well over a poll, is tracked once whole (a half JPEG
// decodes, with a complaint); one that arrives after a later-named image
// was tracked is said, by name, not tracked.
TEST(Fault, FollowedFolderWaitsOutAHalfWrittenJpegAndNamesALateImage) {
  const fs::path dir = fresh_dir("follow_jpeg");
  const fs::path whole = dir / "whole", live = dir / "live";
  fs::create_directories(whole);
  fs::create_directories(live);
  std::vector<std::string> jpeg(4);
  const auto name = [](int i) { return "img" + std::to_string(i) + ".jpg"; };
  for (int i = 0; i < 4; ++i) {
    std::vector<uchar> bytes;
    ASSERT_TRUE(cv::imencode(".jpg", frame_image(i), bytes));
    jpeg[i].assign(bytes.begin(), bytes.end());
    std::ofstream(whole / name(i), std::ios::binary) << jpeg[i];
  }
  const TrackRun r = make_run();
  gtrack::TrackOptions ref;
  ref.input = whole.string();
  ref.out_dir = dir / "ref";
  ref.progress = false;
  gtrack::track_sequence(r.setup, r.config, ref);

  const gtrack::TrackOptions o = followed_run(live, dir, 3.0);
  std::ostringstream log;
  gtrack::logger().sinks().push_back(std::make_shared<spdlog::sinks::ostream_sink_mt>(log));
  std::jthread writer([&] {
    std::ofstream(live / name(0), std::ios::binary) << jpeg[0];
    {
      std::ofstream half(live / name(1), std::ios::binary);
      half << jpeg[1].substr(0, jpeg[1].size() / 2) << std::flush;
      std::this_thread::sleep_for(std::chrono::milliseconds(400));
      half << jpeg[1].substr(jpeg[1].size() / 2);
    }
    std::ofstream(live / name(3), std::ios::binary) << jpeg[3];
    // img2 once img3's row is written (header and three rows).
    for (int i = 0; i < 3000 && read_lines(o.out_dir / "estimates.csv").size() < 4; ++i) {
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    std::ofstream(live / name(2), std::ios::binary) << jpeg[2];
  });
  const auto s = gtrack::track_sequence(r.setup, r.config, o);
  writer.join();
  gtrack::logger().sinks().pop_back();
  EXPECT_EQ(s.frames, 3);
  const auto rows = read_lines(o.out_dir / "estimates.csv"), ref_rows = read_lines(ref.out_dir / "estimates.csv");
  ASSERT_EQ(rows.size(), 4u);
  ASSERT_EQ(ref_rows.size(), 5u);
  // Frames 0 and 1 as from the whole images (all but the time column).
  for (int i : {1, 2}) EXPECT_EQ(rows[i].substr(0, rows[i].rfind(',')), ref_rows[i].substr(0, ref_rows[i].rfind(',')));
  EXPECT_NE(log.str().find(name(2) + ": arrived after img3.jpg, which comes after it in name order"),
            std::string::npos)
      << log.str();
}

// Ctrl-C while a followed folder is waited on, for a new image or for one
// still being written (here never finished), ends the run as cancelled:
// not as a run that ran out of images, nor as an unreadable image.
TEST(Fault, ACancelWhileFollowingEndsTheRunAsCancelled) {
  for (const bool half : {false, true}) {
    SCOPED_TRACE(half ? "an image half written" : "waiting for an image");
    const fs::path dir = fresh_dir(half ? "follow_cancel_half" : "follow_cancel_wait");
    const fs::path staged = write_frames(dir / "staged", 2), live = dir / "live";
    fs::create_directories(live);
    fs::copy_file(staged / "000000.png", live / "000000.png");
    if (half) {
      const std::string bytes = read_text(staged / "000001.png");
      std::ofstream(live / "000001.png", std::ios::binary) << bytes.substr(0, bytes.size() / 2);
    }
    const TrackRun r = make_run();
    gtrack::TrackOptions o = followed_run(live, dir, 60.0);
    std::atomic<bool> cancel{false};
    o.cancel = &cancel;
    std::jthread stopper([&] {
      for (int i = 0; i < 3000 && read_lines(o.out_dir / "estimates.csv").size() < 2; ++i) {
        std::this_thread::sleep_for(std::chrono::milliseconds(20));
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(300));
      cancel = true;
    });
    const auto s = gtrack::track_sequence(r.setup, r.config, o);
    EXPECT_TRUE(s.cancelled);
    EXPECT_EQ(s.frames, 1);
  }
}

// A fresh run into an earlier run's folder: the files of that run the new
// one might not rewrite go first, so a new run that fails part way never
// leaves the old summary or overlay beside its own rows. Other files stay.
TEST(Fault, AFreshRunClearsWhatAnEarlierRunLeft) {
  const fs::path dir = fresh_dir("earlier_run");
  for (const char* f : {"overlay.mp4", "overlay_from_000010.avi", "summary.json", "tracker_state.txt", "notes.txt"}) {
    std::ofstream(dir / f) << "x";
  }
  fs::create_directories(dir / "masks");
  std::ofstream(dir / "masks" / "000003.png") << "x";
  std::ofstream(dir / "masks" / "readme.txt") << "x";
  EXPECT_EQ(gtrack::clear_previous_run(dir), 5);
  std::vector<std::string> left;
  for (const auto& e : fs::recursive_directory_iterator(dir)) {
    if (e.is_regular_file()) left.push_back(fs::relative(e.path(), dir).string());
  }
  std::sort(left.begin(), left.end());
  EXPECT_EQ(left, (std::vector<std::string>{"masks/readme.txt", "notes.txt"}));
}

TEST(Fault, OnlyAFolderCanBeFollowed) {
  const fs::path dir = fresh_dir("follow_video");
  const TrackRun r = make_run();
  gtrack::TrackOptions o = folder_run(dir, 2);
  o.input = (dir / "frames" / "000000.png").string();
  o.follow_input_s = 1.0;
  expect_refusal_naming(track_error(r, o), "only a folder of images can be followed");
}

// A stimulus log cut in the middle of a row (the logger died while writing):
// refused before anything is written, with file and line.
TEST(Fault, StimulusLogCutMidRowIsRefusedWithFileAndLine) {
  const fs::path dir = fresh_dir("cut_stimulus");
  const fs::path csv = dir / "stimulus.csv";
  std::ofstream(csv) << "frame,value\n0,22.0\n1,23.0\n2,";

  const TrackRun r = make_run();
  gtrack::TrackOptions o;
  o.input = write_frames(dir / "frames", 2).string();
  o.stimulus_csv = csv;
  o.out_dir = dir / "out";
  o.progress = false;
  expect_refusal_naming(track_error(r, o), "stimulus.csv:4:");
  EXPECT_FALSE(fs::exists(o.out_dir / "estimates.csv"));
}

// An output folder that cannot exist (a path under a regular file, or under
// /dev/full): refused up front, one line, nothing tracked. Root-proof,
// unlike a chmod'ed folder.
TEST(Fault, UnwritableOutputFolderIsRefusedUpFront) {
  const fs::path dir = fresh_dir("unwritable");
  std::ofstream(dir / "a_file") << "x";
  const TrackRun r = make_run();
  for (const fs::path out : {dir / "a_file" / "out", fs::path("/dev/full/out")}) {
    gtrack::TrackOptions o;
    o.input = write_frames(dir / "frames", 2).string();
    o.out_dir = out;
    o.progress = false;
    int frames_run = 0;
    o.on_frame = [&](const gtrack::Estimate&) { ++frames_run; };
    expect_refusal_naming(track_error(r, o), out.string());
    EXPECT_EQ(frames_run, 0);
  }
}

// The disk fills up mid-run (estimates.jsonl on /dev/full: every write fails
// with ENOSPC): the run stops at the first frame it cannot write, with one
// line; estimates.csv keeps the header and the rows written before.
TEST(Fault, DiskFullMidRunStopsWithOneLine) {
  const fs::path dir = fresh_dir("disk_full");
  const fs::path out = dir / "out";
  fs::create_directories(out);
  fs::create_symlink("/dev/full", out / "estimates.jsonl");

  const TrackRun r = make_run();
  gtrack::TrackOptions o;
  o.input = write_frames(dir / "frames", kFrames).string();
  o.out_dir = out;
  o.progress = false;
  expect_refusal_naming(track_error(r, o), "writing the estimates failed (No space left on device)");
  // The CSV row of the frame whose JSON line failed is already flushed.
  EXPECT_LE(valid_rows(out / "estimates.csv").size(), 1u);
}

// A disk that fills part way also refuses the summary written when the run
// stops: the error still says how many frames are kept and that --resume
// goes on (summary.json made unwritable here by a folder in its place).
TEST(Fault, AStopWhoseSummaryCannotBeWrittenStillSaysWhatIsKept) {
  const fs::path dir = fresh_dir("no_summary");
  const TrackRun r = make_run();
  gtrack::TrackOptions o = folder_run(dir, kFrames);
  int frames_run = 0;
  o.on_frame = [&](const gtrack::Estimate&) {
    if (++frames_run == 2) fs::create_directories(o.out_dir / "summary.json" / "x");
    if (frames_run == 3) throw gtrack::InputError("estimates.jsonl: write failed (No space left on device)");
  };
  const std::string error = track_error(r, o);
  expect_refusal_naming(error, "write failed (No space left on device); the 2 frames before it are kept in " +
                                   o.out_dir.string() + " (--resume goes on");
}

// The output folder is deleted while the run goes on (a user cleaning up):
// the run stops at the next frame, failing to save its tracker state there,
// in one line; nothing crashes and no more frames are tracked for nothing.
TEST(Fault, OutputFolderRemovedMidRunStopsAtTheNextFrame) {
  const fs::path dir = fresh_dir("removed_out");
  const TrackRun r = make_run();
  gtrack::TrackOptions o = folder_run(dir, kFrames);
  int frames_run = 0;
  o.on_frame = [&](const gtrack::Estimate&) {
    if (++frames_run == 3) fs::remove_all(o.out_dir);
  };
  expect_refusal_naming(track_error(r, o), "tracker_state.txt");
  EXPECT_EQ(frames_run, 3);
}

// A folder's images are numbered by their place in name order: with the
// first images moved away (done with, as acquisition scripts do), the ones
// left would be tracked under other numbers. Resuming is refused, naming
// the last frame done and both images; with the folder as it was, it goes on.
TEST(Fault, ResumeRefusesAFolderWhoseImagesMovedUnderTheFramesDone) {
  const fs::path dir = fresh_dir("resume_moved");
  const TrackRun r = make_run();
  gtrack::TrackOptions o = folder_run(dir, kFrames);
  std::atomic<bool> cancel{false};
  o.cancel = &cancel;
  int done = 0;
  o.on_frame = [&](const gtrack::Estimate&) {
    if (++done == 4) cancel = true;
  };
  ASSERT_TRUE(gtrack::track_sequence(r.setup, r.config, o).cancelled);
  const fs::path moved = dir / "moved";
  fs::create_directories(moved);
  for (const char* name : {"000000.png", "000001.png"}) fs::rename(fs::path(o.input) / name, moved / name);
  gtrack::TrackOptions again = o;
  again.resume = true;
  again.on_frame = nullptr;
  again.cancel = nullptr;
  const std::string e = track_error(r, again);
  expect_refusal_naming(e, "frame 3 was \"" + (fs::path(o.input) / "000003.png").string() + "\"");
  EXPECT_NE(e.find("is now \"" + (fs::path(o.input) / "000005.png").string() + "\""), std::string::npos) << e;
  EXPECT_EQ(valid_rows(o.out_dir / "estimates.csv"), (std::vector<int>{0, 1, 2, 3}));
  for (const char* name : {"000000.png", "000001.png"}) fs::rename(moved / name, fs::path(o.input) / name);
  again.input = (fs::path(o.input) / ".").string();  // the same folder, named otherwise
  EXPECT_EQ(track_error(r, again), "");
  EXPECT_EQ(valid_rows(o.out_dir / "estimates.csv").size(), static_cast<size_t>(kFrames));
}

// estimates.csv without the ms column (the one field that is not
// reproducible): the rows a resumed run must reproduce exactly.
std::vector<std::string> rows_without_time(const fs::path& csv) {
  std::vector<std::string> out;
  for (const auto& l : read_lines(csv)) out.push_back(l.substr(0, l.rfind(',')));
  return out;
}

// Tracks the run `o` describes into `out` (o.out_dir is set to it) and
// returns its rows without the time column, the reference a variant of the
// run is compared with.
std::vector<std::string> tracked_rows(const TrackRun& r, gtrack::TrackOptions& o, const fs::path& out) {
  o.out_dir = out;
  gtrack::track_sequence(r.setup, r.config, o);
  return rows_without_time(out / "estimates.csv");
}

// A run interrupted (Ctrl-C) after 3 of 8 frames and resumed gives the same
// rows as a run that was never interrupted: the tracker's state, the
// stimulus plugin's (replayed from the log) and the per-frame random draws
// are all restored. The frame range and stride are kept. The frames are a
// short `gtrack synth` sequence tracked with the default swarm: with a tiny
// swarm on a poor fit the coarse search decides every frame, and the
// stimulus's share of folding particles would not show.
TEST(Fault, ResumedRunMatchesAnUninterruptedOne) {
  const fs::path dir = fresh_dir("resume");
  const CliRun synth = gtrack_cli("synth --frames 16 --seed 3 --out " + (dir / "seq").string());
  ASSERT_EQ(synth.code, 0) << synth.output;
  const fs::path csv = dir / "stimulus.csv";
  // Heated past folding before the interruption, then held inside the
  // hysteresis band, where only the history says which way it goes.
  std::ofstream(csv) << "frame,value\n1,22.0\n3,29.0\n5,29.0\n7,25.5\n9,25.5\n11,25.5\n13,25.5\n15,25.5\n";
  const auto options = [&](const fs::path& out) {
    gtrack::TrackOptions o;
    o.input = (dir / "seq" / "frames").string();
    o.stimulus_csv = csv;
    o.out_dir = out;
    o.range.first = 1;
    o.range.every = 2;
    o.overlay = false;
    o.progress = false;
    return o;
  };
  // Each run loads its own setup, as each `gtrack track` process does (the
  // stimulus plugin keeps its state).
  const std::string config = read_text(dir / "seq" / "sequence.toml") + "[render]\nbackend = \"cpu\"\n";
  const auto load = [&] {
    TrackRun r{gtrack::load_setup(gtrack::ConfigTable::parse(config, "sequence.toml"), {}), {}};
    r.config = gtrack::engine_config(r.setup);
    return r;
  };
  {
    const TrackRun whole = load();
    gtrack::track_sequence(whole.setup, whole.config, options(dir / "whole"));
  }
  const auto reference = rows_without_time(dir / "whole" / "estimates.csv");
  ASSERT_EQ(reference.size(), static_cast<size_t>(kFrames + 1));

  std::atomic<bool> stop{false};
  gtrack::TrackOptions first = options(dir / "out");
  first.cancel = &stop;
  int n = 0;
  first.on_frame = [&](const gtrack::Estimate&) { stop = ++n == 3; };
  TrackRun r = load();
  const auto s1 = gtrack::track_sequence(r.setup, r.config, first);
  EXPECT_TRUE(s1.cancelled);
  EXPECT_EQ(s1.frames, 3);

  gtrack::TrackOptions second = options(dir / "out");
  second.resume = true;
  std::vector<int> tracked;
  second.on_frame = [&](const gtrack::Estimate& e) { tracked.push_back(e.frame); };
  r = load();
  const auto s2 = gtrack::track_sequence(r.setup, r.config, second);
  EXPECT_EQ(s2.frames, kFrames - 3);
  EXPECT_EQ(s2.resumed_after, 5);
  EXPECT_EQ(s2.frames_before, 3);
  ASSERT_FALSE(tracked.empty());
  EXPECT_EQ(tracked.front(), 7);  // frames 1, 3, 5 were done
  EXPECT_EQ(rows_without_time(dir / "out" / "estimates.csv"), reference);
  EXPECT_EQ(read_lines(dir / "out" / "estimates.jsonl").size(), static_cast<size_t>(kFrames));

  // Resuming a finished run tracks nothing and keeps every row.
  second.on_frame = nullptr;
  r = load();
  EXPECT_EQ(gtrack::track_sequence(r.setup, r.config, second).frames, 0);
  EXPECT_EQ(rows_without_time(dir / "out" / "estimates.csv"), reference);

  // An overlay the killed run never closed (an mp4 with no index) is said
  // to be unreadable when the run is resumed.
  std::ofstream(dir / "out" / "overlay.mp4") << std::string(48, '\0');
  second.overlay = true;
  r = load();
  const std::string log = gtrack::testing::logged([&] { gtrack::track_sequence(r.setup, r.config, second); });
  EXPECT_NE(log.find("overlay.mp4: cannot be read (not closed by the run that wrote it"), std::string::npos) << log;
  // After several kills, one line says how many, not one line each.
  for (const char* name : {"overlay_from_000004.mp4", "overlay_from_000007.mp4"}) {
    std::ofstream(dir / "out" / name) << std::string(48, '\0');
  }
  r = load();
  const std::string many = gtrack::testing::logged([&] { gtrack::track_sequence(r.setup, r.config, second); });
  EXPECT_NE(many.find("3 overlays of earlier runs cannot be read ("), std::string::npos) << many;
  EXPECT_EQ(many.find("cannot be read (not closed by the run that wrote it"), std::string::npos) << many;
}

// --two-pass --resume: a two-pass run interrupted in its forward run is
// resumed, its earlier frames read back from estimates.jsonl for the
// backward pass, and gives the two-pass table of a run never interrupted.
// The read-back rows are the estimates as written, their times and
// readings exactly as the run had them.
TEST(Fault, ResumedTwoPassRunMakesTheTableOfAnUninterruptedOne) {
  const fs::path dir = fresh_dir("resume_two_pass");
  const CliRun synth = gtrack_cli("synth --frames 12 --seed 3 --out " + (dir / "seq").string());
  ASSERT_EQ(synth.code, 0) << synth.output;
  const std::string config = read_text(dir / "seq" / "sequence.toml") + "[render]\nbackend = \"cpu\"\n";
  const auto load = [&] {
    TrackRun r{gtrack::load_setup(gtrack::ConfigTable::parse(config, "sequence.toml"), {}), {}};
    r.config = gtrack::engine_config(r.setup);
    return r;
  };
  const auto options = [&](const fs::path& out) {
    gtrack::TrackOptions o;
    o.input = (dir / "seq" / "frames").string();
    o.stimulus_csv = dir / "seq" / "stimulus.csv";
    o.out_dir = out;
    o.overlay = false;
    o.progress = false;
    o.feed_untracked_readings = false;  // as gtrack track --two-pass sets it
    return o;
  };
  std::vector<gtrack::Estimate> forward;
  {
    TrackRun r = load();
    gtrack::TrackOptions o = options(dir / "whole");
    o.on_frame = [&](const gtrack::Estimate& e) { forward.push_back(e); };
    gtrack::track_sequence(r.setup, r.config, o);
    gtrack::two_pass(r.setup, r.config, o, forward);
  }
  ASSERT_EQ(forward.size(), 12u);
  // What is read back is what was made, at the files' precision.
  const auto read_back = gtrack::read_estimates(dir / "whole", 6);
  ASSERT_EQ(read_back.size(), forward.size());
  for (size_t i = 0; i < forward.size(); ++i) {
    EXPECT_EQ(read_back[i].frame, forward[i].frame);
    // The run's inputs exactly (a reading or a time rounded would be fed
    // to the stimulus again otherwise, and the tracks part ways).
    EXPECT_EQ(read_back[i].time_s, forward[i].time_s) << i;
    EXPECT_EQ(gtrack::pose_text(read_back[i].hypothesis), gtrack::pose_text(forward[i].hypothesis)) << i;
    EXPECT_EQ(read_back[i].status, forward[i].status) << i;
    ASSERT_TRUE(read_back[i].stimulus.has_value());
    EXPECT_EQ(*read_back[i].stimulus, *forward[i].stimulus) << i;
  }

  std::atomic<bool> stop{false};
  gtrack::TrackOptions first = options(dir / "out");
  first.cancel = &stop;
  int n = 0;
  first.on_frame = [&](const gtrack::Estimate&) { stop = ++n == 5; };
  TrackRun r = load();
  EXPECT_TRUE(gtrack::track_sequence(r.setup, r.config, first).cancelled);
  gtrack::TrackOptions second = options(dir / "out");
  second.resume = true;
  r = load();
  EXPECT_EQ(gtrack::track_sequence(r.setup, r.config, second).frames, 7);
  const auto parts = gtrack::read_estimates(dir / "out", 6);
  ASSERT_EQ(parts.size(), 12u);
  const std::string log = gtrack::testing::logged([&] { gtrack::two_pass(r.setup, r.config, second, parts); });
  EXPECT_EQ(log.find("gave other estimates"), std::string::npos) << log;
  EXPECT_EQ(rows_without_time(dir / "out" / "two_pass" / "estimates.csv"),
            rows_without_time(dir / "whole" / "two_pass" / "estimates.csv"));
  EXPECT_EQ(rows_without_time(dir / "out" / "backward" / "estimates.csv"),
            rows_without_time(dir / "whole" / "backward" / "estimates.csv"));
  // A row that is not gtrack's is one line naming the file and line.
  std::ofstream(dir / "out" / "estimates.jsonl", std::ios::app) << "{\"frame\":12,\"time_s\":0.4}\n";
  try {
    gtrack::read_estimates(dir / "out", 6);
    ADD_FAILURE() << "a row without its configuration was read";
  } catch (const gtrack::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("estimates.jsonl:13: no 'x_mm'"), std::string::npos) << e.what();
  }
}

// --frames A:B starts at A with what the log said before it: a gripper
// heated past folding before frame A and then held inside the hysteresis
// band is still folded there, by the readings of the frames not tracked.
// Without them the run is the same as one whose log never went above the
// band.
TEST(Fault, ARunFromFrameATakesTheLogsReadingsBeforeIt) {
  const fs::path dir = fresh_dir("frames_from");
  const CliRun synth = gtrack_cli("synth --frames 8 --seed 3 --out " + (dir / "seq").string());
  ASSERT_EQ(synth.code, 0) << synth.output;
  const fs::path heated = dir / "heated.csv", cool = dir / "cool.csv";
  std::ofstream(heated) << "frame,value\n0,22.0\n1,29.0\n2,29.0\n3,25.5\n5,25.5\n7,25.5\n";
  std::ofstream(cool) << "frame,value\n0,22.0\n1,22.0\n2,22.0\n3,25.5\n5,25.5\n7,25.5\n";
  const std::string config = read_text(dir / "seq" / "sequence.toml") + "[render]\nbackend = \"cpu\"\n";
  const auto run = [&](const fs::path& log, const std::string& out) {
    TrackRun r{gtrack::load_setup(gtrack::ConfigTable::parse(config, "sequence.toml"), {}), {}};
    r.config = gtrack::engine_config(r.setup);
    gtrack::TrackOptions o;
    o.input = (dir / "seq" / "frames").string();
    o.stimulus_csv = log;
    o.range.first = 5;
    o.overlay = false;
    o.progress = false;
    return tracked_rows(r, o, dir / out);
  };
  const auto after_heating = run(heated, "heated"), without = run(cool, "cool");
  ASSERT_EQ(after_heating.size(), 4u);  // the header and frames 5, 6, 7
  EXPECT_NE(after_heating, without);
}

// Killed while writing (power cut, kill -9): a row cut short, or written
// after the last saved state, is dropped and tracked again.
TEST(Fault, ResumeDropsRowsPastTheSavedState) {
  const fs::path dir = fresh_dir("resume_cut");
  const TrackRun r = make_run();
  gtrack::TrackOptions o = folder_run(dir, kFrames);
  const auto reference = tracked_rows(r, o, dir / "whole");

  o.out_dir = dir / "out";
  o.range.last = 4;
  gtrack::track_sequence(r.setup, r.config, o);
  // Frame 4's row made it, its state did not; frame 5's row is half written.
  const auto whole = read_lines(dir / "whole" / "estimates.csv");
  const auto whole_json = read_lines(dir / "whole" / "estimates.jsonl");
  std::ofstream(o.out_dir / "estimates.csv", std::ios::app) << whole[5] << "\n" << whole[6].substr(0, 9);
  std::ofstream(o.out_dir / "estimates.jsonl", std::ios::app) << whole_json[4] << "\n" << whole_json[5].substr(0, 12);

  o.range.last = -1;
  o.resume = true;
  EXPECT_EQ(gtrack::track_sequence(r.setup, r.config, o).frames, kFrames - 4);
  EXPECT_EQ(valid_rows(o.out_dir / "estimates.csv").size(), static_cast<size_t>(kFrames));
  EXPECT_EQ(rows_without_time(o.out_dir / "estimates.csv"), reference);
  EXPECT_EQ(read_lines(o.out_dir / "estimates.jsonl").size(), static_cast<size_t>(kFrames));
}

// run_config.toml keeps the fingerprints of the stimulus log and of the
// plugins' libraries beside the config's files: a log mended in place
// between the interrupted run and its resumption is refused, as a changed
// config file is (two runs' readings had been mixed in one table).
TEST(Fault, ResumeRefusesAStimulusLogChangedSinceTheRunBegan) {
  const fs::path dir = fresh_dir("resume_log");
  const TrackRun r = make_run();
  gtrack::TrackOptions o = folder_run(dir, 4);
  std::ofstream(dir / "stimulus.csv") << "frame,value\n0,22\n3,25\n";
  o.stimulus_csv = dir / "stimulus.csv";
  o.range.last = 1;
  gtrack::track_sequence(r.setup, r.config, o);
  const auto kept = read_lines(o.out_dir / "run_config.toml");
  const auto listed = [&](const std::string& start) {
    return std::any_of(kept.begin(), kept.end(), [&](const std::string& l) { return l.rfind(start, 0) == 0; });
  };
  EXPECT_TRUE(listed("# gtrack track: file --stimulus = "));
  EXPECT_TRUE(listed("# gtrack track: file stimulus plugin temperature_hysteresis = "));
  EXPECT_TRUE(listed("# gtrack track: file gripper plugin hydrogel_six_finger = "));

  std::ofstream(dir / "stimulus.csv") << "frame,value\n0,22\n3,35\n";
  o.range.last = -1;
  o.resume = true;
  expect_refusal_naming(track_error(r, o),
                        "stimulus.csv: has changed since the run being resumed began (--stimulus: it was 22 bytes");
  std::ofstream(dir / "stimulus.csv") << "frame,value\n0,22\n3,25\n";  // put back: it goes on
  EXPECT_EQ(gtrack::track_sequence(r.setup, r.config, o).frames, 3);  // frames 1 to 3
}

// A stimulus log that has only grown since the run began (a logger still
// writing): the resumed run reads the bytes the run read, so its frames
// take the readings of a run never interrupted, and says so. Grown and
// changed before its end, it is refused as any changed log.
TEST(Fault, ResumeReadsAGrownStimulusLogAsTheRunHadIt) {
  const fs::path dir = fresh_dir("resume_grown_log");
  const TrackRun r = make_run();
  gtrack::TrackOptions o = folder_run(dir, 4);
  const fs::path csv = dir / "stimulus.csv";
  const std::string original = "frame,value\n0,22\n1,23\n";
  std::ofstream(csv) << original;
  o.stimulus_csv = csv;
  gtrack::TrackOptions whole = o;
  whole.out_dir = dir / "whole";
  gtrack::track_sequence(r.setup, r.config, whole);
  o.range.last = 2;  // frames 0 and 1, then stopped
  gtrack::track_sequence(r.setup, r.config, o);

  std::ofstream(csv, std::ios::app) << "2,24\n3,25\n";
  o.range.last = -1;
  o.resume = true;
  gtrack::TrackSummary resumed;
  const std::string said = gtrack::testing::logged([&] { resumed = gtrack::track_sequence(r.setup, r.config, o); });
  EXPECT_EQ(resumed.frames, 2);
  EXPECT_NE(said.find("stimulus.csv: has grown from 22 to 32 bytes since the run being resumed began; only its "
                      "first 22, unchanged, are read"),
            std::string::npos)
      << said;
  EXPECT_EQ(rows_without_time(o.out_dir / "estimates.csv"), rows_without_time(whole.out_dir / "estimates.csv"));
  const auto rows = read_lines(o.out_dir / "estimates.jsonl");
  ASSERT_EQ(rows.size(), 4u);
  EXPECT_NE(rows[3].find("\"stimulus\":23"), std::string::npos) << rows[3];  // held past the run's log, not 25

  // Grown, and changed within the bytes the run read: refused.
  gtrack::TrackOptions again = o;
  again.out_dir = dir / "again";
  again.resume = false;
  again.range.last = 2;
  std::ofstream(csv) << original;
  gtrack::track_sequence(r.setup, r.config, again);
  std::ofstream(csv) << "frame,value\n0,22\n1,24\n2,24\n";
  again.range.last = -1;
  again.resume = true;
  expect_refusal_naming(track_error(r, again),
                        "stimulus.csv: has changed since the run being resumed began (--stimulus: it was 22 bytes");
}

// --durable syncs each frame's rows and the state to the disk: the same
// rows as without, the state at the last frame, no temporary file left.
// (What it guards against, a power loss, cannot be made here; the fsync
// calls were counted with strace: four a frame, docs/reliability.md.)
TEST(Fault, DurableRunWritesTheSameRowsAndState) {
  const fs::path dir = fresh_dir("durable");
  const TrackRun r = make_run();
  gtrack::TrackOptions o = folder_run(dir, kFrames);
  const auto plain = tracked_rows(r, o, dir / "plain");
  o.durable = true;
  const auto durable = tracked_rows(r, o, dir / "durable");
  EXPECT_EQ(durable.size(), static_cast<size_t>(kFrames + 1));
  EXPECT_EQ(durable, plain);
  EXPECT_EQ(read_lines(dir / "durable" / "estimates.jsonl").size(), static_cast<size_t>(kFrames));
  EXPECT_EQ(gtrack::read_tracker_state(dir / "durable" / "tracker_state.txt").frame, kFrames - 1);
  EXPECT_FALSE(fs::exists(dir / "durable" / "tracker_state.txt.tmp"));
}

// A run of frames 0-2 of kFrames, stopped there, to be resumed.
struct StoppedRun {
  TrackRun run;
  gtrack::TrackOptions options;
};
StoppedRun stopped_run(const std::string& name) {
  StoppedRun s{make_run(), folder_run(fresh_dir(name), kFrames)};
  s.options.range.last = 3;
  gtrack::track_sequence(s.run.setup, s.run.config, s.options);
  return s;
}

// A damaged state file, or rows that stop before the state's frame: one
// line naming the file, and the files are left as they were.
TEST(Fault, ResumeRefusesADamagedStateWithFileAndLine) {
  const auto [r, o] = stopped_run("resume_bad");
  const fs::path state = o.out_dir / "tracker_state.txt";
  std::string text = read_text(state);
  const auto expect_refusal = [&](const std::string& what) {
    gtrack::TrackOptions again = o;
    again.range.last = -1;
    again.resume = true;
    expect_refusal_naming(track_error(r, again), what);
    EXPECT_EQ(valid_rows(o.out_dir / "estimates.csv").size(), 3u);
  };
  // The state with its line that starts with `key` replaced (or dropped).
  const auto with_line = [&](const std::string& key, const std::string& line) {
    const size_t at = text.find("\n" + key) + 1, end = text.find('\n', at) + 1;
    return text.substr(0, at) + line + text.substr(end);
  };
  std::ofstream(state) << with_line("last ", "last 1 2 nan\n");
  expect_refusal("tracker_state.txt:6: 'nan' is not a finite number");
  std::ofstream(state) << with_line("last ", "last 1 2 3\n");
  expect_refusal("holds a configuration of 3 values, this setup has 12; cannot resume");
  std::ofstream(state) << with_line("lost ", "");
  expect_refusal("missing the 'lost' line of a tracker state");
  std::ofstream(state) << "frame 2\n";
  expect_refusal("tracker_state.txt:1: expected 'gtrack-tracker-state 1'");
  std::ofstream(state) << with_line("frame ", "frame 6\n");
  expect_refusal("its rows end at frame 2, the tracker state at frame 6");
  std::ofstream(state) << text;
  fs::remove(state);
  fs::create_directory(state);
  expect_refusal("tracker_state.txt: is a folder; expected a tracker state file");
  fs::remove(state);
  std::ofstream(state) << text;
}

// The two estimate files must hold the same rows up to the state's frame:
// one cut short, or a row that is no row, is refused by file and line, and
// neither file is changed.
TEST(Fault, ResumeRefusesEstimateFilesThatDisagree) {
  const auto [r, o] = stopped_run("resume_rows");
  const fs::path csv = o.out_dir / "estimates.csv", jsonl = o.out_dir / "estimates.jsonl";
  const std::string csv_text = read_text(csv), jsonl_text = read_text(jsonl);
  gtrack::TrackOptions again = o;
  again.range.last = -1;
  again.resume = true;
  // The JSONL cut after its first row.
  std::ofstream(jsonl) << jsonl_text.substr(0, jsonl_text.find('\n') + 1);
  expect_refusal_naming(track_error(r, again), "estimates.jsonl: its rows end at frame 0, the tracker state at frame 2");
  EXPECT_EQ(read_text(csv), csv_text);
  fs::remove(jsonl);
  expect_refusal_naming(track_error(r, again), "estimates.jsonl: missing, while estimates.csv has rows");
  std::ofstream(jsonl) << jsonl_text;
  // A damaged row in the middle of the CSV is named by its line.
  const size_t second = csv_text.find('\n', csv_text.find('\n') + 1) + 1;
  std::ofstream(csv) << csv_text.substr(0, second) << "garbage,row,here\n" << csv_text.substr(csv_text.find('\n', second) + 1);
  expect_refusal_naming(track_error(r, again), "estimates.csv:3: expected a row that starts with a frame index, got 'garbage,row,here'");
  std::ofstream(csv) << csv_text;
  // Estimates whose tracker state is gone are refused, not started over.
  const fs::path state = o.out_dir / "tracker_state.txt";
  const std::string state_text = read_text(state);
  fs::remove(state);
  expect_refusal_naming(track_error(r, again), "estimates.csv: holds tracked frames but tracker_state.txt is missing");
  EXPECT_EQ(read_text(csv), csv_text);
  std::ofstream(state) << state_text;
  // Another stride (or input, or stimulus log) would join two runs' frames.
  gtrack::TrackOptions other = again;
  other.range.every = 2;
  expect_refusal_naming(track_error(r, other), "tracker_state.txt: the run being resumed tracked input=");
  EXPECT_NE(track_error(r, other).find("every=1 stimulus=none; this one input="), std::string::npos);
  // So would another first frame: --frames 0:4, then 100:110 --resume.
  other = again;
  other.range.first = 3;
  EXPECT_NE(track_error(r, other).find("from=0 every=1 stimulus=none; this one input="), std::string::npos);
  EXPECT_EQ(read_text(csv), csv_text);
  EXPECT_EQ(track_error(r, again), "");
  EXPECT_EQ(valid_rows(csv), (std::vector<int>{0, 1, 2, 3, 4, 5, 6, 7}));
  EXPECT_EQ(read_lines(jsonl).size(), 8u);
}

// A run goes on with the config its first frames were tracked with: the
// config is kept beside the results, and another one is refused, naming
// the key; the same config written otherwise (a comment more) resumes.
TEST(Fault, ResumeRefusesAnotherConfig) {
  const auto [r, o] = stopped_run("resume_config");
  const fs::path kept = o.out_dir / "run_config.toml";
  ASSERT_TRUE(fs::exists(kept));
  // A config without a folder of its own took its relative paths from the
  // working folder: the copy says so.
  EXPECT_NE(read_text(kept).find("# gtrack track: its relative paths start at " +
                                 fs::current_path().lexically_normal().string() + "\n"),
            std::string::npos)
      << read_text(kept);
  EXPECT_NE(read_text(kept).find(kConfig), std::string::npos);
  const fs::path csv = o.out_dir / "estimates.csv";
  const std::string csv_text = read_text(csv);
  gtrack::TrackOptions again = o;
  again.range.last = -1;
  again.resume = true;
  expect_refusal_naming(track_error(make_run("mirror_check = false\n"), again),
                        "run_config.toml: [tracker] mirror_check was not set in the run being resumed, is false in "
                        "fault.toml; cannot resume with another config");
  EXPECT_EQ(read_text(csv), csv_text);
  // A damaged copy is named by its line, and nothing is changed.
  const std::string kept_text = read_text(kept);
  std::ofstream(kept) << kept_text << "[pso\n";
  const auto lines = std::count(kept_text.begin(), kept_text.end(), '\n');
  expect_refusal_naming(track_error(r, again), "run_config.toml:" + std::to_string(lines + 1) + ": ");
  EXPECT_EQ(read_text(csv), csv_text);
  // An empty copy (what a power loss can leave) is said to be empty, not
  // another config.
  std::ofstream(kept, std::ios::trunc).flush();
  expect_refusal_naming(track_error(r, again), "run_config.toml: is empty (cut short");
  EXPECT_EQ(read_text(csv), csv_text);
  std::ofstream(kept) << kept_text;
  TrackRun commented{gtrack::load_setup(gtrack::ConfigTable::parse("# a note\n" + kConfig, "fault.toml"), {}), {}};
  commented.config = gtrack::engine_config(commented.setup);
  EXPECT_EQ(track_error(commented, again), "");
  EXPECT_EQ(valid_rows(csv), (std::vector<int>{0, 1, 2, 3, 4, 5, 6, 7}));
  EXPECT_EQ(read_text(kept), kept_text);
  // The copy given as a fresh run's config is copied with one header.
  TrackRun from_copy{gtrack::load_setup(kept, {}), {}};
  from_copy.config = gtrack::engine_config(from_copy.setup);
  gtrack::TrackOptions fresh = o;
  fresh.out_dir = o.out_dir.parent_path() / "from_copy";
  EXPECT_EQ(track_error(from_copy, fresh), "");
  const std::string copied = read_text(fresh.out_dir / "run_config.toml");
  EXPECT_NE(copied.find(kConfig), std::string::npos);
  const std::string first_line = "# gtrack track: the config of the run in this folder";
  EXPECT_EQ(copied.rfind(first_line, 0), 0u) << copied;
  EXPECT_EQ(copied.find(first_line), copied.rfind(first_line)) << copied;
  // A file of the user's own under that name is not replaced.
  fresh.out_dir = o.out_dir.parent_path() / "users_file";
  fs::create_directories(fresh.out_dir);
  std::ofstream(fresh.out_dir / "run_config.toml") << "my notes\n";
  expect_refusal_naming(track_error(r, fresh), "run_config.toml: exists and was not written by gtrack track");
  EXPECT_EQ(read_text(fresh.out_dir / "run_config.toml"), "my notes\n");
  EXPECT_FALSE(fs::exists(fresh.out_dir / "estimates.csv"));
}

// The camera of kConfig as an OpenCV calibration file.
const std::string kCamera = R"(%YAML:1.0
---
image_width: 128
image_height: 128
camera_matrix: !!opencv-matrix
   rows: 3
   cols: 3
   dt: d
   data: [ 1600., 0., 63.5, 0., 1600., 63.5, 0., 0., 1. ]
distortion_coefficients: !!opencv-matrix
   rows: 1
   cols: 5
   dt: d
   data: [ 0., 0., 0., 0., 0. ]
)";

// kConfig with its camera read from camera.yml beside it.
std::string calibrated_config() {
  std::string config = kConfig;
  const std::string keys = "fx = 1600.0\nfy = 1600.0\ncx = 63.5\ncy = 63.5\n";
  EXPECT_NE(config.find(keys), std::string::npos);
  config.replace(config.find(keys), keys.size(), "calibration = \"camera.yml\"\n");
  return config;
}

// The files a config names are kept with it: a resumed run refuses a
// calibration file that changed since the run began, and goes on once it
// is restored. The copy given back as a config takes its relative paths
// from the original's folder, not from the output folder it stands in.
TEST(Fault, ResumeRefusesAChangedFileTheConfigNames) {
  const fs::path dir = fresh_dir("resume_files");
  fs::create_directories(dir / "lab");
  const std::string camera = kCamera;
  std::ofstream(dir / "lab" / "camera.yml") << camera;
  const std::string config = calibrated_config();
  std::ofstream(dir / "lab" / "lab.toml") << config;
  const auto load = [](const fs::path& file) {
    TrackRun r{gtrack::load_setup(file, {}), {}};
    r.config = gtrack::engine_config(r.setup);
    return r;
  };
  const TrackRun r = load(dir / "lab" / "lab.toml");
  gtrack::TrackOptions o = folder_run(dir, kFrames);
  o.range.last = 3;
  gtrack::track_sequence(r.setup, r.config, o);
  const fs::path kept = o.out_dir / "run_config.toml";
  const std::string camera_path = fs::absolute(dir / "lab" / "camera.yml").lexically_normal().string();
  EXPECT_NE(read_text(kept).find("# gtrack track: file [sensor] calibration = " + camera_path + ": " +
                                 std::to_string(camera.size()) + " bytes, FNV-1a 64 "),
            std::string::npos)
      << read_text(kept);
  const fs::path csv = o.out_dir / "estimates.csv";
  const std::string csv_text = read_text(csv);
  gtrack::TrackOptions again = o;
  again.range.last = -1;
  again.resume = true;
  // The same config, its calibration changed (the principal point moved).
  std::string moved = camera;
  moved.replace(moved.find("63.5"), 4, "60.5");
  std::ofstream(dir / "lab" / "camera.yml") << moved;
  expect_refusal_naming(track_error(load(dir / "lab" / "lab.toml"), again),
                        camera_path + ": has changed since the run being resumed began ([sensor] calibration: it was " +
                            std::to_string(camera.size()) + " bytes, FNV-1a 64 ");
  EXPECT_EQ(read_text(csv), csv_text);
  // The same text in another folder names another file.
  fs::create_directories(dir / "elsewhere");
  std::ofstream(dir / "elsewhere" / "camera.yml") << camera;
  std::ofstream(dir / "elsewhere" / "lab.toml") << config;
  expect_refusal_naming(track_error(load(dir / "elsewhere" / "lab.toml"), again),
                        "run_config.toml: [sensor] calibration was the file " + camera_path);
  EXPECT_EQ(read_text(csv), csv_text);
  std::ofstream(dir / "lab" / "camera.yml") << camera;
  EXPECT_EQ(track_error(load(dir / "lab" / "lab.toml"), again), "");
  EXPECT_EQ(valid_rows(csv), (std::vector<int>{0, 1, 2, 3, 4, 5, 6, 7}));
  // The copy, read from the output folder, finds camera.yml in lab/, and
  // a run made with it keeps that folder and that file.
  const TrackRun from_copy = load(kept);
  gtrack::TrackOptions fresh = o;
  fresh.out_dir = dir / "from_copy";
  EXPECT_EQ(track_error(from_copy, fresh), "");
  const std::string copied = read_text(fresh.out_dir / "run_config.toml");
  EXPECT_NE(copied.find("# gtrack track: its relative paths start at " +
                        fs::absolute(dir / "lab").lexically_normal().string() + "\n"),
            std::string::npos)
      << copied;
  EXPECT_NE(copied.find("# gtrack track: file [sensor] calibration = " + camera_path + ": "), std::string::npos)
      << copied;
  // The same folder by another name (a symbolic link) holds the same file.
  fs::create_directory_symlink(dir / "lab", dir / "lablink");
  EXPECT_EQ(track_error(load(dir / "lablink" / "lab.toml"), again), "");
}

// A run's copy keeps its folder whatever the folder's name (a backslash,
// letters beyond ASCII), and a config read from a pipe is read once.
TEST(Fault, ARunsCopyKeepsAnyFolderAndAConfigMayBeAPipe) {
  const fs::path dir = fresh_dir("copy_names");
  const fs::path lab = dir / "back\\slash caf\xC3\xA9";
  fs::create_directories(lab);
  std::ofstream(lab / "camera.yml") << kCamera;
  std::ofstream(lab / "lab.toml") << calibrated_config();
  TrackRun r{gtrack::load_setup(lab / "lab.toml", {}), {}};
  r.config = gtrack::engine_config(r.setup);
  gtrack::TrackOptions o = folder_run(dir, 2);
  EXPECT_EQ(track_error(r, o), "");
  const fs::path kept = o.out_dir / "run_config.toml";
  const std::string text = read_text(kept);
  EXPECT_NE(text.find("\\\\slash caf\\xC3\\xA9"), std::string::npos) << text;
  // Read from the output folder, the copy finds camera.yml in lab.
  EXPECT_NO_THROW(gtrack::load_setup(kept, {}));

  // A pipe: what a shell's <(...) or /dev/stdin gives.
  const fs::path fifo = dir / "config.fifo";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  std::thread writer([&] { std::ofstream(fifo) << text; });
  // Were the pipe opened a second time, that open would wait for a writer
  // for ever: one comes, after 5 s, and the test fails instead of hanging.
  std::atomic<bool> read{false};
  std::thread watchdog([&] {
    for (int i = 0; i < 50 && !read; ++i) std::this_thread::sleep_for(std::chrono::milliseconds(100));
    if (!read) {
      const int fd = ::open(fifo.c_str(), O_WRONLY | O_NONBLOCK);
      if (fd >= 0) ::close(fd);
    }
  });
  std::string error;
  try {
    gtrack::load_setup(fifo, {});
  } catch (const std::exception& e) {
    error = e.what();
  }
  read = true;
  writer.join();
  watchdog.join();
  EXPECT_EQ(error, "");
}

// A plugin whose factory throws: the executable exits non-zero with one line
// naming the plugin and carrying the plugin's own message.
TEST(Fault, ThrowingPluginFactoryIsOneLineFromTheExecutable) {
  const fs::path dir = fresh_dir("throwing_plugin");
  const fs::path cfg = dir / "throwing.toml";
  std::ofstream(cfg) << "[sensor]\nplugin = \"fixture_throwing_factory\"\n[gripper]\nplugin = \"hydrogel_six_finger\"\n";
  const auto r = gtrack_cli("render --plugin-path " + std::string(GTRACK_TEST_FIXTURE_DIR) + " --config " +
                            cfg.string() + " --params 0,0,100,0,0,0,0,0,0,0,0,0 --out " + (dir / "m.png").string());
  EXPECT_NE(r.code, 0);
  EXPECT_EQ(std::count(r.output.begin(), r.output.end(), '\n'), 1) << r.output;
  EXPECT_NE(r.output.find("fixture_throwing_factory"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("calibration file missing"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(dir / "m.png"));
}

struct KeyCase {
  std::string table, key, value;
};

// Each case is a ConfigError naming file, line and key, raised before any
// frame is read.
void expect_each_refused(const std::vector<KeyCase>& cases) {
  for (const auto& c : cases) {
    // Replace the key if the base config has it, else add it to its table.
    std::string text = kConfig;
    const std::string header = "[" + c.table + "]\n";
    const std::string line = c.key + " = " + c.value + "\n";
    const auto at = text.find(header);
    if (at == std::string::npos) {
      text += header + line;
    } else {
      const auto body = at + header.size();
      const auto next = text.find("\n[", body);
      const auto old = text.find("\n" + c.key + " = ", body - 1);
      if (old != std::string::npos && (next == std::string::npos || old < next)) {
        text.replace(old + 1, text.find('\n', old + 1) - old, line);
      } else {
        text.insert(body, line);
      }
    }
    SCOPED_TRACE("[" + c.table + "] " + c.key + " = " + c.value);
    try {
      const gtrack::Setup setup = gtrack::load_setup(gtrack::ConfigTable::parse(text, "bad.toml"), {});
      (void)gtrack::engine_config(setup);
      FAIL() << "accepted";
    } catch (const gtrack::Error& e) {
      const std::string m = e.what();
      EXPECT_TRUE(one_line(m)) << m;
      EXPECT_EQ(m.rfind("bad.toml:", 0), 0u) << m;
      EXPECT_NE(m.find(c.key), std::string::npos) << m;
    }
  }
}

// NaN and infinity are valid TOML; no numeric key may accept them.
TEST(Fault, NonFiniteConfigValuesAreRefusedWithFileLineKey) {
  expect_each_refused({
      {"sensor", "fx", "inf"},          {"sensor", "cx", "nan"},
      {"gripper", "joint_max_deg", "inf"}, {"stimulus", "fold_above_C", "nan"},
      {"pso", "inertia", "nan"},        {"cost", "lambda_dice", "inf"},
      {"cost", "lambda_kinematic", "-nan"}, {"render", "scale", "nan"},
      {"observation", "prior_sigma_px", "inf"}, {"search", "position_min_mm", "[-inf, 0.0, 90.0]"},
      {"tracker", "initial_pose", "[0, 0, nan, 0, 0, 0, 0, 0, 0, 0, 0, 0]"},
      {"tracker", "default_stimulus", "nan"}, {"tracker", "fps", "inf"},
      {"cost", "occlusion_growth_weight", "nan"},
  });
}

// Finite values no real setup has (a principal point a million images
// away, a turn of -900 degrees, a frame rate of 1e300) are refused as well.
TEST(Fault, ImplausibleConfigValuesAreRefusedWithFileLineKey) {
  expect_each_refused({
      {"sensor", "cx", "1e9"},
      {"sensor", "distortion", "[1e10, 1e10, 0, 0]"},
      {"search", "rotation_min_deg", "[-900, -60, -180]"},
      {"tracker", "fps", "1e300"},
      {"tracker", "fps", "1e-300"},
      {"tracker", "default_stimulus", "1e300"},
      {"gripper", "folded_deg", "500"},
      {"gripper", "unfolded_deg", "-10"},
      {"sensor", "fx", "1e300"},
      {"sensor", "working_distance_mm", "1e300"},
      {"cost", "lambda_dice", "0.0"},  // the image would not count
      {"render", "scale", "0.05"},     // 6x6 render pixels
      // A search box beside the field of view (both bounds below each other).
      {"search", "position_min_mm", "[50.0, 50.0, 90.0]\nposition_max_mm = [60.0, 60.0, 110.0]"},
      {"search", "position_min_mm", "[-1.0, -1.0, -20.0]\nposition_max_mm = [1.0, 1.0, -10.0]"},  // behind
  });
}

// A NaN or infinity in --params never reaches the renderer.
TEST(Fault, NonFiniteParameterVectorIsOneLine) {
  const fs::path dir = fresh_dir("nan_params");
  const fs::path cfg = dir / "c.toml";
  std::ofstream(cfg) << kConfig;
  for (const char* p : {"0,0,nan,0,0,0,0,0,0,0,0,0", "0,0,100,inf,0,0,0,0,0,0,0,0", "0,0,100,0,0,0,0,0,0,0,0,-inf"}) {
    const auto r = gtrack_cli("render --config " + cfg.string() + " --params " + p + " --out " +
                              (dir / "m.png").string());
    EXPECT_NE(r.code, 0) << p;
    EXPECT_EQ(std::count(r.output.begin(), r.output.end(), '\n'), 1) << r.output;
    EXPECT_NE(r.output.find("not a finite number"), std::string::npos) << r.output;
  }
}

// The readers' and writers' shared checks: a line and a file have a bound, a
// write is checked after its buffer went out.
// A library's words in a message: OpenCV's source location and function,
// and FFmpeg's pointers, are left out; what it says is kept.
TEST(TextFile, LibraryWordsKeepWhatTheLibrarySaid) {
  EXPECT_EQ(gtrack::library_words("OpenCV(4.6.0) ./modules/core/src/alloc.cpp:73: error: (-4:Insufficient memory) "
                                  "Failed to allocate 4294967296 bytes in function 'OutOfMemoryError'\n"),
            "Insufficient memory: Failed to allocate 4294967296 bytes");
  EXPECT_EQ(gtrack::library_words("imreadmulti_('a.tif'): can't read data: OpenCV(4.6.0) "
                                  "./modules/imgcodecs/src/grfmt_tiff.cpp:704: error: (-2:Unspecified error) OpenCV "
                                  "TIFF: failed TIFFReadRGBAStrip(...) in function 'readData'"),
            "imreadmulti_('a.tif'): can't read data: Unspecified error: OpenCV TIFF: failed TIFFReadRGBAStrip(...)");
  EXPECT_EQ(gtrack::library_words("OpenCV(4.6.0) matrix.cpp:250: error: (-215:Assertion failed) s >= 0 in function 'f'"),
            "Assertion failed: s >= 0");
  EXPECT_EQ(gtrack::library_words("[mov,mp4,m4a,3gp,3g2,mj2 @ 0x55d0c0a1b2c0] moov atom not found"),
            "mov,mp4,m4a,3gp,3g2,mj2: moov atom not found");
  EXPECT_EQ(gtrack::library_words("[mjpeg @ 0x563318912a40] overread 8; [h264 @ 0x55d0] error while decoding"),
            "mjpeg: overread 8; h264: error while decoding");
  EXPECT_EQ(gtrack::library_words("libpng error: Read Error"), "libpng error: Read Error");
}

TEST(TextFile, BoundsAndFailedWritesAreOneLineErrors) {
  std::istringstream three("ab\n\nlast");
  std::string line;
  std::vector<std::string> got;
  for (int n = 1; gtrack::read_bounded_line(three, line, 4, "t.csv", n, "rows"); ++n) got.push_back(line);
  EXPECT_EQ(got, (std::vector<std::string>{"ab", "", "last"}));

  std::istringstream long_line("abcd\nabcde\n");
  EXPECT_TRUE(gtrack::read_bounded_line(long_line, line, 4, "t.csv", 1, "rows"));
  try {
    gtrack::read_bounded_line(long_line, line, 4, "t.csv", 2, "rows");
    FAIL() << "a line of 5 characters over a bound of 4 must throw";
  } catch (const gtrack::InputError& e) {
    EXPECT_STREQ(e.what(), "t.csv:2: a line of more than 4 characters; expected rows");
  }

  const fs::path dir = fs::temp_directory_path() / "gtrack_text_file_test";
  fs::remove_all(dir);
  fs::create_directories(dir);
  gtrack::write_text_file(dir / "a.txt", std::string(3000, 'x'));
  EXPECT_EQ(gtrack::read_text_file(dir / "a.txt", 3000, "text").size(), 3000u);
  try {
    gtrack::read_text_file(dir / "a.txt", 2048, "a small file");
    FAIL() << "3000 bytes over a bound of 2048 must throw";
  } catch (const gtrack::InputError& e) {
    EXPECT_EQ(std::string(e.what()), (dir / "a.txt").string() + ": more than 2 KiB; expected a small file");
  }
  EXPECT_THROW(gtrack::read_text_file(dir, 1000, "text"), gtrack::InputError);
  EXPECT_THROW(gtrack::read_text_file(dir / "none.txt", 1000, "text"), gtrack::InputError);
  EXPECT_THROW(gtrack::write_text_file(dir / "no_folder" / "a.txt", "x"), gtrack::InputError);
  if (fs::exists("/dev/full")) {
    try {
      gtrack::write_text_file("/dev/full", std::string(1 << 16, 'x'));
      FAIL() << "a full disk must throw";
    } catch (const gtrack::InputError& e) {
      EXPECT_STREQ(e.what(), "/dev/full: write failed (No space left on device)");
    }
  }
  fs::remove_all(dir);
}

// A unit mistake that makes the gripper sub-pixel (a focal length in
// millimetres instead of pixels) is said when the setup is loaded, with both
// sizes; the shipped scale is not.
TEST(Fault, AGripperAFewPixelsAcrossIsWarnedAbout) {
  const auto warnings = [](const std::string& text) {
    return gtrack::testing::logged([&] { gtrack::load_setup(gtrack::ConfigTable::parse(text, "units.toml"), {}); });
  };
  EXPECT_EQ(warnings(kConfig).find("pixels across"), std::string::npos) << warnings(kConfig);
  std::string tiny = kConfig;
  for (const char* key : {"fx = 1600.0", "fy = 1600.0"}) tiny.replace(tiny.find(key), 11, std::string(key, 5) + "1.6");
  const std::string said = warnings(tiny);
  EXPECT_NE(said.find("units.toml: the gripper (4 mm across, open) is 0.064 pixels across"), std::string::npos) << said;
  EXPECT_NE(said.find("check the units of [gripper] and [sensor]"), std::string::npos) << said;
}
