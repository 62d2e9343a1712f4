// The articulated gripper model: a palm and fingers that are planar chains.
//
// Geometry (model frame, millimetres): the palm is a polygon in the XY plane
// centred at the origin. Finger f is attached at base point B_f on the palm
// with outward unit direction d_f = (cos phi_f, sin phi_f) and lateral
// l_f = (-sin phi_f, cos phi_f). Its links j = 0..L-1 have lengths len_j; all
// its hinges share one joint value q (degrees), link j is tilted by
// theta_j = (j + 1) * q out of the palm plane, folding towards +Z. With hinge
// points h_0 = 0 and h_{j+1} = h_j + len_j (cos theta_j, sin theta_j) in the
// (radial, z) plane, a point (a, b) of link j (a along the link from its
// hinge, b across) is at
//     B_f + (h_j.r + a cos theta_j) d_f + b l_f + (h_j.z + a sin theta_j) z.
// A palm point (a, b) is at (a, b, 0). World = R(rx,ry,rz) * model + (x,y,z).
// Both render backends implement exactly this (the GL vertex shader in
// shaders/ and pose() below), so a model is described once, as data.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <span>
#include <string>
#include <vector>

#include "gtrack/export.hpp"
#include "gtrack/parameter_space.hpp"

namespace gtrack {

// A link is a trapezoid in its own frame: from width_start at its hinge to
// width_end at its far end (width_end = 0 makes a triangular tip).
struct LinkShape {
  double length_mm = 0;
  double width_start_mm = 0;
  double width_end_mm = 0;
};

struct FingerShape {
  Eigen::Vector2d base_mm{0, 0};  // hinge of the first link, on the palm edge
  double direction_deg = 0;       // outward direction in the palm plane
  std::vector<LinkShape> links;
};

// K(H) judged from joint values only (no triangle tests), paper Section 2.2.
struct CollisionRule {
  std::vector<std::pair<int, int>> adjacent;  // pairs of neighbouring fingers
  double max_difference_deg = 1e9;            // |q_f - q_g| beyond this collides
  double max_sum_deg = 1e9;                   // q_f + q_g beyond this collides
};

// One vertex of the cached mesh: model-local coordinates plus what it hangs on.
struct ModelVertex {
  float a = 0, b = 0;  // see the header comment
  int finger = -1;     // -1 for the palm
  int link = 0;
};

struct GripperGeometry {
  std::string name;
  std::vector<Eigen::Vector2d> palm_mm;  // convex polygon, counter-clockwise
  std::vector<FingerShape> fingers;
  double joint_min_deg = 0;
  double joint_max_deg = 90;
  CollisionRule collision;
  int symmetry_order = 1;  // rotation by 360/order about model Z maps the model onto itself
  double unfolded_deg = 0;
  double folded_deg = 60;
};

class GTRACK_API ArticulatedModel {
 public:
  // Links over all fingers, and the largest extent of any part (mm): a
  // model past either is refused by the constructor.
  static constexpr int kMaxLinks = 255;
  static constexpr double kMaxSizeMm = 100;
  // The least length of a link and radius of a palm a config may give (1 um):
  // less has no area at any render size.
  static constexpr double kMinSizeMm = 0.001;

  ArticulatedModel() = default;
  // Validates the geometry; throws gtrack::Error saying what is wrong.
  explicit ArticulatedModel(GripperGeometry geometry);

  const GripperGeometry& geometry() const { return geometry_; }
  int fingers() const { return static_cast<int>(geometry_.fingers.size()); }
  int dims() const { return kPoseDims + fingers(); }
  int max_links() const;

  // Triangle list (3 vertices per triangle) in model-local form.
  const std::vector<ModelVertex>& mesh() const { return mesh_; }
  int triangles() const { return static_cast<int>(mesh_.size() / 3); }

