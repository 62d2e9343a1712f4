// The hypothesis vector and its bounds.
//
// A hypothesis H is [x, y, z, rx, ry, rz, q_1 .. q_F]: position of the palm
// centre in millimetres, Euler angles in degrees with R = Rz(rz)·Ry(ry)·Rx(rx),
// and one joint value per finger in degrees (every hinge of finger f folds by
// q_f). The same units are used in configs, outputs and in the engine.
#pragma once

#include <Eigen/Core>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "gtrack/export.hpp"

namespace gtrack {

inline constexpr int kPoseDims = 6;  // x, y, z, rx, ry, rz

// "q<finger>_deg", the name of finger `finger`'s joint (from 1) in every
// table gtrack reads and writes.
GTRACK_API std::string joint_name(int finger);
// The name of parameter d of a configuration in those tables: "x_mm",
// "y_mm", "z_mm", "rx_deg", "ry_deg", "rz_deg", then joint_name(d - 5).
GTRACK_API std::string parameter_name(int d);

struct ParameterSpace {
  std::vector<std::string> names;  // "x_mm", ..., "rz_deg", "q1_deg", ...
  Eigen::VectorXd lower;
  Eigen::VectorXd upper;
  // A periodic parameter wraps into [lower, upper) instead of being clamped
  // (used for rz, whose range is a full turn).
  std::vector<bool> periodic;
  // A box for x, y, z given in another frame (the world's, when the space
  // is a turned sensor's): the position p is also kept within it,
  // origin + axes * (p - origin) in [lower, upper]. None: the bounds alone.
  struct PositionBox {
    Eigen::Matrix3d axes = Eigen::Matrix3d::Identity();
    Eigen::Vector3d origin = Eigen::Vector3d::Zero();
    Eigen::Vector3d lower = Eigen::Vector3d::Zero(), upper = Eigen::Vector3d::Zero();

    Eigen::Vector3d to_box(const Eigen::Vector3d& p) const { return origin + axes * (p - origin); }
    Eigen::Vector3d from_box(const Eigen::Vector3d& q) const { return origin + axes.transpose() * (q - origin); }
  };
  std::optional<PositionBox> position_box;

  int dims() const { return static_cast<int>(names.size()); }
  int fingers() const { return dims() - kPoseDims; }

  // Puts h on the nearest point inside the bounds (wrapping periodic ones;
  // the position on the nearest point of position_box when there is one).
  GTRACK_API void clamp(Eigen::Ref<Eigen::VectorXd> h) const;
  // Whether h is inside the bounds; a periodic parameter is inside at any
  // finite value (it wraps).
  GTRACK_API bool contains(const Eigen::Ref<const Eigen::VectorXd>& h) const;

  // Pose bounds from the engine config and joint bounds from the gripper.
  GTRACK_API static ParameterSpace make(int fingers, const Eigen::Vector3d& pos_lo,
                                        const Eigen::Vector3d& pos_hi, const Eigen::Vector3d& rot_lo,
                                        const Eigen::Vector3d& rot_hi, double joint_lo, double joint_hi,
                                        bool rz_periodic);
};

// Parses "x,y,z,rx,ry,rz,q1,...,qF" (mm, degrees). Throws InputError naming
// the offending field and the expected count.
GTRACK_API Eigen::VectorXd parse_parameter_vector(std::string_view text, int expected_dims);

}  // namespace gtrack
