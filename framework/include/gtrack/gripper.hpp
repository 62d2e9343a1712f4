// Gripper plugins: the articulated model of one gripper type.
//
// A gripper plugin describes its shape as data (GripperGeometry) and the
// framework turns it into an ArticulatedModel that both render backends cache.
// It may override the kinematic penalty K(H) if its collision rule is not
// the framework's adjacent-fingers rule.
#pragma once

#include <span>

#include "gtrack/export.hpp"
#include "gtrack/model.hpp"

namespace gtrack {

class GTRACK_API Gripper {
 public:
  virtual ~Gripper();

  virtual const ArticulatedModel& model() const = 0;
  // K(H) from the joint values; the default is model().kinematic_penalty().
  virtual double kinematic_penalty(std::span<const double> joints_deg) const;
};

}  // namespace gtrack
