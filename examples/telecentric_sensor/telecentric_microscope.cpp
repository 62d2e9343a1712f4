// telecentric_microscope: a sensor plugin from outside the gtrack tree.
//
// A telecentric objective images by orthographic projection: the
// magnification does not change with depth, so a gripper's image does not
// grow as it comes closer. Pixel (u, v) sees the world point (x, y) with
//   u = x / mm_per_pixel + width / 2,   v = y / mm_per_pixel + height / 2
// (camera axes, the optical axis along +z). The projection is affine: its
// last row is (0, 0, 0, 1), so both render backends image it as they image
// any other sensor, with no code of their own. Depth is not seen at all: the
// tracker's z follows only its prior, and only the image-plane position,
// orientation and joints are measured.
#include <gtrack/plugin.hpp>

namespace {

class TelecentricMicroscope final : public gtrack::Sensor {
 public:
  explicit TelecentricMicroscope(const gtrack::ConfigTable& t) {
    using gtrack::Range;
    width_ = static_cast<int>(t.integer("width", Range{1, 65536}));
    height_ = static_cast<int>(t.integer("height", Range{1, 65536}));
    s_ = t.number("mm_per_pixel", Range::positive());
    working_distance_ = t.number_or("working_distance_mm", 65.0, Range::positive());
  }

  gtrack::ImageSize image_size() const override { return {width_, height_}; }

  gtrack::Projection projection() const override {
    gtrack::Projection p;
    p.size = {width_, height_};
    p.world_to_image.row(0) << 1 / s_, 0, 0, width_ / 2.0;
    p.world_to_image.row(1) << 0, 1 / s_, 0, height_ / 2.0;
    p.world_to_image.row(2) << 0, 0, 0, 1;
    return p;
  }

  std::optional<Eigen::Vector2d> project(const Eigen::Vector3d& x) const override {
    return Eigen::Vector2d(x.x() / s_ + width_ / 2.0, x.y() / s_ + height_ / 2.0);
  }

  Eigen::Vector3d nominal_position_mm() const override { return {0, 0, working_distance_}; }
  double mm_per_pixel() const override { return s_; }

 private:
  int width_, height_;
  double s_, working_distance_;
};

}  // namespace

GTRACK_PLUGIN(TelecentricMicroscope, gtrack::Sensor, "telecentric_microscope", "0.1.0",
              "example: telecentric (orthographic) microscope, mm per pixel")
