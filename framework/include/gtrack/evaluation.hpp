// Tracking accuracy against ground truth (paper Section 5.1, Fig. 6).
//
// Per frame, an estimate is compared with the truth after choosing, among
// the gripper's rotationally symmetric equivalents
// (ArticulatedModel::symmetric_equivalent, k = 0..order-1), the one whose
// phalanx endpoints lie closest to the truth's: a six-finger gripper turned
// by 60 degrees with its fingers renumbered is the same physical thing and
// must score zero. Errors: palm-centre position (3D, in the image plane x-y,
// depth z; micrometres), orientation (geodesic angle between the rotations,
// and split about the x, y, z axes; degrees), joints (mean absolute over fingers; degrees)
// and the mean distance between corresponding phalanx endpoints
// (micrometres, the paper's Fig. 6 metric).
//
// Nothing is dropped silently. A frame without an estimate row, or with
// status "lost", is counted as lost; frames whose truth is (almost) outside
// the view are kept apart from the in-view statistics and summarised on
// their own; after each stretch outside the view, the frames it takes the
// tracker to be back on the gripper are counted (recovery).
#pragma once

#include <Eigen/Core>
#include <filesystem>
#include <string>
#include <vector>

#include "gtrack/export.hpp"
#include "gtrack/model.hpp"
#include "gtrack/sensor.hpp"
#include "gtrack/sequence_io.hpp"

