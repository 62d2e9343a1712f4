// Posing the cached mesh for the cpu backend, fast.
//
// ArticulatedModel::pose() is the reference formula (model.hpp); this is the
// same formula with everything that does not depend on the hypothesis
// computed once in set_model: per vertex its finger's base point and in-plane
// axes, per finger its link lengths. Per hypothesis only the joint angles
// need trigonometry. The rigid motion is not applied to the vertices at all:
// it is folded into the projection (and the clip planes), which then map
// model coordinates straight to the image.
#pragma once

#include <Eigen/Core>
#include <vector>

#include "gtrack/model.hpp"
#include "gtrack/sensor.hpp"

namespace gtrack::render {

class ModelPoser {
 public:
  ModelPoser() = default;
  explicit ModelPoser(const ArticulatedModel& model);

  int dims() const { return dims_; }
  bool empty() const { return vertices_.empty(); }

  // Model-frame position of every mesh vertex (3 per triangle) for h's joints.
  void pose_model(const double* h, std::vector<Eigen::Vector3d>& out) const;
  // `world` with h's rigid motion folded in: the result takes model points.
  // `out` keeps its capacity so this allocates nothing after the first call.
  static void to_model_frame(const double* h, const Projection& world, Projection& out);

 private:
  struct Vertex {
    double a, b;  // along the link, across it (palm: model x, y)
    Eigen::Vector2d base, dir, lateral;
    int link_slot;  // index into the per-hypothesis link table, -1 for the palm
  };
  struct Finger {
    int first_slot;
    std::vector<double> lengths;
  };
  std::vector<Vertex> vertices_;
  std::vector<Finger> fingers_;
  int slots_ = 0;
  int dims_ = 0;
};

}  // namespace gtrack::render
