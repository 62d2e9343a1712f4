// The table of synthetic setups. A new setup (another gripper, another
// sensor) is one more entry here and, if it needs one, a config in configs/.
#include <algorithm>

#include "gtrack/error.hpp"
#include "gtrack/synth.hpp"

namespace gtrack {

namespace {

SynthPreset microscope() {
  SynthPreset p;
  p.name = "microscope";
  p.summary = "4 mm hydrogel gripper under a 1024x1024 microscope camera, ~8 um/px, on tissue";
  p.config = "microscope_hydrogel.toml";
  // Everything else is the struct's defaults, which were chosen for this
  // setup: the gripper's orange at S = 105 sits far enough above the default
  // segmentation bound (S >= 60) for noise and jitter, while a half-covered
  // edge pixel (gripper mixed with tissue) lands near that bound, so the
  // segmented outline is not biased outwards by anti-aliasing or blur.
  return p;
}

// The metallic grippers are a quarter of the hydrogel's size or less: the
// field of view of their configs is scaled to match (2 and 1.6 mm across), so
// the motion, set in fractions of the view, scales with it; depth and the
// temperature profile are their own: they fold once past 37 C and stay folded.
SynthPreset metallic(const char* name, const char* config, const char* summary, double depth_mm) {
  SynthPreset p;
  p.name = name;
  p.summary = summary;
  p.config = config;
  p.depth_amplitude_mm = depth_mm;
  p.stimulus_low = 30;
  p.stimulus_high = 40;
  p.stimulus_period_s = 10;
  p.gripper_hsv = {20, 90, 215};  // gold
  return p;
}

// The microscope's setup in bright field: a dark grey gripper on a light,
// grey background, segmented by grey level (luminance 0 to 120).
SynthPreset brightfield() {
  SynthPreset p = microscope();
  p.name = "brightfield";
  p.summary = "4 mm hydrogel gripper, dark, under a 1024x1024 bright-field microscope, ~8 um/px, on a light background";
  p.config = "microscope_hydrogel_brightfield.toml";
  p.gripper_hsv = {0, 0, 45};
  p.tissue_hsv = {0, 0, 195};
  return p;
}

// B-mode ultrasound: grey levels only, a bright gripper on darker speckled
// tissue, slow in-plane motion, small tilts and an elevational drift that
// takes parts of the gripper out of the imaged slab.
SynthPreset ultrasound() {
  SynthPreset p;
  p.name = "ultrasound";
  p.summary = "4 mm hydrogel gripper in a 1024x662 B-mode slice, 0.09 mm/px, speckled moving tissue";
  p.config = "ultrasound_hydrogel.toml";
  p.inplane_amplitude = 0.35;
  p.depth_amplitude_mm = 0.25;  // elevation: out of the imaging plane
  p.tilt_amplitude_deg = 15;
  p.spin_deg_per_s = 15;
  p.exits_per_minute = 0;
  p.occluded_frames = 0.3;
  p.max_occlusion = 0.4;
  p.gripper_hsv = {0, 0, 235};
  p.tissue_hsv = {0, 0, 55};
  p.tissue_contrast = 0.3;
  p.noise_sigma = 10;  // speckle-like grain
  p.blur_sigma_px = 1.0;
  p.defocus_px_per_mm = 0;
  return p;
}

}  // namespace

const std::vector<SynthPreset>& synth_presets() {
  static const std::vector<SynthPreset> presets = {
      microscope(),
      metallic("metallic_six", "microscope_metallic_six.toml",
               "0.9 mm six-finger metallic gripper, microscope 2 mm across (~2 um/px)", 0.1),
      metallic("metallic_two", "microscope_metallic_two.toml",
               "0.75 mm two-finger metallic gripper, microscope 1.6 mm across (~1.6 um/px)", 0.08),
      ultrasound(),
      brightfield()};
  return presets;
}

const SynthPreset& synth_preset(const std::string& name) {
  const auto& all = synth_presets();
  auto it = std::find_if(all.begin(), all.end(), [&](const SynthPreset& p) { return p.name == name; });
  if (it != all.end()) return *it;
  throw Error("unknown synthetic preset '" + name + "'; presets are: " + synth_preset_names());
}

std::string synth_preset_names() {
  std::string names;
  for (const auto& p : synth_presets()) names += (names.empty() ? "" : ", ") + p.name;
  return names;
}

}  // namespace gtrack
