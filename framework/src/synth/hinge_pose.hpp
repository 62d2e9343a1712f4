// Posing the gripper with a separate angle at every hinge.
//
// The tracker's model lets all hinges of a finger share one joint value; a
// real gripper does not quite (paper Fig. 6b). This is the formula of
// model.hpp with link j tilted by the sum of the first j + 1 hinge angles
// instead of (j + 1) q; with equal hinge angles it is exactly
// ArticulatedModel::pose().
#pragma once

#include <Eigen/Core>
#include <vector>

#include "gtrack/model.hpp"

namespace gtrack::synth {

// hinge_deg: finger-major, max_links() values per finger (extra ones unused).
// Returns world triangles (3 vertices each), in mesh order.
void pose_hinges(const ArticulatedModel& model, const Eigen::VectorXd& h, const std::vector<double>& hinge_deg,
                 std::vector<Eigen::Vector3d>& out);

// The hinge angles of a hypothesis whose fingers each share one value.
std::vector<double> shared_hinges(const ArticulatedModel& model, const Eigen::VectorXd& h);

}  // namespace gtrack::synth
