// Convex polygon filling with exact edge walks; see span_raster.hpp for the rule.
//
// A convex polygon is filled row by row between its left and right chains.
// Along an edge, the bound on the pixel index for row j is floor(M(j) / D)
// with M linear in j, so it is carried as quotient + remainder and advanced
// with additions only; a division happens once per edge.
#include "render/span_raster.hpp"

#include <algorithm>
#include <bit>
#include <cstdint>

#include "render/clip.hpp"

namespace gtrack::render {

namespace {

using i64 = std::int64_t;

constexpr int kSubBits = 8;
constexpr i64 kSub = i64{1} << kSubBits;  // fixed-point units per pixel
constexpr int kMaxVertices = kMaxPolygonCorners;
static_assert(std::extent_v<decltype(ScreenPolygon::v)> <= kMaxVertices);

// Fixed-point vertex, shifted by half a pixel so that pixel i's centre is at kSub * i.
struct Fx {
  i64 x, y;
};

// Round half to even, without a libm call: adding 1.5 * 2^52 leaves no
// fraction bits, so the FPU's default rounding does the work.
inline i64 snap(double v) {
  constexpr double magic = 6755399441055744.0;
  return static_cast<i64>((v * static_cast<double>(kSub) + magic) - magic);
}

inline i64 floor_shift(i64 v) { return v >> kSubBits; }        // floor(v / kSub)
inline i64 ceil_shift(i64 v) { return -((-v) >> kSubBits); }   // ceil(v / kSub)

// floor(m / d) and m mod d for d > 0, with the quotient estimated in double
// (m and d are far below 2^53, so it is off by at most one) and made exact
// by correcting the remainder. Branch-free: the signs are unpredictable.
inline void floor_divmod(i64 m, i64 d, double inv_d, i64& q, i64& r) {
  const double x = static_cast<double>(m) * inv_d;
  q = static_cast<i64>(x);
  q -= static_cast<double>(q) > x;  // truncation -> floor for negative x
  r = m - q * d;
  const i64 below = r >> 63;  // all ones when r < 0
  q += below;
  r += d & below;
  const i64 above = ~((r - d) >> 63);  // all ones when r >= d
  q -= above;  // minus all ones: plus one
  r -= d & above;
}

// The bound an edge a -> b puts on pixel indices of row j, tracked as
// q + r / d = (C(j) - t) / d. For a left edge the row's first pixel is -q,
// for a right edge the last pixel is q.
struct EdgeWalk {
  i64 q, r, d, sq, sr;

