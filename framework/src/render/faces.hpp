// The mesh regrouped into convex planar faces, for the cpu backend.
//
// The model is stored as triangles, but most of them come in fans that make
// up one convex planar face: the palm polygon, the two halves of a link's
// trapezoid. Filling a face once instead of triangle by triangle halves the
// rows the rasteriser walks, and since coverage follows a sampling rule that
// does not depend on how a region is cut (span_raster.hpp), the pixels are
// the same. A face that any plane cuts goes back to its triangles, so clipped
// geometry is exactly what project_and_clip produces.
#pragma once

#include <Eigen/Core>
#include <vector>

#include "gtrack/model.hpp"
#include "gtrack/renderer.hpp"

namespace gtrack::render {

class Faces {
 public:
  Faces() = default;
  explicit Faces(const ArticulatedModel& model);

  int count() const { return static_cast<int>(faces_.size()); }

  // Screen polygons of the posed mesh (`vertices`: 3 per triangle, in the
  // frame `projection` takes), replacing the contents of `out`.
  void project(const std::vector<Eigen::Vector3d>& vertices, const Projection& projection,
               std::vector<ScreenPolygon>& out) const;

 private:
  struct Face {
    int first_corner;    // into corners_
    int corners;         // polygon size
    int first_triangle;  // its triangles in the mesh
    int triangles;
  };
  std::vector<int> corners_;  // mesh vertex index of each polygon corner
  std::vector<Face> faces_;
};

}  // namespace gtrack::render
