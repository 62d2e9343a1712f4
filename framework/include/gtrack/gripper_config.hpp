// Reading the common keys of a radial gripper's config table.
//
// The built-in grippers are radial (identical fingers on the edges of a
// regular palm); each ships its paper dimensions as defaults and lets a lab
// override them from its [gripper] table with the same keys:
//   palm_circumradius_mm, link_lengths_mm, link_widths_mm (one more than
//   links: width at each hinge and at the tip), joint_min_deg, joint_max_deg,
//   max_adjacent_difference_deg, max_adjacent_sum_deg, unfolded_deg, folded_deg.
#pragma once

#include "gtrack/config.hpp"
#include "gtrack/export.hpp"
#include "gtrack/gripper.hpp"
#include "gtrack/model.hpp"

namespace gtrack {

struct RadialGripperDefaults {
  RadialGripperSpec spec;
  std::vector<double> widths_mm;  // links + 1 values
  double joint_min_deg = 0;
  double joint_max_deg = 90;
  double max_adjacent_difference_deg = 45;
  double max_adjacent_sum_deg = 1e9;
  double unfolded_deg = 0;
  double folded_deg = 60;
};

// The links of a finger from link_lengths_mm and link_widths_mm (the width
// at each hinge and at the tip, one more than the lengths): a link 0 wide
// at both ends fails on link_widths_mm, naming the link.
GTRACK_API std::vector<LinkShape> links_from_config(const ConfigTable& table, const std::vector<double>& lengths,
                                                    const std::vector<double>& widths);

GTRACK_API GripperGeometry radial_gripper_from_config(const ConfigTable& table, RadialGripperDefaults defaults);

// A radial gripper plugin is its defaults: RadialGripper<my_defaults> reads
// the keys above over them.
//     gtrack::RadialGripperDefaults my_defaults() { ... }
//     using MyGripper = gtrack::RadialGripper<my_defaults>;
//     GTRACK_PLUGIN(MyGripper, gtrack::Gripper, "my_gripper", "1.0.0", "...")
template <RadialGripperDefaults (*Defaults)()>
class RadialGripper final : public Gripper {
 public:
  explicit RadialGripper(const ConfigTable& table) : model_(radial_gripper_from_config(table, Defaults())) {}
  const ArticulatedModel& model() const override { return model_; }

 private:
  ArticulatedModel model_;
};

}  // namespace gtrack
