// Where on the render target a hypothesis can have pixels at all.
//
// The count pass only visits, per layer of 32 hypotheses, the union of their
// boxes: the projection of a cube around the palm centre that holds the model
// in any configuration. Found on the CPU from the parameter vector alone (8
// projected corners per hypothesis), so it costs nothing on the GPU and needs
// no extra round trip. A hypothesis whose cube reaches behind the camera gets
// the whole target; one entirely outside a clip plane gets an empty box.
#pragma once

#include <Eigen/Core>

#include "gtrack/model.hpp"
#include "gtrack/sensor.hpp"

namespace gtrack::gl {

struct PixelBox {
  int x0 = 0, y0 = 0, x1 = 0, y1 = 0;  // half-open: [x0, x1) x [y0, y1)

  bool empty() const { return x0 >= x1 || y0 >= y1; }
  int width() const { return empty() ? 0 : x1 - x0; }
  int height() const { return empty() ? 0 : y1 - y0; }
  void unite(const PixelBox& b);
};

// A radius about the palm centre (mm) that no point of the model leaves for
// any joint values: palm corners, and along each finger the links before a
// point plus the point's own offsets.
double model_reach_mm(const ArticulatedModel& model);

// Pixels of `projection` (render size) that hypothesis position `centre` can
// cover with a model of radius `reach`.
PixelBox hypothesis_box(const Projection& projection, const Eigen::Vector3d& centre, double reach);

}  // namespace gtrack::gl