  // The world position of every mesh vertex for hypothesis h.
  void pose(const Eigen::Ref<const Eigen::VectorXd>& h, std::vector<Eigen::Vector3d>& out) const;
  // The model-frame position of every mesh vertex for the given joint values.
  void pose_model(std::span<const double> joints_deg, std::vector<Eigen::Vector3d>& out) const;

  // Phalanx endpoints (the far end of every link, on the finger's axis), world frame.
  std::vector<Eigen::Vector3d> link_endpoints(const Eigen::Ref<const Eigen::VectorXd>& h) const;
  // Fingertips (end of the last link, on the axis), world frame.
  std::vector<Eigen::Vector3d> fingertips(const Eigen::Ref<const Eigen::VectorXd>& h) const;

  // K(H): joint-limit violation plus adjacent-finger collisions, normalised
  // by the joint range; 0 for a plausible configuration.
  double kinematic_penalty(std::span<const double> joints_deg) const;

  // The hypothesis that describes the same physical configuration after a
  // rotation of the model by k * 360/symmetry_order about its Z axis
  // (fingers renumbered accordingly). k = 0 returns h.
  Eigen::VectorXd symmetric_equivalent(const Eigen::Ref<const Eigen::VectorXd>& h, int k) const;

  // Radius of the model's bounding sphere about the palm centre (mm), open.
  double radius_mm() const;

 private:
  GripperGeometry geometry_;
  std::vector<ModelVertex> mesh_;
  std::vector<int> finger_shift_;  // finger permutation for one symmetry step
};

// Why a palm polygon is not one the mesh can be made of ("" when it is):
// its points must run counter-clockwise around a convex polygon.
GTRACK_API std::string palm_shape_mismatch(const std::vector<Eigen::Vector2d>& palm);

// The distance from `p` to the nearest side of the closed polygon.
GTRACK_API double distance_to_outline(const Eigen::Vector2d& p, const std::vector<Eigen::Vector2d>& polygon);

// Why a geometry's symmetry_order does not hold ("" when it does): a turn
// by 360/order must take every palm point onto a palm point and every finger
// onto a finger of the same links, at its hinge and in its direction.
// `finger_shift`, when given, receives where one turn takes each finger.
GTRACK_API std::string symmetry_mismatch(const GripperGeometry& geometry, std::vector<int>* finger_shift = nullptr);

// Each finger with the next, around the palm (one pair for two fingers).
GTRACK_API std::vector<std::pair<int, int>> ring_adjacency(int fingers);

// R = Rz(rz) * Ry(ry) * Rx(rx), angles in degrees.
GTRACK_API Eigen::Matrix3d rotation_from_euler_deg(double rx, double ry, double rz);
// Inverse of the above (rx, ry, rz in degrees).
GTRACK_API Eigen::Vector3d euler_deg_from_rotation(const Eigen::Matrix3d& r);

// h (x, y, z, rx, ry, rz, joints...) with its Euler pair (rx, ry) turned
// by `deg` in its own plane, rz and the rest unchanged: about as much tilt,
// its direction turned about as much, the fingers' heading in the image
// kept. Exact at 180 (the tilt mirror, -rx, -ry); elsewhere the pair is not
// the tilt itself (rx = 60 turned by 60 tilts the palm 57.75 deg, its
// direction turned by 53.8). Re-detection's turned starts are this; the
// exact turn of the palm normal tracked worse (docs/tracker.md).
GTRACK_API Eigen::VectorXd tilt_turned(const Eigen::VectorXd& h, double deg);

// A regular-polygon gripper with identical fingers on every palm edge: the
// shape of all three grippers of the paper.
struct RadialGripperSpec {
  std::string name;
  int fingers = 6;
  int palm_sides = 6;
  double palm_circumradius_mm = 0.75;
  std::vector<LinkShape> links;
  double finger_phase_deg = 0;  // direction of finger 0
};
GTRACK_API GripperGeometry make_radial_gripper(const RadialGripperSpec& spec);

}  // namespace gtrack
