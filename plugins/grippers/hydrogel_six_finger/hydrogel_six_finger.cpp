// hydrogel_six_finger: the 4 mm soft gripper of the paper's Fig. 3.
//
// A hexagonal palm with a finger on each edge; each finger is 4 links (three
// trapezoids and a pointed tip), 46 triangles in all, 4.0 mm tip to tip when
// open: apothem 0.65 mm + 0.35 + 0.35 + 0.35 + 0.30 mm = 2.0 mm per side.
// 12 parameters. Unfolded ~0 deg, folded ~60 deg per hinge.
#include <gtrack/gripper_config.hpp>
#include <gtrack/plugin.hpp>

namespace {

gtrack::RadialGripperDefaults hydrogel_defaults() {
  gtrack::RadialGripperDefaults d;
  d.spec.name = "hydrogel_six_finger";
  d.spec.fingers = 6;
  d.spec.palm_sides = 6;
  d.spec.palm_circumradius_mm = 0.65 / 0.8660254037844386;  // apothem 0.65 mm
  d.widths_mm = {0.60, 0.55, 0.50, 0.45, 0.0};
  for (double len : {0.35, 0.35, 0.35, 0.30}) d.spec.links.push_back({len, 0, 0});
  d.joint_min_deg = 0;
  d.joint_max_deg = 80;
  d.max_adjacent_difference_deg = 40;
  d.unfolded_deg = 0;
  d.folded_deg = 60;
  return d;
}

using HydrogelSixFinger = gtrack::RadialGripper<hydrogel_defaults>;

}  // namespace

GTRACK_PLUGIN(HydrogelSixFinger, gtrack::Gripper, "hydrogel_six_finger", "1.0.0",
              "soft hydrogel gripper, 6 fingers x 4 links, 46 triangles, 4 mm tip to tip")
