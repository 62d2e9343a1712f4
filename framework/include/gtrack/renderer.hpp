// The hot path: N pose hypotheses in, N pairs of pixel counts out (paper 4).
//
// A Renderer caches the gripper model once, takes the sensor's Projection and
// a render scale (paper: 1/4 of the image side; default 1/2), and holds the current
// observation mask at render size. For a batch of hypotheses (one per column,
// see parameter_space.hpp) it returns, per hypothesis,
//   intersection = |O & P|  and  rendered = |P|,
// from which |O | P| = |O| + |P| - |O & P|, and rim = |R & P| for a second
// mask R (set_rim; the cost's occlusion rim, pixels just outside O). Both backends fill triangles with
// the pixel-centre rule (pixel (i, j) is covered when (i + 0.5, j + 0.5) is
// inside, top-left rule on edges), after clipping against the projection's
// clip planes; a mask is the union of the triangles, never a sum.
//
// submit() starts a batch and returns at once where the backend can work
// asynchronously (gl): the caller computes K(H), S(H) and swarm bookkeeping,
// then finish() waits for the counts.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <memory>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "gtrack/export.hpp"
#include "gtrack/model.hpp"
#include "gtrack/sensor.hpp"

namespace gtrack {

struct PairCounts {
  std::uint32_t intersection = 0;  // |O & P|
  std::uint32_t rendered = 0;      // |P|
  std::uint32_t rim = 0;           // |R & P| (0 while no rim is set)
};

struct RenderOptions {
  std::string backend = "auto";  // "auto" | "gl" | "cpu"
  // render size = round(scale * image size). The paper renders at 1/4 of the
  // image side; at 1/2 the silhouette's sub-pixel shifts from small tilts
  // and folds reach more pixels (docs/tracker.md, "Render scale and the
  // rim's width").
  double scale = 0.5;
  int threads = 0;               // cpu backend worker threads, and llvmpipe's for gl; 0 = hardware concurrency
  std::string egl_device;        // gl: device index or "surfaceless"; "" = GTRACK_EGL_DEVICE or auto
};

class GTRACK_API Renderer {
 public:
  virtual ~Renderer();

  virtual std::string name() const = 0;
  virtual void set_model(const ArticulatedModel& model) = 0;
  // Clears the observation and the rim, whether or not the render size changes.
  virtual void set_projection(const Projection& projection, double scale) = 0;
  virtual ImageSize render_size() const = 0;
  // CV_8U at render_size(); non-zero pixels belong to the observation.
  virtual void set_observation(const cv::Mat& mask) = 0;
  // CV_8U at render_size(); non-zero pixels are counted in PairCounts::rim.
  // An empty Mat clears the rim; set_observation() clears it too. The rim is
  // meant to lie outside O, but nothing requires it.
  virtual void set_rim(const cv::Mat& rim) = 0;
  // |O| of the current observation.
  virtual std::uint64_t observation_count() const = 0;

  virtual void submit(const Eigen::MatrixXd& hypotheses) = 0;
  virtual void finish(std::vector<PairCounts>& out) = 0;
  void evaluate(const Eigen::MatrixXd& hypotheses, std::vector<PairCounts>& out) {
    submit(hypotheses);
    finish(out);
  }

  // One hypothesis as a CV_8U mask (0 / 255) at render_size().
  virtual cv::Mat render_mask(const Eigen::VectorXd& hypothesis) = 0;
};

// Creates a backend. "auto" takes gl when a hardware GPU is found, else cpu.
// Throws gtrack::Error with the reason when the requested backend cannot run.
GTRACK_API std::unique_ptr<Renderer> make_renderer(const RenderOptions& options);
GTRACK_API std::unique_ptr<Renderer> make_cpu_renderer(const RenderOptions& options);
GTRACK_API std::unique_ptr<Renderer> make_gl_renderer(const RenderOptions& options);
// True when a hardware (non-software) GPU is reachable through EGL.
GTRACK_API bool hardware_gpu_available();

// The projection scaled to render resolution.
GTRACK_API Projection scaled_projection(const Projection& projection, double scale);

// Why `scale` is too small for an image of `size` ("" when it is not): a
// render with fewer than 8 pixels on a side has no shape left to compare.
// Said as "renders the WxH image at wxh pixels; expected a scale that keeps
// at least 8 pixels on each side".
GTRACK_API std::string render_scale_problem(ImageSize size, double scale);
// The same projection on a canvas grown by margin_x and margin_y pixels on
// every side: pixel (u, v) becomes (u + margin_x, v + margin_y), so what lies
// beyond the image's borders (up to the margin) is rendered too.
GTRACK_API Projection padded_projection(const Projection& projection, int margin_x, int margin_y);

// Geometry both backends share: the posed, projected and clipped triangles of
// one hypothesis in render pixels (each polygon a fan after clipping). Used by
// the cpu backend, the reference rasteriser in tests and the overlay.
struct ScreenPolygon {
  int count = 0;
  Eigen::Vector2d v[9];  // a triangle clipped by two planes has at most 5; room to spare
};
GTRACK_API void project_and_clip(const std::vector<Eigen::Vector3d>& world_triangles,
                                 const Projection& render_projection, std::vector<ScreenPolygon>& out);

}  // namespace gtrack
