// pinhole_microscope: a camera on a microscope, modelled as a pinhole with
// optional lens distortion (OpenCV's model). World = camera frame, OpenCV
// axes: x right, y down, z forward. Distortion is removed from input frames
// (rectify) so that the renderers use the linear projection.
#include <gtrack/plugin.hpp>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>

namespace {

class PinholeMicroscope final : public gtrack::Sensor {
 public:
  explicit PinholeMicroscope(const gtrack::ConfigTable& t) {
    using gtrack::Range;
    width_ = static_cast<int>(t.integer("width", Range{1, 65536}));
    height_ = static_cast<int>(t.integer("height", Range{1, 65536}));
    fx_ = t.number("fx", Range::positive());
    fy_ = t.number_or("fy", fx_, Range::positive());
    // cx, cy as calibration tools give them (OpenCV: pixel centres on integers).
    // A principal point far outside the image is a unit or typing mistake.
    cx_ = t.number_or("cx", (width_ - 1) / 2.0, Range::closed(-10.0 * width_, 11.0 * width_));
    cy_ = t.number_or("cy", (height_ - 1) / 2.0, Range::closed(-10.0 * height_, 11.0 * height_));
    near_ = t.number_or("near_mm", 1.0, Range::positive());
    working_distance_ = t.number_or("working_distance_mm", 100.0, Range::positive());
    // Real lenses stay well inside +-1000, even in the rational model.
    dist_ = t.numbers_or("distortion", {}, std::nullopt, Range::closed(-1000, 1000));
    if (!(dist_.empty() || dist_.size() == 4 || dist_.size() == 5 || dist_.size() == 8)) {
      t.fail("distortion", "expected 4, 5 or 8 coefficients (k1, k2, p1, p2[, k3[, k4, k5, k6]]), got " +
                               std::to_string(dist_.size()));
    }
    if (near_ >= working_distance_) t.fail("near_mm", "must be less than working_distance_mm");
    K_ = (cv::Mat_<double>(3, 3) << fx_, 0, cx_, 0, fy_, cy_, 0, 0, 1);
    has_distortion_ = false;
    for (double d : dist_) has_distortion_ = has_distortion_ || d != 0.0;
    if (has_distortion_) {
      cv::initUndistortRectifyMap(K_, dist_, cv::Mat(), K_, cv::Size(width_, height_), CV_32FC1, map1_, map2_);
    }
  }

  gtrack::ImageSize image_size() const override { return {width_, height_}; }

  gtrack::Projection projection() const override {
    gtrack::Projection p;
    p.size = {width_, height_};
    // gtrack puts pixel centres at +0.5, OpenCV on integers.
    p.world_to_image << fx_, 0, cx_ + 0.5, 0, 0, fy_, cy_ + 0.5, 0, 0, 0, 1, 0;
    p.clip_planes.push_back(Eigen::Vector4d(0, 0, 1, -near_));  // z >= near
    return p;
  }

  std::optional<Eigen::Vector2d> project(const Eigen::Vector3d& X) const override {
    if (X.z() < near_) return std::nullopt;
    std::vector<cv::Point3d> in{{X.x(), X.y(), X.z()}};
    std::vector<cv::Point2d> out;
    cv::projectPoints(in, cv::Vec3d(0, 0, 0), cv::Vec3d(0, 0, 0), K_, dist_, out);
    // OpenCV puts pixel centres on integers; gtrack puts them at +0.5.
    return Eigen::Vector2d(out[0].x + 0.5, out[0].y + 0.5);
  }

  cv::Mat rectify(const cv::Mat& frame) const override {
    if (!has_distortion_) return frame;
    cv::Mat out;
    cv::remap(frame, out, map1_, map2_, cv::INTER_LINEAR);
    return out;
  }

  Eigen::Vector3d nominal_position_mm() const override { return {0, 0, working_distance_}; }
  double mm_per_pixel() const override { return working_distance_ / fx_; }

 private:
  int width_, height_;
  double fx_, fy_, cx_, cy_, near_, working_distance_;
  std::vector<double> dist_;
  bool has_distortion_;
  cv::Mat K_, map1_, map2_;
};

}  // namespace

GTRACK_PLUGIN(PinholeMicroscope, gtrack::Sensor, "pinhole_microscope", "1.0.0",
              "microscope camera: pinhole with optional distortion, world = camera frame")
