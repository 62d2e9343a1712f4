// The tracker: one frame in, the gripper's configuration out (paper Fig. 2).
//
// Tracker is the per-frame API: process() segments the frame into the
// observation O (with the previous estimate's ROI and prior), feeds the
// stimulus reading to the Stimulus plugin, initialises the swarm from the
// previous best (biased by Stimulus::fold_fraction), runs Algorithm 1 with
// every generation rendered and counted as one batch, and returns the best
// hypothesis g^ with its cost terms.
//
// The first frame starts from [tracker] initial_pose when configured, else
// from a coarse search: the observation's centroid is lifted to 3D at the
// sensor's nominal depth, a grid of rz / tilt / joint hypotheses there is
// scored in batches, and the best few are refined by a PSO each.
//
// Lost: a frame whose observation is empty (or whose best D exceeds
// [tracker] lost_dice) is reported with status "lost", the previous estimate
// is held, and the search region of the next frame grows with each lost
// frame. After reinit_after_lost lost frames the next frame with anything
// detected in the full image is re-initialised by the coarse search
// (status "search").
//
// track_sequence() is the whole `gtrack track` job as a library call: frames
// from a source, stimulus from a CSV, results, overlay and summary written to
// a folder as they are computed. It stops cleanly between frames when the
// cancel flag is raised.
#pragma once

#include <Eigen/Core>
#include <atomic>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <opencv2/core.hpp>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include "gtrack/cost.hpp"
#include "gtrack/engine_config.hpp"
#include "gtrack/export.hpp"
#include "gtrack/frame_source.hpp"
#include "gtrack/observation.hpp"
#include "gtrack/pso.hpp"
#include "gtrack/renderer.hpp"
#include "gtrack/setup.hpp"
#include "gtrack/tracker_state.hpp"

namespace gtrack {

enum class TrackStatus {
  Tracked,  // "ok": PSO from the previous estimate
  Search,   // "search": coarse search (first frame, after a loss)
  Lost,     // "lost": nothing usable detected; the previous estimate is held
};
GTRACK_API const char* to_string(TrackStatus status);

// Milliseconds spent per stage of one frame.
struct StageTimes {
  double segment_ms = 0;
  double pso_ms = 0;
  // In an estimate: reading the frame (a followed folder's wait for it left
  // out); the row is written before its overlay, so that a controller gets
  // it first. In a run's mean: reading, and writing results and overlay.
  double io_ms = 0;
};

// A tilt margin (Estimate::tilt_margin) under this is a tilt whose sign the
// image barely decides: the overlay says so and gtrack eval --breakdown
// splits the frames there (docs/tracker.md, "How sure the tilt's sign is").
inline constexpr double kNarrowTiltMargin = 0.1;

struct Estimate {
  int frame = 0;
  double time_s = 0;
  Eigen::VectorXd hypothesis;  // g^: x,y,z (mm), rx,ry,rz (deg), q1..qF (deg)
  CostTerms terms;             // of g^ against this frame's observation
  TrackStatus status = TrackStatus::Tracked;
  std::optional<double> stimulus;  // the reading used for this frame
  // A followed stimulus log (--follow-stimulus): seconds since the row the
  // reading came from was read, when the frame took it.
  std::optional<double> stimulus_age_s;
  std::uint64_t observed_pixels = 0;  // |O|
  double outside_weight = 1;          // weight of P\O in D this frame ([cost] occlusion_discount)
  double outside_allowance = 0;       // P\O pixels not counted in D this frame ([cost] occlusion_budget)
  std::uint64_t evaluations = 0;      // hypotheses scored for this frame
  bool redetected = false;            // the coarse search's result replaced the tracked one
  bool mirrored = false;              // the tilt mirror of the result scored lower and replaced it
  // How sure the tilt's sign is: at the mirror check ([tracker]
  // mirror_check, a result tilted more than 3 deg), the costs of the result
  // and of its refined tilt mirror, the higher less the lower over the lower.
  // Seen along the optical axis the two branches differ only through
  // perspective and occlusion: a small margin is a tilt whose sign the image
  // barely decides (under kNarrowTiltMargin). Empty when the check did not
  // run (a flat gripper, whose mirror is itself) or the frame is lost.
  std::optional<double> tilt_margin;
  // Fingers (1 = q1) the image did not see, whose joints are reported at
  // the seen fingers' mean fold ([tracker] unseen_joint_tolerance).
  std::vector<int> unseen_fingers;
  // A reference configuration (TrackOptions::score_truth) scored on this
  // frame exactly as the estimate was: same observation, allowance,
  // temporal prediction and stimulus.
  std::optional<CostTerms> reference_terms;
  // In the two-pass table (gtrack/two_pass.hpp): the pass the row was taken
  // from, "forward" or "backward" ("two_pass" in estimates.jsonl).
  std::string two_pass_source;
  StageTimes times;
  double ms = 0;  // segment + PSO (the tracker's own time for the frame)
  // Set by track_sequence(): the image the frame came from (an image's
  // path, "<video> frame N"), when it had been read (decoded: for a live
  // source, about when it arrived) and when its estimate was written
  // (seconds since the Unix epoch, this machine's clock), for matching a
  // streamed estimate with its image and measuring the delay; "" and 0
  // otherwise. An image file's modification time (Frame::written_unix_s)
  // is when it was written.
  std::string image;
  double written_unix_s = 0;
  double read_unix_s = 0;
  double unix_time_s = 0;
};

// One Tracker follows one sequence. It keeps the Setup's plugin instances
// (shared pointers): process() feeds the Setup's Stimulus, so two trackers
// running at once need a Setup each (nothing detects two on one Setup).
//
// Threads: a Tracker is used by one thread at a time. With the gl backend
// its OpenGL context is made current on the thread that constructs it, so
// construct it on the thread that will call process() (a camera thread,
// say); from another, process() throws "eglMakeCurrent failed".
//
// The configurations it takes and gives are in the world. It searches in
// the sensor's own frame (SensorFrame in sensor.hpp), as its config's space
// is, so that a probe or a camera turned in the world is tracked as an
// upright one; for a sensor that looks down world z the two are the same.
class GTRACK_API Tracker {
 public:
  // Makes the renderer named by config.render.
  Tracker(const Setup& setup, EngineConfig config);
  // With a renderer of the caller's (e.g. one shared by tests).
  Tracker(const Setup& setup, EngineConfig config, std::unique_ptr<Renderer> renderer);
  ~Tracker();
  Tracker(const Tracker&) = delete;
  Tracker& operator=(const Tracker&) = delete;
  Tracker(Tracker&&) noexcept;  // the moved-from tracker can only be destroyed or assigned
  Tracker& operator=(Tracker&&) noexcept;

