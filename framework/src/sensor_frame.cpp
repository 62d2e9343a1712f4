// A sensor's own frame, and the sensor seen from it (see sensor.hpp).
#include <cmath>
#include <utility>

#include "gtrack/model.hpp"
#include "gtrack/sensor.hpp"

namespace gtrack {

namespace {

// `h` at `position`, its orientation turned by `turn`, its joints as they are.
Eigen::VectorXd moved(const Eigen::VectorXd& h, const Eigen::Vector3d& position, const Eigen::Matrix3d& turn) {
  Eigen::VectorXd out = h;
  out.head<3>() = position;
  out.segment<3>(3) = euler_deg_from_rotation(turn * rotation_from_euler_deg(h[3], h[4], h[5]));
  return out;
}

class SensorInFrame final : public Sensor {
 public:
  SensorInFrame(std::shared_ptr<const Sensor> sensor, const SensorFrame& frame)
      : sensor_(std::move(sensor)), frame_(frame) {}

  ImageSize image_size() const override { return sensor_->image_size(); }

  Projection projection() const override {
    // world = axes * p + (origin - axes * origin)
    Eigen::Matrix4d to_world = Eigen::Matrix4d::Identity();
    to_world.topLeftCorner<3, 3>() = frame_.axes;
    to_world.topRightCorner<3, 1>() = frame_.origin - frame_.axes * frame_.origin;
    Projection p = sensor_->projection();
    p.world_to_image = p.world_to_image * to_world;
    for (auto& plane : p.clip_planes) plane = (plane.transpose() * to_world).transpose();
    return p;
  }

  std::optional<Eigen::Vector2d> project(const Eigen::Vector3d& p) const override {
    return sensor_->project(frame_.point_to_world(p));
  }

  cv::Mat rectify(const cv::Mat& frame) const override { return sensor_->rectify(frame); }
  SegmentationDefaults segmentation_defaults() const override { return sensor_->segmentation_defaults(); }
  // The frame turns about the nominal position.
  Eigen::Vector3d nominal_position_mm() const override { return frame_.origin; }
  double mm_per_pixel() const override { return sensor_->mm_per_pixel(); }

 private:
  std::shared_ptr<const Sensor> sensor_;
  SensorFrame frame_;
};

}  // namespace

Eigen::Vector3d viewing_axis(const Projection& projection) {
  // P = [M | p4]: a camera's principal ray runs along M's third row; an
  // affine view (third row zero) looks along what neither image axis sees.
  const Eigen::Matrix3d m = projection.world_to_image.leftCols<3>();
  Eigen::Vector3d axis = m.row(2).transpose();
  if (axis.norm() == 0) axis = m.row(0).transpose().cross(m.row(1).transpose());
  return axis.norm() > 0 ? Eigen::Vector3d(axis.normalized()) : Eigen::Vector3d::UnitZ();
}

std::optional<double> slab_thickness_mm(const Projection& projection) {
  if (projection.clip_planes.size() != 2) return std::nullopt;
  const Eigen::Vector4d& a = projection.clip_planes[0];
  const Eigen::Vector4d& b = projection.clip_planes[1];
  const double na = a.head<3>().norm(), nb = b.head<3>().norm();
  if (!(na > 0 && nb > 0)) return std::nullopt;
  const Eigen::Vector3d axis = viewing_axis(projection);
  const Eigen::Vector3d ua = a.head<3>() / na, ub = b.head<3>() / nb;
  if (!(std::abs(std::abs(ua.dot(axis)) - 1) < 1e-6 && ua.dot(ub) < -1 + 1e-6)) return std::nullopt;
  // Kept: -a3/|a| <= ua.x and ua.x <= b3/|b|.
  return a[3] / na + b[3] / nb;
}

bool SensorFrame::is_world() const { return (axes - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff() < 1e-12; }

Eigen::VectorXd SensorFrame::to_world(const Eigen::VectorXd& h) const {
  return is_world() ? h : moved(h, point_to_world(h.head<3>()), axes);
}

Eigen::VectorXd SensorFrame::from_world(const Eigen::VectorXd& h) const {
  return is_world() ? h : moved(h, point_from_world(h.head<3>()), axes.transpose());
}

SensorFrame sensor_frame(const Sensor& sensor) {
  const Projection p = sensor.projection();
  SensorFrame f;
  f.origin = sensor.nominal_position_mm();
  const Eigen::Vector3d e3 = viewing_axis(p);
  const Eigen::Vector3d m1 = p.world_to_image.block<1, 3>(0, 0).transpose();
  Eigen::Vector3d e1 = m1 - m1.dot(e3) * e3;
  if (!(e1.norm() > 0)) return f;
  e1.normalize();
  f.axes << e1, e3.cross(e1), e3;
  return f;
}

std::shared_ptr<Sensor> sensor_in_frame(std::shared_ptr<const Sensor> sensor, const SensorFrame& frame) {
  return std::make_shared<SensorInFrame>(std::move(sensor), frame);
}

}  // namespace gtrack
