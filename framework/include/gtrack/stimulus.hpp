// Stimulus plugins: what the gripper's material responds to (paper 2.2, 3).
//
// One instance follows one sequence: update() is called once per frame with
// the reading(s) of that frame, in order. From its state the plugin supplies
// S(H), the penalty for joint values the stimulus makes infeasible, and the
// bias of the swarm's initial joint values.
//
// The contract (docs/plugins.md, "Writing a plugin"):
// - Readings are in the plugin's own unit (reading_unit()), as the lab's
//   log has them. update() throws (gtrack::Error, or a standard exception,
//   with a one-line message) for a reading it cannot take: not finite, out
//   of its range, a change faster than the material allows; and when it
//   throws, leaves its state as it was. gtrack checks a finished log's
//   every row with it before tracking and names the row; a followed log's
//   rows as they come, leaving out one refused after others were taken.
// - All calls to an instance come from one thread, in frame order.
// - The state is a function of the readings and times fed so far: --resume
//   and --two-pass rebuild it by feeding them again to a new instance, so
//   update() must not depend on the wall clock, randomness or globals.
// - state(), penalty() (0 or more), fold_fraction() and target_joint_deg()
//   return finite numbers; a result that is not is refused as the plugin's
//   error.
#pragma once

#include <span>
#include <string>

#include "gtrack/export.hpp"

namespace gtrack {

enum class StimulusTrend { Steady, Folding, Unfolding };

struct StimulusState {
  double value = 0;                 // the latest reading (e.g. degrees Celsius)
  double rate = 0;                  // smoothed change per second (or per frame)
  StimulusTrend trend = StimulusTrend::Steady;
  bool in_transition = false;       // inside the range where the gripper changes shape
  // Joint range (degrees) the stimulus allows now; joints outside it are
  // infeasible and count in S(H).
  double feasible_min_deg = -1e9;
  double feasible_max_deg = 1e9;
};

class GTRACK_API Stimulus {
 public:
  virtual ~Stimulus();

  // Feeds one frame's reading; time_s is the frame time (monotonic).
  virtual void update(double value, double time_s) = 0;
  virtual StimulusState state() const = 0;
  // S(H): mean absolute error of the infeasible joints against the reference
  // values, normalised by the folded-unfolded span; 0 if all are feasible.
  virtual double penalty(std::span<const double> joints_deg) const = 0;
  // Fraction of the swarm whose joints start increased (folding); the rest
  // start decreased. Paper: 0.75 when folding is likely, 0.25 when unfolding
  // is likely, 0.5 otherwise.
  virtual double fold_fraction() const = 0;
  // For synthetic sequences: the joint value a gripper at `current_deg` moves
  // towards under the present state.
  virtual double target_joint_deg(double current_deg) const = 0;
  // Name and unit of the reading, for logs and overlays ("T", "C").
  virtual std::string reading_label() const;
  virtual std::string reading_unit() const;
};

}  // namespace gtrack
