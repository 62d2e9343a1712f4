// Which synthetic preset draws frames a config can track: shared by
// gtrack synth and gtrack sweep, which both make sequences from a config.
#include <algorithm>
#include <fmt/format.h>

#include "command.hpp"
#include "gtrack/config.hpp"
#include "gtrack/log.hpp"
#include "gtrack/synth.hpp"

namespace {

// Whether an HSV colour (OpenCV units) is within the bounds; a grey one by
// its luminance (its value) for grey-level bounds.
bool within(const cv::Vec3d& hsv, const gtrack::ObservationConfig& o) {
  if (o.color_space == "luminance") return hsv[2] >= o.luminance_min && hsv[2] <= o.luminance_max;
  const bool hue = o.hue_min <= o.hue_max ? hsv[0] >= o.hue_min && hsv[0] <= o.hue_max
                                          : hsv[0] >= o.hue_min || hsv[0] <= o.hue_max;
  return hue && hsv[1] >= o.saturation_min && hsv[1] <= o.saturation_max && hsv[2] >= o.value_min &&
         hsv[2] <= o.value_max;
}

// A preset's frames are ones the bounds find the gripper in, and not its
// background.
bool look_fits(const gtrack::SynthPreset& p, const gtrack::ObservationConfig& o) {
  return within(p.gripper_hsv, o) && !within(p.tissue_hsv, o);
}

std::string look_text(const cv::Vec3d& hsv, bool grey) {
  return grey ? fmt::format("luminance {:g}", hsv[2])
              : fmt::format("hue {:g}, saturation {:g}, value {:g}", hsv[0], hsv[1], hsv[2]);
}

}  // namespace

namespace gtrack::cli {

std::string synth_preset_for(const boost::program_options::variables_map& vm, const std::filesystem::path& config,
                             const gtrack::Setup& setup, const gtrack::ObservationConfig& bounds) {
  std::string preset = vm["preset"].as<std::string>();
  // A config given without --preset: the preset whose config it is, else
  // the one whose config names the same gripper plugin (a lab's own copy
  // of a shipped config), else one whose look the config's bounds find: an
  // ultrasound slice's for a slab sensor, else the first in the table
  // (colour microscope frames; for grey-level bounds, a bright gripper on
  // dark speckle or a dark one in bright field, as the bounds say), so that
  // the frames are ones the config can track.
  const bool grey_look = bounds.color_space == "luminance";
  const auto grey = [](const gtrack::SynthPreset& p) { return p.gripper_hsv[1] == 0; };
  const auto fits = [&](const gtrack::SynthPreset& p) { return grey(p) == grey_look && look_fits(p, bounds); };
  if (vm.count("config") && vm["preset"].defaulted()) {
    const auto& all = gtrack::synth_presets();
    const auto gripper_of = [](const gtrack::ConfigTable& root) {
      return root.table("gripper").string_or("plugin", "");
    };
    const std::string gripper = gripper_of(setup.root);
    const auto same = std::find_if(all.begin(), all.end(), [&](const auto& p) {
      return p.config == config.filename() && fits(p);
    });
    const auto same_gripper = std::find_if(all.begin(), all.end(), [&](const auto& p) {
      return fits(p) &&
             gripper_of(gtrack::ConfigTable::load_file((gtrack::data_dir() / "configs" / p.config).string())) ==
                 gripper;
    });
    const bool slab = gtrack::cli::images_a_slab(*setup.sensor);
    const auto any = std::find_if(all.begin(), all.end(), [&](const auto& p) {
      return fits(p) && (!slab || p.name == "ultrasound");
    });
    preset = same != all.end()           ? same->name
               : same_gripper != all.end() ? same_gripper->name
               : any != all.end()          ? any->name
               : grey_look                 ? "ultrasound"
                                           : "microscope";
  }
  const gtrack::SynthPreset& chosen = gtrack::synth_preset(preset);
  if (const bool grey_frames = grey(chosen); grey_frames != grey_look) {
    gtrack::logger().warn("--preset {} draws {} frames, but {} segments {}: its config will not find the "
                          "gripper in them (leave --preset out to take one it can)",
                          preset, grey_frames ? "grey-level" : "colour", config.string(),
                          grey_look ? "grey levels" : "colour");
  } else if (!look_fits(chosen, bounds)) {
    gtrack::logger().warn("--preset {} draws its gripper at {}, its background at {}, but the [observation] bounds "
                          "of {} do not take the one without the other: its config will not track the frames{}",
                          preset, look_text(chosen.gripper_hsv, grey_look), look_text(chosen.tissue_hsv, grey_look),
                          config.string(),
                          vm["preset"].defaulted() ? " (no preset draws what they look for)"
                                                   : " (leave --preset out to take one it can)");
  }
  return preset;
}

}  // namespace gtrack::cli