namespace gtrack {

struct EvalOptions {
  // A truth frame with less than this share of the gripper inside the image
  // is "out of view" (ground_truth.csv's in_view column; computed from the
  // sensor when the column is absent).
  double out_of_view_below = 0.1;
  // An estimate whose mean endpoint error exceeds this is off the gripper:
  // it counts as not yet recovered after a return into view.
  double off_track_endpoint_um = 400;
  // Judge off track by the endpoints' distance across the viewing axis
  // (FrameErrors::endpoint_inplane_um): for an ultrasound slice, whose image
  // does not show where within its slab the gripper lies, and for a small
  // gripper's small threshold, which a camera's depth error alone would
  // pass (gtrack eval --off-track-in-plane).
  bool off_track_in_plane = false;
};

struct ErrorStats {
  double mean = 0, std = 0, max = 0;
  double median = 0;  // robust to the few frames of a track that drifted off
  int count = 0;
};

// The statistics of several sets of frames taken as one (a sweep's cell
// over its sequences): each part weighs by its count, and the spread
// between the parts' means counts in std. The median cannot be pooled and
// is NaN.
GTRACK_API ErrorStats pooled(const std::vector<ErrorStats>& parts);

struct FrameErrors {
  // depth_um along the sensor's viewing axis (a camera's optical axis, the
  // normal of an ultrasound slice), inplane_um across it: world z and x-y
  // for a camera looking down world z.
  double position_um = 0, inplane_um = 0, depth_um = 0;
  double orientation_deg = 0;
  // The rotation from the truth's orientation to the estimate's, split
  // about x, y, z (|components of its rotation vector|; their squares sum
  // to orientation_deg's): the sensor's own axes when evaluate() has the
  // sensor (SensorFrame; the world's for one looking down z), else the
  // world's.
  Eigen::Vector3d axis_deg{0, 0, 0};
  double joint_deg = 0;
  double endpoint_um = 0;
  double endpoint_inplane_um = 0;  // the same, each distance taken across the viewing axis
  int symmetry_k = 0;  // the equivalent of the estimate that was compared
  // The truth is flat (every link within kFlatShare of the model's radius of
  // the palm plane) and tilted by more than kMirrorMinTiltDeg from the line
  // of sight v, and the estimate's palm normal lies nearer to the truth's
  // tilt mirror (n turned by 180 degrees about v: m = 2 (n.v) v - n) than to
  // n or to -n (e.m > |e.n|).
  // Seen along v, a flat gripper and its tilt mirror cast the same outline
  // but for perspective (a microscope), or cut the same slice (ultrasound,
  // v the plane's normal): such a frame's orientation error is the tilt's
  // sign, which the image barely holds. A diagnostic; it changes no error.
  bool tilt_mirror = false;
  // The same test of the palm normal (e.m > |e.n|, the truth tilted by more
  // than kMirrorMinTiltDeg), whatever the fold: the estimate is on the other
  // branch of the tilt's sign. For a folded gripper the outline does tell
  // the two apart, but under an occluder or at the image's border little of
  // it is seen. tilt_mirror is this and a flat truth. A diagnostic too.
  bool tilt_branch = false;
  static constexpr double kFlatShare = 0.05;
  static constexpr double kMirrorMinTiltDeg = 3.0;
};

// Compares one estimate with one truth, modulo the model's symmetry.
// `line_of_sight` (any length, either sign) is the sensor's viewing
// direction at the truth's palm centre, for FrameErrors::tilt_mirror;
// `viewing_axis` (unit length) splits the position error into depth and
// in-plane.
GTRACK_API FrameErrors compare_to_truth(const ArticulatedModel& model, const Eigen::VectorXd& truth,
                                        const Eigen::VectorXd& estimate,
                                        const Eigen::Vector3d& line_of_sight = Eigen::Vector3d::UnitZ(),
                                        const Eigen::Vector3d& viewing_axis = Eigen::Vector3d::UnitZ());
// The line of sight of `projection` through the image of `world_mm` (unit
// length; the optical ray of a camera, the plane's normal of a slice).
GTRACK_API Eigen::Vector3d line_of_sight(const Projection& projection, const Eigen::Vector3d& world_mm);
// Angle (deg) of the rotation between two Euler triples (rx, ry, rz in deg).
GTRACK_API double geodesic_angle_deg(const Eigen::Vector3d& euler_a, const Eigen::Vector3d& euler_b);

struct FrameEvaluation {
  int frame = 0;
  double in_view = 1;
  bool out_of_view = false;
  bool has_estimate = false;
  bool lost = false;      // no row, status "lost", or a non-finite estimate
  std::string status;
  FrameErrors errors;     // valid when has_estimate && !lost
};

struct GTRACK_API ErrorSet {
  ErrorStats position_um, position_inplane_um, depth_um, orientation_deg, joint_deg, endpoint_um;
  ErrorStats axis_deg[3];
  void add(const FrameErrors& e);
  void finish();
 private:
  std::vector<double> values_[9];
};

struct RecoveryEpisode {
  int returned_at = 0;        // first frame back in view
  int frames_to_recover = 0;  // frames lost or off track from there on
  bool recovered = false;
};

struct Evaluation {
  EvalOptions options;
  int frames = 0;             // truth frames
  int in_view_frames = 0;
  int out_of_view_frames = 0;
  int evaluated_frames = 0;   // in view, with a usable estimate
  int lost_frames = 0;        // all frames (status lost or missing)
  int lost_in_view_frames = 0;
  int missing_frames = 0;     // no estimate row at all
  int search_frames = 0;      // status "search" (coarse search)
  int off_track_frames = 0;   // in view, estimate present but endpoint error above the threshold
  ErrorSet in_view;           // the headline numbers
  ErrorSet out_of_view;       // frames mostly outside the view that still got an estimate
  // Evaluated frames whose estimate is the tilt mirror of a flat truth
  // (FrameErrors::tilt_mirror), the share of the summed orientation error
  // they carry, and the orientation error of the other evaluated frames.
  int tilt_mirror_frames = 0;
  double tilt_mirror_orientation_share = 0;
  ErrorStats orientation_without_tilt_mirror_deg;
  // Evaluated frames on the other tilt branch, whatever the fold
  // (FrameErrors::tilt_branch), and the share of the summed orientation
  // error they carry.
  int tilt_branch_frames = 0;
  double tilt_branch_orientation_share = 0;
  std::vector<RecoveryEpisode> recovery;
  int frames_lost_after_return = 0;
  std::vector<FrameEvaluation> per_frame;  // in frame order, whatever the truth table's
};

// `sensor` is used only when the truth has no in_view column (may be null:
// then every frame counts as in view).
GTRACK_API Evaluation evaluate(const ArticulatedModel& model, const PoseTable& truth, const PoseTable& estimates,
                               const EvalOptions& options = {}, const Sensor* sensor = nullptr);

// The evaluation as one JSON object (keys as in DESIGN.md, plus the rest).
GTRACK_API std::string evaluation_json(const Evaluation& evaluation);
// Per-frame errors as CSV.
GTRACK_API void write_frame_errors(const std::filesystem::path& file, const Evaluation& evaluation);

}  // namespace gtrack
