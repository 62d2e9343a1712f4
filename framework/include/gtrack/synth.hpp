// Synthetic sequences with ground truth (paper Section 5.1).
//
// A synthetic sequence is planned first and drawn second. The plan
// (plan_sequence) fixes, for every frame, the true hypothesis (smooth
// in-plane motion with excursions outside the field of view, slow depth
// changes, rotation about all three axes with large out-of-plane tilts,
// joints that follow a temperature log through the Stimulus plugin's
// hysteresis with a first-order lag), the stimulus reading and the
// occluder. Drawing (render_frame) turns a planned frame into the image a
// sensor would deliver: a tissue-like background, the gripper in a colour the
// default segmentation accepts, anti-aliased at full resolution, an opaque
// occluder in colours the segmentation rejects, defocus blur, colour jitter
// and sensor noise. Everything random comes from the seed, so a seed gives
// the same sequence on every machine.
//
// What varies between setups (motion ranges, temperature profile, colours,
// noise) is a SynthPreset; synth_presets() is the table of them, so a new
// setup is a new entry there.
#pragma once

#include <optional>

#include <Eigen/Core>
#include <cstdint>
#include <filesystem>
#include <limits>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "gtrack/export.hpp"
#include "gtrack/setup.hpp"

namespace gtrack {

// Colours are HSV in OpenCV units (H in [0, 180), S and V in [0, 255]).
struct SynthPreset {
  std::string name;
  std::string summary;
  std::string config;  // file in data_dir()/configs used when no config is given
  double frame_rate_hz = 30;

  // Motion. In-plane amplitudes are fractions of the room the field of view
  // leaves around the gripper (half the view minus the gripper's radius);
  // the depth amplitude is in mm ([synth] depth_amplitude_mm may set it).
  double inplane_amplitude = 0.8;
  double depth_amplitude_mm = 0.4;
  double tilt_amplitude_deg = 50;       // peak of rx and ry
  double spin_deg_per_s = 25;           // typical rate of rz
  double motion_period_s = 8;           // slowest component of the smooth paths
  double exits_per_minute = 12;         // excursions out of the field of view
  double exit_depth = 1.15;             // how far out: 1 = the model's edge touches the border

  // Stimulus (temperature) profile and the joints' response. The config's
  // [synth] table may set the profile (stimulus_low, stimulus_high,
  // stimulus_period_s, stimulus_noise) in its stimulus plugin's units.
  double stimulus_low = 22, stimulus_high = 30;
  double stimulus_period_s = 7;
  double stimulus_noise = 0.03;         // reading noise, stimulus units
  double joint_lag_s = 0.35;            // first-order lag of the material
  double joint_lag_spread = 0.25;       // relative spread of the lag between fingers

  // Occlusion.
  double occluded_frames = 0.7;         // share of frames with an occluder on the gripper
  double max_occlusion = 0.8;           // largest share of the visible shape covered

