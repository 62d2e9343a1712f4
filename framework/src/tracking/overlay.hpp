// Drawing an estimate on its frame, as in the paper's figures: the model in
// green over the input and the stimulus reading in the bottom-right corner.
#pragma once

#include <opencv2/core.hpp>

#include "gtrack/model.hpp"
#include "gtrack/sensor.hpp"
#include "gtrack/stimulus.hpp"
#include "gtrack/tracker.hpp"

namespace gtrack::detail {

cv::Mat draw_estimate(const cv::Mat& frame, const Sensor& sensor, const ArticulatedModel& model,
                      const Stimulus* stimulus, const Estimate& estimate);

}  // namespace gtrack::detail