  // Tracks one frame (BGR at the sensor's image size; a camera's 16-bit or
  // grey frames through to_tracker_image() first). `index` numbers the
  // frame and seeds its random draws (frames numbered alike give the same
  // estimates); `time_s` is its time in seconds, finite and, for the
  // stimulus plugin, increasing. `stimulus` is the reading for this frame;
  // nullopt = no reading (the configured default is used if any, else S and
  // the bias are off). InputError for a frame of another size or type, a
  // time or reading that is not finite, or a reading the stimulus plugin
  // refuses (naming the frame); a frame refused for its size or type leaves
  // the tracker as it was.
  Estimate process(const cv::Mat& frame, int index, double time_s, std::optional<double> stimulus);

  // Forget the history: the next frame starts like the first. The stimulus
  // plugin is made anew from the config's [stimulus] table when the
  // Setup's loader made it (load_setup's Setups; PluginError if it can no
  // longer be loaded); a stimulus the application set itself keeps its state.
  void reset();
  // The history, in the frame the tracker searches in (the class comment).
  TrackerState state() const;
  // Continue from a state (of a tracker with the same setup and config);
  // gtrack::Error when its configurations are not of this setup's size.
  void restore(const TrackerState& state);
  // Feeds a past frame's reading to the stimulus plugin as process() would,
  // without tracking: replayed in order, it rebuilds the plugin's state.
  void replay_stimulus(std::optional<double> stimulus, double time_s);
  // Start the next frame from this hypothesis (as if it were the last estimate).
  void set_estimate(const Eigen::VectorXd& hypothesis);
  std::optional<Eigen::VectorXd> last_estimate() const;

  // The observation of the last processed frame (render size, 0/255); the
  // next process() overwrites it, so copy what is to be kept.
  const Observation& last_observation() const;
  // A configuration scored on the last processed frame as its estimate was:
  // the same observation, occlusion allowance, temporal prediction and
  // stimulus state. Throws before this tracker has processed a frame (a
  // restored state holds no observation).
  CostTerms score(const Eigen::VectorXd& hypothesis);
  // The same, but with the occlusion allowance a track whose previous
  // estimate was `previous` would have had on this frame (the model's whole
  // area there against the observation's). The tracker's own allowance is
  // left as it was.
  CostTerms score_after(const Eigen::VectorXd& hypothesis, const Eigen::VectorXd& previous);
  // T of a configuration against another taken as the prediction (the
  // temporal term's spreads, rz wrapped as the search space wraps it),
  // without changing the tracker's own prediction.
  double temporal_term(const Eigen::VectorXd& hypothesis, const Eigen::VectorXd& prediction) const;
  // The estimate drawn on a frame: posed triangles projected with
  // Sensor::project and filled in green with alpha, plus the stimulus reading
  // in the bottom-right corner; "lost", or "tilt's sign uncertain" under a
  // narrow tilt margin, in the top-left one.
  cv::Mat draw_overlay(const cv::Mat& frame, const Estimate& estimate) const;

