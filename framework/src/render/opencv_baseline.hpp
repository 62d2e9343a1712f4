// The OpenCV baseline evaluator behind make_opencv_baseline (bench.hpp).
//
// Written as a user of OpenCV would write the evaluation, with no tricks of
// the cpu backend: ArticulatedModel::pose, the shared projection and
// clipping, one cv::fillConvexPoly per polygon into a full-size byte mask,
// then cv::bitwise_and / cv::bitwise_or and cv::countNonZero over the whole
// image. It runs on the same thread pool as the cpu backend so that the two
// are compared at equal thread counts, kernel against kernel.
#pragma once

#include <memory>
#include <vector>

#include "gtrack/renderer.hpp"
#include "render/worker_pool.hpp"

namespace gtrack::render {

class OpenCvBaseline final : public Renderer {
 public:
  explicit OpenCvBaseline(const RenderOptions& options);

  std::string name() const override { return "opencv_baseline"; }
  void set_model(const ArticulatedModel& model) override;
  void set_projection(const Projection& projection, double scale) override;
  ImageSize render_size() const override { return projection_.size; }
  void set_observation(const cv::Mat& mask) override;
  void set_rim(const cv::Mat& rim) override;
  std::uint64_t observation_count() const override { return observation_count_; }
  void submit(const Eigen::MatrixXd& hypotheses) override;
  void finish(std::vector<PairCounts>& out) override { out.assign(results_.begin(), results_.end()); }
  cv::Mat render_mask(const Eigen::VectorXd& hypothesis) override;

 private:
  struct Scratch {
    std::vector<Eigen::Vector3d> world;
    std::vector<ScreenPolygon> polygons;
    std::vector<cv::Point> points;
    cv::Mat mask, combined;
  };
  void fill(const Eigen::Ref<const Eigen::VectorXd>& h, Scratch& s) const;
  void require_ready(Eigen::Index dims) const;

  WorkerPool pool_;
  std::vector<Scratch> scratch_;
  std::unique_ptr<ArticulatedModel> model_;
  Projection projection_;
  bool has_projection_ = false;
  cv::Mat observation_, rim_;  // rim_ empty: none
  std::uint64_t observation_count_ = 0;
  std::vector<PairCounts> results_;
};

}  // namespace gtrack::render
