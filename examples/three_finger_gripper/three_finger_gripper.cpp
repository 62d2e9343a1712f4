// three_finger_gripper: a compiled gripper plugin from outside the gtrack tree.
//
// A triangular palm with one three-link finger per edge; open, its tips lie
// on a circle 2 mm across (1.73 mm from one tip to the next).
// Dimensions can be overridden from the [gripper] table with the keys every
// radial gripper understands (see docs/plugins.md).
#include <gtrack/gripper_config.hpp>
#include <gtrack/plugin.hpp>

namespace {

gtrack::RadialGripperDefaults three_finger_defaults() {
  gtrack::RadialGripperDefaults d;
  d.spec.name = "three_finger_gripper";
  d.spec.fingers = 3;
  d.spec.palm_sides = 3;
  d.spec.palm_circumradius_mm = 0.5;  // apothem 0.25 mm
  d.widths_mm = {0.40, 0.34, 0.28, 0.0};
  for (double len : {0.3, 0.25, 0.2}) d.spec.links.push_back({len, 0, 0});
  d.joint_min_deg = 0;
  d.joint_max_deg = 80;
  d.max_adjacent_difference_deg = 45;
  d.folded_deg = 50;
  return d;
}

using ThreeFingerGripper = gtrack::RadialGripper<three_finger_defaults>;

}  // namespace

GTRACK_PLUGIN(ThreeFingerGripper, gtrack::Gripper, "three_finger_gripper", "0.1.0",
              "example: triangular palm, 3 fingers x 3 links, tips on a 2 mm circle")
