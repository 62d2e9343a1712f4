// Drawing an estimate on its frame, as in the paper's figures: the model in
// green over the input and the stimulus reading in the bottom-right corner.
#pragma once

#include <opencv2/core.hpp>
#include <string>

#include "gtrack/model.hpp"
#include "gtrack/sensor.hpp"
#include "gtrack/stimulus.hpp"
#include "gtrack/tracker.hpp"

namespace gtrack::detail {

// "T = 36.5 C": the estimate's stimulus reading as the plugin names it ("" when none).
std::string reading_text(const Stimulus* stimulus, const Estimate& estimate);

// `reading`: written in the bottom-right corner (reading_text). Only const
// calls: it may run on a thread of its own while the tracker works (the
// sensor's project(), the model's pose()).
cv::Mat draw_estimate(const cv::Mat& frame, const Sensor& sensor, const ArticulatedModel& model,
                      const std::string& reading, const Estimate& estimate);

}  // namespace gtrack::detail