  // Appearance.
  cv::Vec3d gripper_hsv{18, 105, 205};
  cv::Vec3d tissue_hsv{4, 16, 188};
  double tissue_contrast = 0.12;        // relative spread of the background's value
  double noise_sigma = 2.5;             // sensor noise, grey levels
  double blur_sigma_px = 0.7;           // in focus
  double defocus_px_per_mm = 1.5;       // extra blur per mm away from the focal plane
  double colour_jitter = 0.02;          // per-frame relative gain spread per channel
};

GTRACK_API const std::vector<SynthPreset>& synth_presets();
// Their names, "microscope, ...", in the table's order.
GTRACK_API std::string synth_preset_names();
// Throws Error listing the presets when `name` is not one.
GTRACK_API const SynthPreset& synth_preset(const std::string& name);

struct SynthOptions {
  int frames = 300;
  std::uint64_t seed = 1;
  std::string preset = "microscope";
  // Fig. 6b: every hinge gets its own Gaussian deviation (sd, degrees) from
  // the finger's joint value, drawn anew per frame; the ground truth keeps
  // the finger's value.
  double joint_noise_deg = 0;
  // Multiplies every occluder's planned share of the shape, in [0, 1]; 0
  // draws no occluders. The occluders are planned as at 1, so the motion,
  // the fold, the stimulus and the noise of a seed stay the same: the same
  // sequence with smaller occluders, or none.
  double occlusion_scale = 1;
  int threads = 0;  // frames drawn in parallel; 0 = hardware concurrency
  // A lab's own stimulus log (StimulusLog: frame- or time-keyed, its
  // `stimulus_column` of several) drives the material in place of the
  // preset's profile: each frame takes the log's reading at its time (the
  // nearest row's past the log's ends, warned about). A log none of whose
  // rows falls within the frames is refused. The rest of the seed's
  // sequence (motion, occluders, look) stays the same.
  std::optional<std::filesystem::path> stimulus_log;
  std::string stimulus_column;
  // A time_s log on another clock: its time at the first frame
  // (StimulusLog::shift_time; --stimulus-offset, as for tracking).
  double stimulus_offset_s = 0;
};

struct OccluderPlan {
  bool active = false;
  Eigen::Vector2d offset_px{0, 0};  // centre relative to the gripper's image centre
  double target = 0;                // share of the in-view shape to cover
  double shape_phase = 0;           // seeds the blob's outline
  bool tissue_coloured = true;      // else a pale debris colour
};

struct SynthFrame {
  int frame = 0;
  double time_s = 0;
  Eigen::VectorXd truth;            // x,y,z (mm), rx,ry,rz (deg), q1..qF (deg)
  std::vector<double> hinge_deg;    // per finger per link: the angle each hinge folds by
  double stimulus = 0;
  OccluderPlan occluder;
};

struct SynthPlan {
  SynthPreset preset;
  SynthOptions options;
  std::vector<SynthFrame> frames;
  // The sensor's lens distortion, applied to every frame drawn with the
  // linear projection (a cv::remap map; empty: none).
  cv::Mat lens_map;
};

// What was drawn: shares of the gripper's full shape (at full resolution).
struct SynthVisibility {
  double in_view = 0;   // inside the image
  double occluded = 0;  // of the in-view part, covered by the occluder
  double visible = 0;   // in view and not covered
};

GTRACK_API SynthPlan plan_sequence(const Setup& setup, const SynthOptions& options);

// Draws one planned frame (BGR, the sensor's image size).
GTRACK_API cv::Mat render_frame(const Setup& setup, const SynthPlan& plan, int index, SynthVisibility* visibility);

struct SynthSummary {
  int frames = 0;
  int occluded_frames = 0;      // occluder covers more than 1% of the in-view shape
  int partly_out_frames = 0;    // 10% to 99% in view (as gtrack eval counts them)
  int out_of_view_frames = 0;   // less than 10% in view
  double mean_occlusion = 0;    // over occluded frames
  double max_occlusion = 0;
  double seconds = 0;            // to plan, draw and write
  double duration_s = 0;         // of the sequence, at the preset's frame rate
  double stimulus_low = 0, stimulus_high = 0;  // the profile's range, as planned
  double stimulus_min = 0, stimulus_max = 0;   // the readings' range over the frames written
  double joint_min_deg = std::numeric_limits<double>::infinity();   // over fingers and frames
  double joint_max_deg = -std::numeric_limits<double>::infinity();
  std::filesystem::path sequence_config;
};

// Plans and draws a sequence into `out`: frames/NNNNNN.png, stimulus.csv,
// ground_truth.csv, sequence.toml (a config that tracks it, see
// write_sequence_config). Creates the folder; InputError if it cannot.
GTRACK_API SynthSummary write_synthetic_sequence(const Setup& setup, const SynthOptions& options,
                                                 const std::filesystem::path& out);

// A config for tracking a synthetic sequence: every table of `config`
// (plugin tables as they are, but for relative paths made absolute: those
// the plugins read through ConfigTable::file_path(), and those in keys
// ending in "_file", such as a gripper's model_file; plugin_path made
// absolute, with `plugin_paths`, the folders given on the command line,
// first) plus the engine settings the sequence needs (its frame rate).
// Nothing about the truth goes in: the tracker starts from its coarse search.
GTRACK_API void write_sequence_config(const ConfigTable& config, const SynthPlan& plan,
                                      const std::filesystem::path& out_file,
                                      const std::vector<std::filesystem::path>& plugin_paths = {});
// The same for a config file, read again: no plugin has read it, so only
// the relative paths in keys ending in "_file" are made absolute.
GTRACK_API void write_sequence_config(const std::filesystem::path& input_config, const SynthPlan& plan,
                                      const std::filesystem::path& out_file,
                                      const std::vector<std::filesystem::path>& plugin_paths = {});

}  // namespace gtrack
