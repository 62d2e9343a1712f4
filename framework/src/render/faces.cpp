// Faces: fan detection on the mesh, and the clipping fallback.
#include "render/faces.hpp"

#include "render/clip.hpp"
#include "render/span_raster.hpp"

namespace gtrack::render {

namespace {

constexpr int kMaxCorners = kMaxPolygonCorners;  // larger fans are split; any size would be correct

bool same_vertex(const ModelVertex& p, const ModelVertex& q) {
  return p.a == q.a && p.b == q.b && p.finger == q.finger && p.link == q.link;
}

// Convex with one orientation, in the face's own (a, b) plane, where the
// palm and every link are flat.
bool convex(const std::vector<ModelVertex>& mesh, const int* idx, int n) {
  double sign = 0;
  for (int i = 0; i < n; ++i) {
    const ModelVertex& p = mesh[idx[i]];
    const ModelVertex& q = mesh[idx[(i + 1) % n]];
    const ModelVertex& r = mesh[idx[(i + 2) % n]];
    const double c = (double(q.a) - p.a) * (double(r.b) - q.b) - (double(q.b) - p.b) * (double(r.a) - q.a);
    if (c == 0) continue;
    if (sign == 0) sign = c;
    if ((c > 0) != (sign > 0)) return false;
  }
  return sign != 0;
}

}  // namespace

Faces::Faces(const ArticulatedModel& model) {
  const std::vector<ModelVertex>& mesh = model.mesh();
  const int triangles = model.triangles();
  for (int t = 0; t < triangles; ++t) {
    const int v0 = 3 * t, v1 = 3 * t + 1, v2 = 3 * t + 2;
    if (!faces_.empty()) {
      // Triangle (first, last, new) of the current fan extends it.
      Face& f = faces_.back();
      const int first = corners_[f.first_corner];
      const int last = corners_[f.first_corner + f.corners - 1];
      if (f.first_triangle + f.triangles == t && f.corners < kMaxCorners && same_vertex(mesh[v0], mesh[first]) &&
          same_vertex(mesh[v1], mesh[last]) && mesh[v2].finger == mesh[first].finger &&
          mesh[v2].link == mesh[first].link) {
        corners_.push_back(v2);
        if (convex(mesh, corners_.data() + f.first_corner, f.corners + 1)) {
          ++f.corners;
          ++f.triangles;
          continue;
        }
        corners_.pop_back();
      }
    }
    faces_.push_back({static_cast<int>(corners_.size()), 3, t, 1});
    corners_.insert(corners_.end(), {v0, v1, v2});
  }
}

void Faces::clip(const Face& f, const std::vector<Eigen::Vector3d>& vertices, const Projection& projection,
                 const Frustum& frustum, std::vector<ScreenPolygon>& out) const {
  for (int t = f.first_triangle; t < f.first_triangle + f.triangles; ++t) {
    clip_triangle(vertices[3 * t], vertices[3 * t + 1], vertices[3 * t + 2], projection, frustum, out);
  }
}

}  // namespace gtrack::render
