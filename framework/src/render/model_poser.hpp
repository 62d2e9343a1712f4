// Posing and projecting the cached mesh for the cpu backend, fast.
//
// ArticulatedModel::pose() is the reference formula (model.hpp). Every point
// of link k of a finger is O_k + a U_k + b V_k in the model frame (a along
// the link, b across it), and the palm is the same with the model axes; the
// projection and the clip planes are linear in the point. So per hypothesis
// the rigid motion is folded into the projection, O, U and V of each link are
// mapped once to image and plane space, and each vertex then costs two
// multiply-adds per value instead of a pose and a projection.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "gtrack/model.hpp"
#include "gtrack/sensor.hpp"
#include "render/clip.hpp"

namespace gtrack::render {

// Chosen mesh vertices of one hypothesis in homogeneous image coordinates
// (u*w, v*w, w), and whether each is inside all of the projection's planes.
struct ProjectedMesh {
  std::vector<Eigen::Vector3d> image;
  std::vector<std::uint8_t> inside_planes;
};

class ModelPoser {
 public:
  ModelPoser() = default;
  explicit ModelPoser(const ArticulatedModel& model);

  int dims() const { return dims_; }
  bool empty() const { return vertices_.empty(); }

  // `world` with h's rigid motion folded in: the result takes model points.
  // `out` keeps its capacity so this allocates nothing after the first call.
  static void to_model_frame(const double* h, const Projection& world, Projection& out);

  // Mesh vertices `which` of h through `model_projection` (from
  // to_model_frame), in that order.
  void project(const double* h, const Projection& model_projection, const std::vector<int>& which,
               ProjectedMesh& out) const;
  // Model-frame position of every mesh vertex (3 per triangle), for the
  // faces that need clipping.
  void pose_model(const double* h, std::vector<Eigen::Vector3d>& out) const;

 private:
  struct Vertex {
    double a, b;  // along the link, across it (palm: model x, y)
    int slot;     // link slot; the palm is slot 0
  };
  struct Finger {
    Eigen::Vector2d base, dir, lateral;
    int first_slot;
    std::vector<double> lengths;
  };
  // Hinge (r, z) and direction (cos, sin) of every link, palm first.
  struct Links {
    double hr, hz, c, s;
  };
  void links(const double* h, Links* out) const;

  std::vector<Vertex> vertices_;
  std::vector<Finger> fingers_;
  std::vector<int> slot_finger_;  // finger of each slot, -1 for the palm
  int dims_ = 0;
};

}  // namespace gtrack::render
