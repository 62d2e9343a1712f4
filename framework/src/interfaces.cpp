// Out-of-line virtual destructors and defaults of the plugin interfaces, so
// that their vtables and type_info live in the framework library.
#include "gtrack/gripper.hpp"
#include "gtrack/sensor.hpp"
#include "gtrack/stimulus.hpp"

namespace gtrack {

Sensor::~Sensor() = default;
cv::Mat Sensor::rectify(const cv::Mat& frame) const { return frame; }

Eigen::Vector2d pixel_size_mm(const Sensor& sensor) {
  const double s = sensor.mm_per_pixel();
  const Projection p = sensor.projection();
  const bool affine = p.world_to_image.row(2).head<3>().isZero() && p.world_to_image(2, 3) != 0;
  if (!affine) return {s, s};
  const double across = p.world_to_image.row(0).head<3>().norm(), down = p.world_to_image.row(1).head<3>().norm();
  const double ratio = down > 0 ? across / down : 1.0;
  return {s, std::abs(ratio - 1) < 1e-9 ? s : s * ratio};  // square pixels stay exactly so
}
SegmentationDefaults Sensor::segmentation_defaults() const { return {}; }

Gripper::~Gripper() = default;
double Gripper::kinematic_penalty(std::span<const double> joints_deg) const {
  return model().kinematic_penalty(joints_deg);
}

Stimulus::~Stimulus() = default;
std::string Stimulus::reading_label() const { return "S"; }
std::string Stimulus::reading_unit() const { return ""; }

}  // namespace gtrack
