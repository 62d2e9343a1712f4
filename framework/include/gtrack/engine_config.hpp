// The engine's own config tables, read and validated in one place.
//
// A config names three plugins ([sensor], [gripper], [stimulus]) whose tables
// the plugins read; every other table belongs to the engine: [observation]
// (segmentation), [pso] (Algorithm 1), [cost] (eq. 1 weights), [render]
// (backend and scale), [search] (bounds of the hypothesis space) and
// [tracker] (initial pose, initial spreads, frame rate, lost handling).
// engine_config() reads all of them, with the paper's defaults except for the
// additions docs/tracker.md lists (each can be turned off), and checks
// that each table holds no unknown key (file, line, key, suggestion).
// Defaults that depend on the setup (search box, spreads) are derived from the
// sensor's nominal position and the model's size.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <opencv2/core.hpp>
#include <optional>
#include <string>
#include <vector>

#include "gtrack/config.hpp"
#include "gtrack/export.hpp"
#include "gtrack/parameter_space.hpp"
#include "gtrack/renderer.hpp"

namespace gtrack {

struct Setup;

// Segmentation (paper 2.1) and temporal continuity (paper 3, last paragraph).
struct ObservationConfig {
  std::string color_space = "hsv";  // "hsv" (camera) or "luminance" (ultrasound)
  // HSV bounds in OpenCV units (H in [0, 180), S and V in [0, 255]); the paper
  // bounds S and V only, so H is open by default.
  double hue_min = 0, hue_max = 180;
  double saturation_min = 60, saturation_max = 255;
  double value_min = 0, value_max = 255;
  double luminance_min = 128, luminance_max = 255;
  int open_kernel_px = 3;           // morphological opening, full-resolution pixels; 0 = off
  double downscale_threshold = 0.5; // a render pixel is set when this share of its area is
  bool roi = true;                  // search only around the previous estimate
  double roi_margin_px = 48;        // margin around its projected box, full-resolution pixels
  bool prior = true;                // drop pixels unlikely given the previous model
  double prior_sigma_px = 24;       // full-resolution pixels
  double prior_threshold = 0.05;    // keep p(O_t+1 | P_t) = exp(-d^2 / 2 sigma^2) above this
  // Full-resolution rectangles never observed: what the recording burns
  // into every frame (a scale bar, a time stamp, a scanner's text, ruler
  // and caliper marks).
  std::vector<cv::Rect> exclude_px;
};

struct PsoConfig {
  int particles = 32;              // N
  int generations = 25;            // G
  double inertia = 0.4;            // w
  double c = 1.0;                  // C of the rank-adaptive coefficients
  int randomize_every = 8;         // k_r; 0 = never
  double randomize_fraction = 0.25;  // share of the swarm partially randomised
  double max_velocity_fraction = 0.5;  // |v_d| <= this * (upper_d - lower_d); 0 = no clamp
  std::uint64_t seed = 1;
};

struct CostWeights {
  double dice = 2.0;        // lambda_D
  double kinematic = 0.15;  // lambda_K
  double stimulus = 1.0;    // lambda_S
  // lambda_T: weight of the temporal term T, the mean squared distance of a
  // hypothesis's pose to the constant-velocity prediction in units of
  // [tracker] init_spread (a diagonal Mahalanobis distance over the six pose
  // parameters, and the joints with temporal_joint_sigma_deg below). A
  // tie-breaker: under occlusion many poses explain O equally well. With
  // lambda_T > 0, particle 1 of the swarm also starts at the prediction.
  // 0 = paper.
  double temporal = 0.001;
  // The joints' scale in T (deg): > 0 adds the joints to T, each against the
  // prediction's joint (the middle of the range the stimulus allows now, or
  // the last estimate's without a stimulus) in units of this value. Near
  // flat a finger's outline barely changes with its fold (cos q), so the
  // image leaves the joints free within a few degrees and the swarm ends
  // anywhere there; this ties them to what the stimulus expects. 0 = the
  // joints are left out of T.
  double temporal_joint_sigma_deg = 3.0;
  // lambda_C: weight of the joint-coherence term C, the mean squared
  // deviation of the fingers' joints from their mean, in units of
  // coherence_sigma_deg. The fingers share one stimulus and one material,
  // so they fold alike; under an occluder the image leaves the hidden
  // fingers' joints free, and a configuration that bends them apart to fit
  // what is visible otherwise costs no more than the truth. 0 = paper (the
  // default); the metallic grippers' configs set 0.003 (docs/tracker.md).
  double coherence = 0.0;
  double coherence_sigma_deg = 10.0;
  // occlusion_discount in [0, 1]: when |O| falls below the area of the model
  // rendered at the previous estimate (ratio r < 1), rendered pixels outside
  // O are weighted w = 1 - occlusion_discount * (1 - r) in D (see cost.hpp).
  // 0 = paper (w = 1 always).
  double occlusion_discount = 0.0;
  // occlusion_budget b >= 0: when the observation is smaller than the model
  // rendered at the previous estimate, P\O pixels up to b * (|P_prev| - |O|)
  // (+ occlusion_tolerance * |P_prev|) are taken as hidden and not counted
  // in D (see cost.hpp). 0 = paper's D.
  double occlusion_budget = 1.0;
  // The share of |P_prev| by which O may fall short of the model before any
  // of it is taken as hidden, and the slack added to the allowance then.
  double occlusion_tolerance = 0.05;
  // occlusion_growth_weight in [0, 1]: the weight in D of the P\O pixels in
  // that slack (beyond b * (|P_prev| - |O|), up to the tolerance). At 0 a
  // hypothesis may be larger than the previous model by the slack for free;
  // the next frame's allowance, taken from that larger model, lets it grow
  // again, so under a long occlusion the model ratchets up.
  double occlusion_growth_weight = 0.1;
  // occlusion_rim_px >= 0: rendered pixels outside O but within this many
  // render pixels of it (the rim) are never taken as hidden. An occluder
  // hides a part that continues the gripper, so the true configuration's
  // spill crosses the rim only along the occluder's edge; a model placed
  // loosely around the visible part spills along the whole outline and
  // pays for it. 0 = the budget alone. In render pixels: 3 at the default
  // render scale 1/2 is 6 image pixels (docs/tracker.md, "Render scale and
  // the rim's width").
  int occlusion_rim_px = 3;
};

// The search's bounds, like the hypotheses the tracker searches and
// TrackerConfig::initial_pose, are in the sensor's own frame (SensorFrame in
// sensor.hpp: rx, ry tilt away from face-on, rz turns about the line of
// sight), which for a sensor looking down world z is the world's. The config
// gives positions in the world, angles in the sensor's frame. For a turned
// sensor given a position box, the bounds below are the box about its
// corners in the sensor's frame, and `world_box` (ParameterSpace's
// position_box) keeps the positions searched within the world's box.
struct SearchConfig {
  Eigen::Vector3d position_min_mm{0, 0, 0}, position_max_mm{0, 0, 0};
  Eigen::Vector3d rotation_min_deg{-90, -90, -180}, rotation_max_deg{90, 90, 180};
  std::optional<ParameterSpace::PositionBox> world_box;
};

struct TrackerConfig {
  std::optional<Eigen::VectorXd> initial_pose;  // none: coarse search on the first frame
  // Half-widths of the uniform perturbation of the previous best:
  // x, y, z (mm), rx, ry, rz (deg), joints (deg).
  Eigen::Matrix<double, 7, 1> init_spread = Eigen::Matrix<double, 7, 1>::Zero();
  double fps = 0;                        // 0: from the video, else 30
  // Significant bits of 16-bit input images (12 for a 12-bit camera that
  // stores its values in the low bits): scaled to 8 bits by 255 / (2^bits - 1).
  int image_bits = 16;
  std::optional<double> default_stimulus;  // used when no stimulus log is given
  double lost_dice = 0.95;               // best D above this: the gripper is not where we think
  int reinit_after_lost = 3;             // lost frames before the coarse search takes over
  int coarse_rz_steps = 12;              // rz hypotheses over one symmetry period
  int coarse_candidates = 4;             // best coarse hypotheses refined by a PSO each
  bool coarse_wide_tilts = true;         // the coarse grid also tries 50 deg tilts (x, y, diagonals)
  // Where O touches the image's border, each coarse grid point is also tried
  // moved out across it by 1..n steps of 0.3 model radii (a gripper coming
  // into view shows a sliver of itself; docs/tracker.md). 0 = off.
  int coarse_border_steps = 3;
  // Re-detection: when the tracked estimate's D is above this, the coarse
  // search and a wide swarm also run on the frame, and their result replaces
  // the track on a clear gain (docs/tracker.md); it pulls a track that
  // settled in a wrong basin back once the gripper is clearly seen.
  // 1 = never (the paper's tracker).
  double redetect_dice = 0.01;
  // Re-detection's tilt directions: n >= 2 adds n - 1 short CMA-ES searches
  // started from the track with its tilt (rx, ry) turned by 360/n, 2 x 360/n,
  // ... degrees (docs/tracker.md, re-detection); 0 or 1 = none.
  int redetect_tilt_directions = 0;
  bool mirror_check = true;              // refine the tilt mirror of a tilted (> 3 deg) result, keep the lower
  int mirror_particles = 2;              // particles started at the mirror tilt (-rx, -ry); 0 = paper's plain init
  // Refinement: after the swarm (and any re-detection or mirror check), a
  // second search of [pso] N samples and G generations starts around the
  // result with the spreads times this; the lower of the two is kept.
  // 0 = none (the paper's tracker).
  double refine_spread = 0.25;
  // The refinement's optimiser: "cmaes" (CMA-ES, its first samples with a
  // standard deviation of refine_spread / sqrt(3) spreads) or "pso" (a swarm
  // initialised uniformly within refine_spread spreads, the previous
  // release's refinement).
  std::string refine_optimizer = "cmaes";
  // Unseen fingers (docs/tracker.md): a finger whose joint can be moved to
  // the other fingers' mean for at most this much cost E is one the image
  // does not see; the estimate reports such fingers at the mean fold of the
  // seen ones when that costs at most this much too (the track itself goes
  // on from the search's result). 0 = off (the paper's tracker).
  double unseen_joint_tolerance = 0.001;
  // With --two-pass: the standard deviation, in frames of the table, of the
  // Gaussian kernel the two-pass table's orientations are averaged with
  // (docs/tracker.md, "Two passes over a recording"). 0 = none.
  double two_pass_smoothing = 1.5;
  int progress_every = 50;               // frames between progress lines when stderr is not a terminal
  bool overlay = true;                   // write overlay.mp4
};

struct EngineConfig {
  ObservationConfig observation;
  PsoConfig pso;
  CostWeights cost;
  RenderOptions render;
  SearchConfig search;
  TrackerConfig tracker;
  ParameterSpace space;  // from [search] and the gripper's joint limits
};

// Reads [observation], [pso], [cost], [render], [search], [tracker] from the
// setup's root table (defaults from the sensor and the model), checks every
// key of those tables, marks them used on the root. Throws ConfigError.
GTRACK_API EngineConfig engine_config(const Setup& setup);

// [observation] color_space: "hsv" or "luminance", by default the sensor's
// (hsv unless it says luminance). `gtrack synth` draws frames of that look.
GTRACK_API std::string observation_color_space(const ConfigTable& observation, const Sensor& sensor);
// [tracker] fps: 0 (the source's rate) or a rate from 0.001 to 10^6 frames/s.
GTRACK_API double tracker_fps(const ConfigTable& tracker);

// After engine_config(): every root key that neither the plugins nor the
// engine read is an error (e.g. a misspelled table name).
GTRACK_API void check_root_keys(const Setup& setup);

}  // namespace gtrack
