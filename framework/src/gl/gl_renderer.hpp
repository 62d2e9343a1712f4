// The gl backend of Renderer: OpenGL 4.5 core through headless EGL.
//
// One generation of N hypotheses costs, on the GPU side: one buffer upload of
// the parameter vectors (N x dims floats) and of the per-layer count boxes,
// one instanced draw (instance = hypothesis; 32 hypotheses share an R32UI
// layer, each its own bit, merged with the OR logic op; a batch larger than
// the render target's memory budget is drawn in chunks), one compute dispatch
// that reduces |O & P|, |P| and |R & P| per hypothesis, one 12 N-byte copy into a
// persistently mapped buffer and one fence. submit() issues all of it and
// returns; finish() waits on the fence once and reads the counts from the
// mapping. The model, the projection and the observation stay on the GPU
// until they change.
//
// Threads: the constructor leaves the context current on no thread; the first
// thread that calls the renderer makes it current and keeps it until it ends
// (its EGL state is then released), and is the only one that may use the
// renderer meanwhile (another gets EGL_BAD_ACCESS). Destroyed on another
// thread while that one runs, the renderer cannot delete its objects (a
// warning says so): they are freed with the context once the thread that
// used it makes it current no more, or ends.
#pragma once

#include <cstdint>
#include <vector>

#include "gl/egl_context.hpp"
#include "gl/gl_api.hpp"
#include "gl/hypothesis_bounds.hpp"
#include "gtrack/renderer.hpp"

namespace gtrack::gl {

class GlRenderer final : public Renderer {
 public:
  explicit GlRenderer(const RenderOptions& options);
  ~GlRenderer() override;
  GlRenderer(const GlRenderer&) = delete;
  GlRenderer& operator=(const GlRenderer&) = delete;

  std::string name() const override { return "gl"; }
  void set_model(const ArticulatedModel& model) override;
  void set_projection(const Projection& projection, double scale) override;
  ImageSize render_size() const override { return projection_.size; }
  void set_observation(const cv::Mat& mask) override;
  void set_rim(const cv::Mat& rim) override;
  std::uint64_t observation_count() const override { return observation_count_; }

  void submit(const Eigen::MatrixXd& hypotheses) override;
  void finish(std::vector<PairCounts>& out) override;

  cv::Mat render_mask(const Eigen::VectorXd& hypothesis) override;

 private:
  void require_ready(const char* what, Eigen::Index rows) const;
  void reserve_hypotheses(int count);
  void reserve_layers(int layers);
  // Layers drawn at once: the driver's limit, or the memory budget's.
  int chunk_layers() const;
  // Draws and counts hypotheses first .. first+m-1 (at most chunk_layers()
  // layers), their counts copied to their place in the read-back buffer.
  void submit_chunk(const Eigen::MatrixXd& hypotheses, int first, int m);
  void upload_hypotheses(const double* data, int count);
  // Clears the batch's layers (within `counted` only, when given: the
  // union of the boxes the counts are taken in) and draws its hypotheses.
  void draw(int count, const PixelBox* counted = nullptr);
  void wait_for_fence();
  void release() noexcept;

  EglContext context_;
  Api gl_;

  GLuint draw_program_ = 0;
  GLuint count_program_ = 0;
  GLint u_clip_ = -1, u_planes_ = -1, u_draw_dims_ = -1, u_draw_max_links_ = -1, u_hypotheses_ = -1;
  GLuint vao_ = 0;
  GLuint framebuffer_ = 0;
  GLuint target_ = 0;       // R32UI 2D array, one layer per 32 hypotheses
  GLuint observation_ = 0;  // R8UI: bit 0 O, bit 1 the rim
  cv::Mat texture_bits_;      // the observation texture's bytes: bit 0 O, bit 1 the rim
  bool texture_dirty_ = false;  // texture_bits_ not uploaded yet (done by submit())
  GLuint mesh_buffer_ = 0, finger_buffer_ = 0, link_buffer_ = 0;
  GLuint hypothesis_buffer_ = 0, box_buffer_ = 0, count_buffer_ = 0, readback_buffer_ = 0;
  const std::uint32_t* readback_ = nullptr;  // persistent, coherent mapping of readback_buffer_

  int hypothesis_capacity_ = 0;
  int layer_capacity_ = 0;  // layers of target_: at least those of the largest batch so far
  int max_clip_planes_ = 0;
  int count_rows_ = 0;  // rows per count invocation (COUNT_ROWS of count.comp)
  int max_layers_ = 1;  // GL_MAX_ARRAY_TEXTURE_LAYERS
  long target_budget_bytes_ = 0;  // the render target's most memory (GTRACK_GL_TARGET_MB)

  int dims_ = 0;
  int vertices_ = 0;
  double reach_mm_ = 0;
  Projection projection_;  // at render size
  // Where the vertex shader's coordinates start (render_origin): the
  // hypotheses' positions are uploaded less it, computed in double.
  Eigen::Vector3d origin_ = Eigen::Vector3d::Zero();
  bool has_projection_ = false;
  std::uint64_t observation_count_ = 0;

  GLsync fence_ = nullptr;
  int pending_ = -1;  // hypotheses of the batch in flight, -1 when none
  std::vector<float> staging_;
  std::vector<PixelBox> boxes_;
};

}  // namespace gtrack::gl
