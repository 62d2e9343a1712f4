// Two passes over a recorded sequence (`gtrack track --two-pass`).
//
// A track that settles in a wrong basin (the tilt's other branch under an
// occluder, a sliver of the gripper coming back into view) stays there for
// several frames, until a clearer frame lets re-detection or the mirror
// check correct it. On a recording, the frames before that correction can be
// tracked again from it: the backward pass runs a second tracker over the
// frames in reverse order, from its own coarse search on the last frame.
// The forward run is then tracked again (the same seed: the same estimates),
// and each frame's backward estimate is scored beside its forward one, on
// the forward track's observation and stimulus state, as --score-truth
// scores a reference, with the occlusion allowance that each candidate of
// the previous frame gives (Tracker::score_after). The two-pass table
// takes, over the whole sequence, the path through the two candidates that
// minimises their costs (temporal term aside) plus the temporal term's
// distance between consecutive estimates at the same weight λT; its
// orientations are then smoothed over neighbouring frames
// (smooth_orientations, below). docs/tracker.md, "Two passes over a
// recording", has the figures.
//
// The stimulus plugin's state is that of the forward run at the frame (the
// readings up to it replayed into a fresh instance of the plugin), so the
// hysteresis and the response time act as they did; only the swarm's fold
// bias is turned around (a gripper folding forward in time unfolds
// backward).
#pragma once

#include <array>
#include <string>
#include <vector>

#include "gtrack/export.hpp"
#include "gtrack/setup.hpp"
#include "gtrack/tracker.hpp"

namespace gtrack {

struct TwoPassSummary {
  int frames = 0;         // frames of the two-pass table
  int from_backward = 0;  // of those, taken from the backward pass
  int backward_lost = 0;  // frames the backward pass reported lost
  double wall_s = 0;      // the backward pass, the forward run again and the choice
  bool smoothed = false;            // [tracker] two_pass_smoothing > 0
  double smoothing_change_deg = 0;  // mean change of orientation made by the smoothing
  bool cancelled = false; // interrupted: backward/ holds the frames done, no two-pass table is written
};

// Runs the backward pass over the frames of `forward` (a finished run of
// track_sequence with `options`, its estimates in frame order) and writes,
// in options.out_dir: backward/estimates.csv and .jsonl (the backward track,
// rows appended as its frames are done, last frame first) and
// two_pass/estimates.csv and .jsonl (frame order, once both passes are
// done). The tracker's time is about three times the forward run's.
// InputError for a live camera (no recording to go back over).
GTRACK_API TwoPassSummary two_pass(const Setup& setup, const EngineConfig& config, const TrackOptions& options,
                                   const std::vector<Estimate>& forward);

// For reports: "orientations smoothed (0.52 deg on the mean)" or
// "orientations not smoothed".
GTRACK_API std::string smoothing_report(const TwoPassSummary& summary);

// The orientations of a table smoothed over neighbouring rows (the last
// step of two_pass, with [tracker] two_pass_smoothing as `sigma`): around
// each row, the rotations of the rows within ceil(3 sigma), as rotation
// vectors relative to the row's, are fitted by a straight line in the row
// index, with Gaussian weights of standard deviation `sigma` rows times
// each row's support (below); the row takes the line's value. The scatter
// of single rows is averaged out, and a steady turn is kept as it is, also
// where the window is one-sided (the table's ends, next to lost rows).
// Lost rows neither take part nor change.
// Each row's support is its overlap with the observation (terms.overlap)
// against the table's 90th percentile, within [0.05, 1], cubed: a sliver at
// the image's border or a gripper mostly under an occluder takes its
// orientation from its neighbours and gives them little of its own. A
// table without overlaps (all 0) has every row at support 1.
// Each row is first taken as its symmetric equivalent nearest the previous
// row's, so that like is fitted with like, and the result is given back in
// the row's own equivalent. Position and joints are left as they are.
// Returns the mean change of orientation (deg) over the rows that are not
// lost; sigma <= 0 changes nothing. `sigma` counts rows of the table: with
// `--every K`, K times as many frames of the input.
GTRACK_API double smooth_orientations(const ArticulatedModel& model, std::vector<Estimate>& rows, double sigma);

// The choice between two candidates per frame (0 the forward estimate, 1
// the backward one), over a whole table: costs[i][from][to] is the cost of
// taking candidate `to` at frame i after candidate `from` at frame i - 1
// (in two_pass: its cost with the occlusion allowance `from` gives, plus
// the temporal distance between the two); at the first frame only
// costs[0][0] is read. An infinite cost rules the candidate, or the step,
// out. Returns, per frame, the candidate of the path whose summed cost is
// least (dynamic programming over the whole table: a candidate that costs
// more at one frame is taken when the frames after it repay it); ties go
// to the forward candidate, as does every frame where each path is ruled
// out.
GTRACK_API std::vector<int> cheapest_path(const std::vector<std::array<std::array<double, 2>, 2>>& costs);

}  // namespace gtrack
