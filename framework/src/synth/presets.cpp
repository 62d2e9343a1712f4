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

}  // namespace

const std::vector<SynthPreset>& synth_presets() {
  static const std::vector<SynthPreset> presets = {microscope()};
  return presets;
}

const SynthPreset& synth_preset(const std::string& name) {
  const auto& all = synth_presets();
  auto it = std::find_if(all.begin(), all.end(), [&](const SynthPreset& p) { return p.name == name; });
  if (it != all.end()) return *it;
  std::string names;
  for (const auto& p : all) names += (names.empty() ? "" : ", ") + p.name;
  throw Error("unknown synthetic preset '" + name + "'; presets are: " + names);
}

}  // namespace gtrack
