// The backward pass of a recorded sequence (`gtrack track --two-pass`).
//
// A track that settles in a wrong basin (the tilt's other branch under an
// occluder, a sliver of the gripper coming back into view) stays there for
// several frames, until a clearer frame lets re-detection or the mirror
// check correct it. On a recording, the frames before that correction can be
// tracked again from it: the backward pass runs a second tracker over the
// frames in reverse order, from its own coarse search on the last frame.
// After each of its frames, the forward estimate of that frame is scored on
// the same observation, occlusion allowance and stimulus state
// (Tracker::score), and the two-pass table takes whichever scores lower, the
// temporal term left out of the comparison (each track's prediction favours
// its own estimate). docs/tracker.md, "The two-pass track", has the figures.
//
// The stimulus plugin's state is that of the forward run at the frame (the
// readings up to it replayed into a fresh instance of the plugin), so the
// hysteresis and the response time act as they did; only the swarm's fold
// bias is turned around (a gripper folding forward in time unfolds
// backward).
#pragma once

#include <vector>

#include "gtrack/export.hpp"
#include "gtrack/setup.hpp"
#include "gtrack/tracker.hpp"

namespace gtrack {

struct TwoPassSummary {
  int frames = 0;         // frames of the two-pass table
  int from_backward = 0;  // of those, taken from the backward pass
  int backward_lost = 0;  // frames the backward pass reported lost
  double wall_s = 0;      // the backward pass and the choice
  bool cancelled = false; // interrupted: backward/ holds the frames done, no two-pass table is written
};

// Runs the backward pass over the frames of `forward` (a finished run of
// track_sequence with `options`, its estimates in frame order) and writes,
// in options.out_dir: backward/estimates.csv and .jsonl (the backward track,
// rows appended as its frames are done, last frame first) and
// two_pass/estimates.csv and .jsonl (frame order, once the pass is done).
// InputError for a live camera (no recording to go back over).
GTRACK_API TwoPassSummary two_pass(const Setup& setup, const EngineConfig& config, const TrackOptions& options,
                                   const std::vector<Estimate>& forward);

}  // namespace gtrack
