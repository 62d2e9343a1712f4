// OpenCvBaseline: byte masks, cv::fillConvexPoly, bitwise ops, countNonZero.
#include "render/opencv_baseline.hpp"

#include <opencv2/imgproc.hpp>
#include <string>

#include "gtrack/bench.hpp"
#include "gtrack/error.hpp"

namespace gtrack {

namespace render {

namespace {
constexpr int kShift = 8;  // cv::fillConvexPoly's sub-pixel bits
}

OpenCvBaseline::OpenCvBaseline(const RenderOptions& options) : pool_(options.threads), scratch_(pool_.size()) {}

void OpenCvBaseline::set_model(const ArticulatedModel& model) { model_ = std::make_unique<ArticulatedModel>(model); }

void OpenCvBaseline::set_projection(const Projection& projection, double scale) {
  projection_ = scaled_projection(projection, scale);
  const ImageSize s = projection_.size;
  observation_ = cv::Mat(s.height, s.width, CV_8UC1, cv::Scalar(0));
  observation_count_ = 0;
  rim_.release();
  for (Scratch& sc : scratch_) sc.mask = cv::Mat(s.height, s.width, CV_8UC1, cv::Scalar(0));
  has_projection_ = true;
}

void OpenCvBaseline::set_observation(const cv::Mat& mask) {
  if (!has_projection_) throw Error("opencv baseline: set_projection() must come before set_observation()");
  const ImageSize s = projection_.size;
  if (mask.type() != CV_8UC1 || mask.cols != s.width || mask.rows != s.height) {
    throw Error("opencv baseline: the observation must be CV_8U at the render size " + std::to_string(s.width) +
                "x" + std::to_string(s.height));
  }
  cv::compare(mask, 0, observation_, cv::CMP_NE);
  observation_count_ = static_cast<std::uint64_t>(cv::countNonZero(observation_));
  rim_.release();
}

void OpenCvBaseline::set_rim(const cv::Mat& rim) {
  if (!has_projection_) throw Error("opencv baseline: set_projection() must come before set_rim()");
  rim_.release();
  if (rim.empty()) return;
  const ImageSize s = projection_.size;
  if (rim.type() != CV_8UC1 || rim.cols != s.width || rim.rows != s.height) {
    throw Error("opencv baseline: the rim must be CV_8U at the render size " + std::to_string(s.width) + "x" +
                std::to_string(s.height));
  }
  cv::compare(rim, 0, rim_, cv::CMP_NE);
}

void OpenCvBaseline::fill(const Eigen::Ref<const Eigen::VectorXd>& h, Scratch& s) const {
  model_->pose(h, s.world);
  project_and_clip(s.world, projection_, s.polygons);
  s.mask.setTo(0);
  for (const ScreenPolygon& p : s.polygons) {
    s.points.clear();
    // OpenCV puts pixel centres on integers, gtrack at +0.5.
    for (int i = 0; i < p.count; ++i) {
      s.points.emplace_back(cvRound((p.v[i].x() - 0.5) * (1 << kShift)), cvRound((p.v[i].y() - 0.5) * (1 << kShift)));
    }
    cv::fillConvexPoly(s.mask, s.points.data(), p.count, cv::Scalar(255), cv::LINE_8, kShift);
  }
}

void OpenCvBaseline::require_ready(Eigen::Index dims) const {
  if (!has_projection_ || !model_) throw Error("opencv baseline: set_model() and set_projection() come first");
  if (dims != model_->dims()) {
    throw Error("opencv baseline: a hypothesis has " + std::to_string(dims) + " values, the model needs " +
                std::to_string(model_->dims()));
  }
}

void OpenCvBaseline::submit(const Eigen::MatrixXd& hypotheses) {
  require_ready(hypotheses.rows());
  const int n = static_cast<int>(hypotheses.cols());
  results_.resize(n);
  auto job = [&](int worker, int i) {
    Scratch& s = scratch_[worker];
    fill(hypotheses.col(i), s);
    cv::bitwise_and(s.mask, observation_, s.combined);
    const int both = cv::countNonZero(s.combined);
    cv::bitwise_or(s.mask, observation_, s.combined);
    const int either = cv::countNonZero(s.combined);
    results_[i].intersection = static_cast<std::uint32_t>(both);
    results_[i].rendered = static_cast<std::uint32_t>(either + both - static_cast<int>(observation_count_));
    results_[i].rim = 0;
    if (!rim_.empty()) {
      cv::bitwise_and(s.mask, rim_, s.combined);
      results_[i].rim = static_cast<std::uint32_t>(cv::countNonZero(s.combined));
    }
  };
  pool_.run(n, job);
}

cv::Mat OpenCvBaseline::render_mask(const Eigen::VectorXd& hypothesis) {
  require_ready(hypothesis.size());
  fill(hypothesis, scratch_[0]);
  return scratch_[0].mask.clone();
}

}  // namespace render

std::unique_ptr<Renderer> make_opencv_baseline(const RenderOptions& options) {
  return std::make_unique<render::OpenCvBaseline>(options);
}

}  // namespace gtrack
