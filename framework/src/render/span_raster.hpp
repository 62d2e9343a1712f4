// The cpu backend's rasteriser: screen polygons -> bit-packed spans, then
// |O & P| and |P| by AND + popcount over the touched box.
//
// Coverage rule (shared with the GL backend and the test oracle): vertices
// are snapped to 1/256 pixel (round half to even, as GPUs snap to 8
// sub-pixel bits), pixel (i, j) is covered when its centre (i + 0.5, j + 0.5)
// is inside, and a centre exactly on an edge belongs to the polygon only if
// that edge is a top edge (horizontal, interior below) or a left edge
// (interior to its right), image y pointing down. This is the same as
// sampling at a point nudged infinitesimally right and down, so coverage of
// a union does not depend on how it is cut into triangles: shared edges are
// counted once and the mask is a union, never a sum.
//
// All edge arithmetic is exact (64-bit integers); the guard band applied by
// project_and_clip keeps coordinates small enough for that.
#pragma once

#include <Eigen/Core>
#include <climits>
#include <vector>

#include "gtrack/renderer.hpp"
#include "render/bit_mask.hpp"

namespace gtrack::render {

// Rows y0..y1 and words w0..w1 (inclusive) that may hold set bits.
struct Box {
  int y0 = INT_MAX, y1 = -1, w0 = INT_MAX, w1 = -1;
  bool empty() const { return y0 > y1 || w0 > w1; }
};

// Polygons passed to fill_projected may have up to this many corners.
inline constexpr int kMaxPolygonCorners = 32;

// ORs the polygons (render pixels) into `mask` and grows `box` to cover them.
void fill_polygons(const std::vector<ScreenPolygon>& polygons, BitMask& mask, Box& box);

// The same for one convex polygon given in homogeneous image coordinates,
// inside the frustum of clip.hpp: exactly the pixels that emit_projected
// followed by fill_polygons would give, without building ScreenPolygons.
void fill_projected(const Eigen::Vector3d* corners, int n, BitMask& mask, Box& box);

// Counts |O & P| and |P| over `box` and clears P there, so that the mask is
// all zero again for the next hypothesis.
PairCounts count_and_clear(BitMask& rendered, const BitMask& observation, const Box& box);
// The same, with |R & P| counted against `rim` too.
PairCounts count_and_clear(BitMask& rendered, const BitMask& observation, const BitMask& rim, const Box& box);

}  // namespace gtrack::render
