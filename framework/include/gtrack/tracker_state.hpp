// What the tracker carries from one frame to the next, and its file,
// tracker_state.txt (`gtrack track --resume`, docs/tracker.md).
//
//   gtrack-tracker-state 1
//   frame 41
//   lost 0
//   started 1
//   reference_area 0
//   last 0.28088680263448867 -0.65538763658777754 100.09506213033944 ...
//   before_last -
//   reported 0.28088680263448867 -0.65538763658777754 100.09506213033944 ...
//   last_found 0
//   found_step -
//   run input=/data/rec1/frames every=1 stimulus=/data/rec1/stimulus.csv
//
// The configurations are written with 17 significant digits, so a resumed
// run starts from exactly the values the interrupted one held.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>

#include "gtrack/export.hpp"

namespace gtrack {

// With the stimulus plugin's state (rebuilt by replaying the past readings)
// it is all a run needs to continue where it stopped, with the same results.
struct TrackerState {
  int frame = -1;  // the last frame processed; -1 = none
  // In the sensor's frame (Tracker's class comment). `last` is the result
  // the track goes on from: before unseen fingers take the seen fingers'
  // fold, so its joints can differ from the reported Estimate::hypothesis;
  // restore() continues exactly, set_estimate(e.hypothesis) does not.
  std::optional<Eigen::VectorXd> last, before_last;
  // What the last frame not lost reported (unseen joints filled in), which
  // a lost frame reports; states of earlier releases have none (a lost
  // frame then reports `last`).
  std::optional<Eigen::VectorXd> reported;
  // `last` came from a search (coarse search or re-detection); the x, y step
  // between two such estimates of consecutive frames (none: -).
  bool last_found = false;
  std::optional<Eigen::VectorXd> found_step;
  int lost = 0;
  bool started = false;
  std::uint64_t reference_area = 0;
  // What the run tracks (its input, stride and stimulus log), written by
  // track_sequence() so that --resume refuses to join another recording's
  // frames; the tracker itself neither sets nor reads it. Empty in states of
  // earlier releases.
  std::string run;
};

// Replaces `file` (write, then rename): never a half-written state.
// durable: on the disk when it returns (fsync of the data and the folder).
GTRACK_API void write_tracker_state(const std::filesystem::path& file, const TrackerState& state,
                                    bool durable = false);
// InputError "name:line: ..." when the text is not a tracker state.
GTRACK_API TrackerState parse_tracker_state(std::string_view text, const std::string& name);
GTRACK_API TrackerState read_tracker_state(const std::filesystem::path& file);

}  // namespace gtrack
