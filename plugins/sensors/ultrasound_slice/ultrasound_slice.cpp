// ultrasound_slice: a B-mode image of one plane, as a linear probe sees it.
//
// The probe's pose in the world is given by probe_position_mm (the point of
// the image's top centre) and probe_rotation_deg (R = Rz·Ry·Rx; its columns
// are the image's lateral axis, the depth axis and the elevation normal).
// A pixel is mm_per_pixel wide and mm_per_pixel_depth high (the same
// unless given: some scanners' pixels are not square): u = lateral / s +
// W/2, v = depth / s_depth. Only what lies in the elevational slab |elevation| <=
// slab_thickness_mm / 2 is imaged, projected orthogonally onto the plane:
// the projection is affine and the slab is two clip planes, so both render
// backends image it with no code of their own.
#include <gtrack/model.hpp>
#include <gtrack/plugin.hpp>

namespace {

class UltrasoundSlice final : public gtrack::Sensor {
 public:
  explicit UltrasoundSlice(const gtrack::ConfigTable& t) {
    using gtrack::Range;
    width_ = static_cast<int>(t.integer_or("width", 1024, Range{1, 65536}));
    height_ = static_cast<int>(t.integer_or("height", 662, Range{1, 65536}));
    s_ = t.number_or("mm_per_pixel", 0.09, Range::positive());
    s_depth_ = t.number_or("mm_per_pixel_depth", s_, Range::positive());
    slab_ = t.number_or("slab_thickness_mm", 0.6, Range::positive());
    auto p = t.numbers_or("probe_position_mm", {0, 0, 0}, 3, Range::closed(-1e4, 1e4));  // within 10 m
    auto r = t.numbers_or("probe_rotation_deg", {0, 0, 0}, 3, Range::closed(-360, 360));
    origin_ = Eigen::Vector3d(p[0], p[1], p[2]);
    R_ = gtrack::rotation_from_euler_deg(r[0], r[1], r[2]);
  }

  gtrack::ImageSize image_size() const override { return {width_, height_}; }

  gtrack::Projection projection() const override {
    gtrack::Projection p;
    p.size = {width_, height_};
    const Eigen::Vector3d ex = R_.col(0), ey = R_.col(1), ez = R_.col(2);
    p.world_to_image.row(0) << ex.transpose() / s_, -ex.dot(origin_) / s_ + width_ / 2.0;
    p.world_to_image.row(1) << ey.transpose() / s_depth_, -ey.dot(origin_) / s_depth_;
    p.world_to_image.row(2) << 0, 0, 0, 1;
    p.clip_planes.push_back((Eigen::Vector4d() << ez, -ez.dot(origin_) + slab_ / 2).finished());
    p.clip_planes.push_back((Eigen::Vector4d() << -ez, ez.dot(origin_) + slab_ / 2).finished());
    return p;
  }

  std::optional<Eigen::Vector2d> project(const Eigen::Vector3d& X) const override {
    const Eigen::Vector3d d = R_.transpose() * (X - origin_);
    if (std::abs(d.z()) > slab_ / 2) return std::nullopt;
    return Eigen::Vector2d(d.x() / s_ + width_ / 2.0, d.y() / s_depth_);
  }

  gtrack::SegmentationDefaults segmentation_defaults() const override { return {"luminance"}; }
  Eigen::Vector3d nominal_position_mm() const override { return origin_ + R_.col(1) * (height_ * s_depth_ / 2); }
  // The lateral spacing (the depth's is the projection's second row).
  double mm_per_pixel() const override { return s_; }

 private:
  int width_, height_;
  double s_, s_depth_, slab_;
  Eigen::Vector3d origin_;
  Eigen::Matrix3d R_;
};

}  // namespace

GTRACK_PLUGIN(UltrasoundSlice, gtrack::Sensor, "ultrasound_slice", "1.0.0",
              "B-mode ultrasound plane: probe pose, mm per pixel (lateral, depth), elevational slab")