  // `inv` is 1 / d, computed ahead for all edges of a polygon so that the
  // divisions overlap instead of each stalling its walk.
  void start(const Fx& a, const Fx& b, i64 row, double inv) {
    const i64 dx = b.x - a.x, dy = b.y - a.y;
    const i64 tie = dy < 0 ? 0 : 1;  // left edges keep centres on them, right edges do not
    const i64 m = dx * (kSub * row - a.y) + dy * a.x - tie;
    d = kSub * (dy < 0 ? -dy : dy);
    floor_divmod(m, d, inv, q, r);
    floor_divmod(kSub * dx, d, inv, sq, sr);
  }
  // Branch-free: whether the remainder carries is as good as random, and a
  // mispredicted branch per edge and row would cost more than the row's work.
  void step() {
    r += sr - d;
    const i64 no_carry = r >> 63;  // all ones when r + sr < d
    q += sq + 1 + no_carry;
    r += d & no_carry;
  }
};

// ORs pixels x0..x1 into a row. Rows carry one spare zero word at the end,
// so the common case (a span of at most 64 pixels, at most two words) needs
// no branch on where the word boundary falls.
inline void set_span(std::uint64_t* row, int x0, int x1) {
  const int w0 = x0 >> 6, w1 = x1 >> 6;
  const std::uint64_t head = ~std::uint64_t{0} << (x0 & 63);
  const std::uint64_t tail = ~std::uint64_t{0} >> (63 - (x1 & 63));
  if (x1 - x0 < 64) {
    const bool one = w0 == w1;
    row[w0] |= one ? head & tail : head;
    row[w0 + 1] |= one ? 0 : tail;
    return;
  }
  row[w0] |= head;
  for (int w = w0 + 1; w < w1; ++w) row[w] = ~std::uint64_t{0};
  row[w1] |= tail;
}

// `rows` rows between two edges, from `row` on (which it advances). The
// walks are copied into locals: the mask's words may alias their integers,
// and the compiler would otherwise reload them after every store.
template <bool Clamp>
inline void walk_band(EdgeWalk& left, EdgeWalk& right, std::uint64_t*& row, int words, int rows, int i_max) {
  EdgeWalk lw = left, rw = right;
  std::uint64_t* out = row;
  for (int k = 0; k < rows; ++k, out += words) {
    i64 lo = -lw.q, hi = rw.q;
    if constexpr (Clamp) {
      lo = std::max<i64>(lo, 0);
      hi = std::min<i64>(hi, i_max);
    }
    if (lo <= hi) set_span(out, static_cast<int>(lo), static_cast<int>(hi));
    lw.step();
    rw.step();
  }
  left = lw;
  right = rw;
  row = out;
}

// Fills a convex polygon with positive orientation (interior where
// (b - a) x (p - a) > 0 for every edge a -> b, y down).
void fill_convex(const Fx* v, int n, BitMask& mask, Box& box) {
  i64 ymin = v[0].y, ymax = v[0].y, xmin = v[0].x, xmax = v[0].x;
  int top = 0;
  for (int i = 1; i < n; ++i) {
    top = v[i].y < ymin ? i : top;
    ymin = std::min(ymin, v[i].y);
    ymax = std::max(ymax, v[i].y);
    xmin = std::min(xmin, v[i].x);
    xmax = std::max(xmax, v[i].x);
  }
  // The last row is exclusive: at a bottom vertex or bottom edge the span is empty.
  const int j0 = static_cast<int>(std::max<i64>(ceil_shift(ymin), 0));
  const int j1 = static_cast<int>(std::min<i64>(floor_shift(ymax - 1), mask.height() - 1));
  const int i0 = static_cast<int>(std::max<i64>(ceil_shift(xmin), 0));
  const int i1 = static_cast<int>(std::min<i64>(floor_shift(xmax), mask.width() - 1));
  if (j0 > j1 || i0 > i1) return;

  // Two turns of the polygon, so that both chains can be walked from the top
  // without wrapping: forwards (e[r] -> e[r + 1]) the edges go down the right
  // side, backwards (e[l] -> e[l - 1] as walked, e[l - 1] -> e[l] as
  // oriented) down the left side. Horizontal edges are stepped over: they
  // only bound the row range, which the exclusive last row and the edge
  // walks already do.
  Fx e[2 * kMaxVertices + 1];
  double inv[2 * kMaxVertices];  // 1 / d of the walk along edge e[i] -> e[i + 1]
  for (int i = 0; i < n; ++i) e[i] = e[i + n] = v[i];
  e[2 * n] = v[0];
  for (int i = 0; i < n; ++i) {
    const i64 dy = e[i + 1].y - e[i].y;
    inv[i] = inv[i + n] = 1.0 / static_cast<double>(kSub * (dy < 0 ? -dy : dy) + (dy == 0));
  }
  int r = top, l = top + n, j = j0;
  auto right_done = [&](i64 y) { return e[r + 1].y < y || e[r + 1].y == e[r].y; };
  auto left_done = [&](i64 y) { return e[l - 1].y < y || e[l - 1].y == e[l].y; };

  // Bands of rows over which the same two edges bound the span. Spans from
  // the edges never leave the polygon's own x range, so they only need
  // clamping when that range leaves the image.
  const bool clamp = ceil_shift(xmin) < 0 || floor_shift(xmax) > mask.width() - 1;
  const int words = mask.words_per_row();
  std::uint64_t* row = mask.row(j0);
  EdgeWalk lw, rw;
  while (right_done(kSub * j)) ++r;
  while (left_done(kSub * j)) --l;
  rw.start(e[r], e[r + 1], j, inv[r]);
  lw.start(e[l - 1], e[l], j, inv[l - 1]);
  for (;;) {
    const int band_end = static_cast<int>(std::min<i64>(floor_shift(std::min(e[r + 1].y, e[l - 1].y)), j1));
    const int rows = band_end - j + 1;
    if (clamp) {
      walk_band<true>(lw, rw, row, words, rows, i1);
    } else {
      walk_band<false>(lw, rw, row, words, rows, i1);
    }
    j = band_end + 1;
    if (j > j1) break;
    // An edge ending exactly on a sample row hands over to the next one
    // there; both give the same bound on that row.
    if (right_done(kSub * j)) {
      while (right_done(kSub * j)) ++r;
      rw.start(e[r], e[r + 1], j, inv[r]);
    }
    if (left_done(kSub * j)) {
      while (left_done(kSub * j)) --l;
      lw.start(e[l - 1], e[l], j, inv[l - 1]);
    }
  }
  box.y0 = std::min(box.y0, j0);
  box.y1 = std::max(box.y1, j1);
  box.w0 = std::min(box.w0, i0 >> 6);
  box.w1 = std::max(box.w1, i1 >> 6);
}

i64 cross(const Fx& o, const Fx& a, const Fx& b) { return (a.x - o.x) * (b.y - o.y) - (a.y - o.y) * (b.x - o.x); }

// Convex after snapping (snapping can bend a nearly straight boundary): no
// turn against the orientation and, from five corners on, y changing
// direction at most twice (a polygon that winds twice turns one way too).
// `v` holds n + 2 points, the first two repeated at the end.
bool is_convex(const Fx* v, int n) {
  bool left_turns = true;
  for (int i = 0; i < n; ++i) left_turns &= cross(v[i], v[i + 1], v[i + 2]) >= 0;
  if (!left_turns) return false;
  if (n <= 4) return true;
  int turns = 0;
  i64 last_dy = 0, first_dy = 0;
  for (int i = 0; i < n; ++i) {
    const i64 dy = v[i + 1].y - v[i].y;
    if (dy == 0) continue;
    if (last_dy == 0) first_dy = dy;
    else if ((dy > 0) != (last_dy > 0)) ++turns;
    last_dy = dy;
  }
  if ((first_dy > 0) != (last_dy > 0)) ++turns;  // the wrap from the last edge to the first
  return turns <= 2;
}

// `v` has room for n + 2 points.
void fill_fixed(Fx* v, int n, BitMask& mask, Box& box) {
  v[n] = v[0];
  i64 area = 0;
  for (int i = 0; i < n; ++i) area += v[i].x * v[i + 1].y - v[i + 1].x * v[i].y;
  if (area == 0) return;
  if (area < 0) std::reverse(v, v + n);
  v[n] = v[0];
  v[n + 1] = v[1];
  if (n == 3 || is_convex(v, n)) {
    fill_convex(v, n, mask, box);
    return;
  }
  // Not convex after snapping: the fan's triangles, each oriented on its own.
  for (int i = 1; i + 1 < n; ++i) {
    Fx t[3] = {v[0], v[i], v[i + 1]};
    const i64 c = cross(t[0], t[1], t[2]);
    if (c == 0) continue;
    if (c < 0) std::swap(t[1], t[2]);
    fill_convex(t, 3, mask, box);
  }
}

Fx to_fixed(const Eigen::Vector2d& p) { return {snap(p.x()) - kSub / 2, snap(p.y()) - kSub / 2}; }

}  // namespace

void fill_projected(const Eigen::Vector3d* corners, int n, BitMask& mask, Box& box) {
  if (n < 3 || n > kMaxVertices) return;
  Fx v[kMaxVertices + 2];
  for (int i = 0; i < n; ++i) v[i] = to_fixed(dehomogenise(corners[i]));
  fill_fixed(v, n, mask, box);
}

void fill_polygons(const std::vector<ScreenPolygon>& polygons, BitMask& mask, Box& box) {
  Fx v[kMaxVertices + 2];
  for (const ScreenPolygon& p : polygons) {
    if (p.count < 3) continue;
    for (int i = 0; i < p.count; ++i) v[i] = to_fixed(p.v[i]);
    fill_fixed(v, p.count, mask, box);
  }
}

namespace {

// One pass over the box for both overloads; without a rim (null) the third
// AND + popcount is compiled out.
template <bool kWithRim>
PairCounts count_and_clear_impl(BitMask& rendered, const BitMask& observation, const BitMask* rim, const Box& box) {
  PairCounts c;
  if (box.empty()) return c;
  std::uint32_t both = 0, mine = 0, near = 0;
  for (int y = box.y0; y <= box.y1; ++y) {
    std::uint64_t* p = rendered.row(y);
    const std::uint64_t* o = observation.row(y);
    const std::uint64_t* r = kWithRim ? rim->row(y) : nullptr;
    for (int w = box.w0; w <= box.w1; ++w) {
      const std::uint64_t bits = p[w];
      mine += static_cast<std::uint32_t>(std::popcount(bits));
      both += static_cast<std::uint32_t>(std::popcount(bits & o[w]));
      if constexpr (kWithRim) near += static_cast<std::uint32_t>(std::popcount(bits & r[w]));
      p[w] = 0;
    }
  }
  c.intersection = both;
  c.rendered = mine;
  c.rim = near;
  return c;
}

}  // namespace

PairCounts count_and_clear(BitMask& rendered, const BitMask& observation, const Box& box) {
  return count_and_clear_impl<false>(rendered, observation, nullptr, box);
}

PairCounts count_and_clear(BitMask& rendered, const BitMask& observation, const BitMask& rim, const Box& box) {
  return count_and_clear_impl<true>(rendered, observation, &rim, box);
}

}  // namespace gtrack::render
