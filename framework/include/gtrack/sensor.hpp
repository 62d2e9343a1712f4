// Sensor plugins: how the world becomes an image.
//
// A sensor tells the renderers everything they need, as data, so that a new
// imaging model needs no change in any render backend:
//   - a 3x4 matrix taking world points (mm) to homogeneous image coordinates
//     (u*w, v*w, w) in pixels of the full-resolution image (pixel centres at
//     +0.5; a point is imaged when w > 0),
//   - clip planes in world coordinates (n.x + d >= 0 is kept), at most 8
//     (both backends): the pinhole's near plane, the ultrasound slab's two
//     faces; none for an orthographic (telecentric) sensor.
// Both backends clip triangles against the planes, divide by w and fill with
// the pixel-centre rule. project() is the full model (with lens distortion)
// used for drawing overlays and for tests.
#pragma once

#include <Eigen/Core>
#include <memory>
#include <opencv2/core.hpp>
#include <optional>
#include <string>
#include <vector>

#include "gtrack/export.hpp"

namespace gtrack {

struct ImageSize {
  int width = 0;
  int height = 0;
};

struct Projection {
  Eigen::Matrix<double, 3, 4> world_to_image = Eigen::Matrix<double, 3, 4>::Zero();
  std::vector<Eigen::Vector4d> clip_planes;  // (n, d): keep n.x + d >= 0
  ImageSize size;
};

// What the observation step should do with this sensor's frames by default.
struct SegmentationDefaults {
  std::string color_space = "hsv";  // "hsv" (camera) or "luminance" (ultrasound)
};

class GTRACK_API Sensor {
 public:
  virtual ~Sensor();

  virtual ImageSize image_size() const = 0;
  virtual Projection projection() const = 0;
  // Pixel coordinates of a world point, distortion included; nullopt if the
  // point is not imaged (behind the camera, outside the slab).
  virtual std::optional<Eigen::Vector2d> project(const Eigen::Vector3d& world_mm) const = 0;
  // Removes what the linear projection does not model (lens distortion) from
  // an input frame; the default returns the frame unchanged.
  virtual cv::Mat rectify(const cv::Mat& frame) const;
  virtual SegmentationDefaults segmentation_defaults() const;
  // A typical world position for the gripper in view (mm), for synthetic
  // sequences and the first-frame search.
  virtual Eigen::Vector3d nominal_position_mm() const = 0;
  // Millimetres per pixel at the nominal position (for metrics and presets).
  virtual double mm_per_pixel() const = 0;
};

// A pixel's width and height in mm: for an affine projection (a slice), the
// height by the ratio of its rows to its columns (a scanner whose pixels
// are not square); else mm_per_pixel() for both.
GTRACK_API Eigen::Vector2d pixel_size_mm(const Sensor& sensor);

// The sensor's viewing axis (unit length): a camera's optical axis, the
// normal of an orthographic view or an ultrasound slice.
GTRACK_API Eigen::Vector3d viewing_axis(const Projection& projection);

// The thickness (mm) of the slab a projection images, for an ultrasound
// slice: its two clip planes facing each other across the viewing axis;
// none for any other projection.
GTRACK_API std::optional<double> slab_thickness_mm(const Projection& projection);

// A sensor's own frame: axes whose columns are the image's u direction, the
// direction normal to it within the image, and the viewing axis (unit,
// right-handed), turning about `origin`, the nominal position. A point p
// given in the frame is origin + axes * (p - origin) in the world. For a
// sensor that looks down world z with u along x the frame is the world's.
//
// The tracker searches in it, so that rx, ry are tilts away from face-on
// and rz is a turn about the line of sight whichever way the sensor is
// turned in the world; what it reads and writes stays in the world.
struct GTRACK_API SensorFrame {
  Eigen::Matrix3d axes = Eigen::Matrix3d::Identity();
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();

  bool is_world() const;
  // A point given in this frame, in the world, and back.
  Eigen::Vector3d point_to_world(const Eigen::Vector3d& p) const { return origin + axes * (p - origin); }
  Eigen::Vector3d point_from_world(const Eigen::Vector3d& p) const { return origin + axes.transpose() * (p - origin); }
  // A configuration x, y, z, rx, ry, rz, q.. given in this frame, in the
  // world (joints unchanged), and back.
  Eigen::VectorXd to_world(const Eigen::VectorXd& h) const;
  Eigen::VectorXd from_world(const Eigen::VectorXd& h) const;
};

GTRACK_API SensorFrame sensor_frame(const Sensor& sensor);
// The sensor seen from `frame`: its projection, clip planes, project() and
// nominal position take and give points in the frame.
GTRACK_API std::shared_ptr<Sensor> sensor_in_frame(std::shared_ptr<const Sensor> sensor, const SensorFrame& frame);

}  // namespace gtrack