  // The renderer, config and space the search uses: in the sensor's frame,
  // like the configurations they take (for a sensor looking down world z,
  // the world's).
  Renderer& renderer();
  const EngineConfig& config() const;
  const ParameterSpace& space() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

struct TrackOptions {
  std::string input;                          // video file, image folder or "camera:N"
  std::optional<std::filesystem::path> stimulus_csv;
  // The log's column of readings when it has several named ones (a
  // logger's channels); "" = its only one (StimulusLog).
  std::string stimulus_column;
  // A time_s log on another clock (a logger started before the camera, or
  // one in Unix time): its time at the recording's first frame, subtracted
  // from its time_s column (--stimulus-offset).
  double stimulus_offset_s = 0;
  std::filesystem::path out_dir;
  FrameRange range;                           // --frames A:B, --every K
  bool save_masks = false;                    // out_dir/masks/NNNNNN.png (observation O)
  std::optional<bool> overlay;                // overrides [tracker] overlay
  bool progress = true;                       // progress line on stderr
  const std::atomic<bool>* cancel = nullptr;  // raised: finish the frame, close files, return
  // Continue the run whose files are in out_dir, after the last frame its
  // tracker_state.txt records (none there: start from the first frame).
  bool resume = false;
  // Each frame's rows, then the tracker state, are on the disk (fsync)
  // before the next frame, so that a power loss loses no finished frame and
  // --resume continues after the last one. Without it a crash or a kill
  // loses nothing either; a power loss can lose what the system had not yet
  // written, and --resume then refuses with a one-line error.
  bool durable = false;
  // The stimulus plugin is also fed the log's readings of the frames not
  // tracked (before --frames A:B's first, between --every's). Off for a
  // two-pass run, whose backward pass replays the tracked frames' readings
  // only, so that both passes see the stimulus in the same states.
  bool feed_untracked_readings = true;
  // The stimulus log is still being written (a live run): before each frame
  // its new rows are read, and the frame takes the last row's reading.
  bool follow_stimulus = false;
  // The input folder is still being written (acquisition software saving
  // images as they come): new images are tracked as they arrive, and the
  // run ends after this many seconds without one (0: not followed).
  double follow_input_s = 0;
  // A live source (a camera, a followed folder) faster than the tracker:
  // each frame tracked is the newest one read, and the frames that came
  // while the tracker was busy are left out (counted in the summary's
  // skipped_frames) instead of queueing up behind it, the estimates falling
  // ever further behind the images. Refused for a recording.
  bool newest = false;
  // A pose table (ground_truth.csv, or another run's estimates.csv): before
  // each frame the track is set to the table's row for the range's previous
  // frame, so each estimate is one frame of tracking from that row. With the
  // ground truth it separates what one frame's search adds from what
  // accumulates over a sequence. Frames whose previous row is missing are
  // tracked from the track as it is.
  std::optional<std::filesystem::path> restart_from;
  // A pose table (ground_truth.csv): after each frame its row for that frame
  // is scored as the estimate was (Tracker::score) and written beside it in
  // estimates.jsonl ("reference"). A reference that scores lower than the
  // estimate is a configuration the search missed; one that scores no lower
  // is one the cost cannot prefer (docs/RESULTS.md, "Where the error comes
  // from"). The track itself is not changed.
  std::optional<std::filesystem::path> score_truth;
  std::function<void(const Estimate&)> on_frame;  // called after each frame is written
};

struct TrackSummary {
  int frames = 0;
  int lost_frames = 0;
  double mean_cost = 0;      // over frames not lost (NaN when every frame was lost)
  double mean_ms = 0;        // tracker time per frame
  StageTimes mean_times;     // per stage, per frame
  double wall_s = 0;
  bool cancelled = false;
  std::string renderer;
  std::filesystem::path overlay_file;  // empty if none was written
  int resumed_after = -1;    // --resume: the last frame done before this run (-1: a fresh run)
  int frames_before = 0;     // --resume: rows kept from before; `frames` counts this run's only
  std::string input_ended_early;  // FrameSource::ended_early: "" when the input ended where it said it would
  int skipped_frames = 0;    // TrackOptions::newest: frames read and left out for a newer one
  int skipped_stimulus_rows = 0;  // follow_stimulus: rows of the log left out, malformed or refused (warned about)
  std::string stopped_by;    // the error that stopped the run part way ("" when none; it is then thrown on)
};

// Runs the tracker over a source and writes, in options.out_dir:
// estimates.csv, estimates.jsonl (appended and flushed per frame),
// overlay.mp4 (or overlay.avi), masks/ (with save_masks) and summary.json.
// Throws InputError for unusable inputs or an unwritable folder.
GTRACK_API TrackSummary track_sequence(const Setup& setup, const EngineConfig& config, const TrackOptions& options);

}  // namespace gtrack
