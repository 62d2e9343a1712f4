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
#include "render/clip.hpp"
#include "render/model_poser.hpp"

namespace gtrack::render {

class Faces {
 public:
  Faces() = default;
  explicit Faces(const ArticulatedModel& model);

  struct Face {
    int first_corner;    // into corners()
    int corners;         // polygon size
    int first_triangle;  // its triangles in the mesh
    int triangles;
  };
  const std::vector<Face>& faces() const { return faces_; }
  // The mesh vertex of every face corner, face after face: what needs
  // projecting (ModelPoser::project) for inside() and the fast path.
  const std::vector<int>& corners() const { return corners_; }

  // Whether no plane and no frustum side cuts the face, given corners()
  // projected; such a face is filled straight from its projected corners.
  bool inside(const Face& face, const ProjectedMesh& mesh, const Frustum& frustum) const {
    bool in = true;
    for (int c = face.first_corner; c < face.first_corner + face.corners; ++c) {
      in &= (mesh.inside_planes[c] != 0) & frustum.contains(mesh.image[c]);
    }
    return in;
  }
  // Appends the face clipped triangle by triangle (project_and_clip's way);
  // `vertices` are the mesh's, in the frame `projection` takes.
  void clip(const Face& face, const std::vector<Eigen::Vector3d>& vertices, const Projection& projection,
            const Frustum& frustum, std::vector<ScreenPolygon>& out) const;

 private:
  std::vector<int> corners_;  // mesh vertex index of each polygon corner
  std::vector<Face> faces_;
};

}  // namespace gtrack::render
