// metallic_six_finger: the 900 um chromium/gold/nickel gripper (paper Fig. 5c-d).
//
// A hexagonal palm with a finger on each edge, each finger 3 links (two
// trapezoids and a pointed tip), 34 triangles, 0.9 mm tip to tip when open:
// apothem 0.18 mm + 3 x 0.09 mm = 0.45 mm per side. 12 parameters. The
// hinges are pre-stressed: once the trigger polymer softens (37 C) each
// folds to about 70 deg; see configs/microscope_metallic_six.toml.
#include <gtrack/gripper_config.hpp>
#include <gtrack/plugin.hpp>

namespace {

gtrack::RadialGripperDefaults metallic_six_defaults() {
  gtrack::RadialGripperDefaults d;
  d.spec.name = "metallic_six_finger";
  d.spec.fingers = 6;
  d.spec.palm_sides = 6;
  d.spec.palm_circumradius_mm = 0.18 / 0.8660254037844386;
  d.widths_mm = {0.16, 0.13, 0.10, 0.0};
  for (double len : {0.09, 0.09, 0.09}) d.spec.links.push_back({len, 0, 0});
  d.joint_min_deg = 0;
  d.joint_max_deg = 90;
  d.max_adjacent_difference_deg = 45;
  d.unfolded_deg = 0;
  d.folded_deg = 70;
  return d;
}

using MetallicSixFinger = gtrack::RadialGripper<metallic_six_defaults>;

}  // namespace

GTRACK_PLUGIN(MetallicSixFinger, gtrack::Gripper, "metallic_six_finger", "1.0.0",
              "metallic gripper, 6 fingers x 3 links, 0.9 mm tip to tip")
