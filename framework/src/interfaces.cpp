// Out-of-line virtual destructors and defaults of the plugin interfaces, so
// that their vtables and type_info live in the framework library.
#include "gtrack/gripper.hpp"
#include "gtrack/sensor.hpp"
#include "gtrack/stimulus.hpp"

namespace gtrack {

Sensor::~Sensor() = default;
cv::Mat Sensor::rectify(const cv::Mat& frame) const { return frame; }
SegmentationDefaults Sensor::segmentation_defaults() const { return {}; }

Gripper::~Gripper() = default;
double Gripper::kinematic_penalty(std::span<const double> joints_deg) const {
  return model().kinematic_penalty(joints_deg);
}

Stimulus::~Stimulus() = default;
std::string Stimulus::reading_label() const { return "S"; }
std::string Stimulus::reading_unit() const { return ""; }

}  // namespace gtrack
