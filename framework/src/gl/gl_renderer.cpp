// GlRenderer: model, projection and observation on the GPU; a generation per
// draw + dispatch; counts back through one fence.
#include "gl/gl_renderer.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <numbers>
#include <opencv2/core.hpp>
#include <string>

#include "gl/shader_program.hpp"
#include "gtrack/error.hpp"
#include "gtrack/log.hpp"

namespace gtrack {

namespace gl {

namespace {

// A point near what the projection images, from which the vertex shader's
// float coordinates are taken, so that they are sizes of the gripper rather
// than its distance from the world's origin (a probe placed metres from it,
// where a float's step is half a micrometre): a camera's centre, or for an
// affine projection (a slice) the point imaged at the image's centre that
// lies midway between its clip planes.
Eigen::Vector3d render_origin(const Projection& p) {
  const Eigen::Matrix<double, 3, 4>& m = p.world_to_image;
  const Eigen::Matrix3d a = m.leftCols<3>();
  if (m.row(2).head<3>().norm() > 0) {
    const Eigen::FullPivLU<Eigen::Matrix3d> lu(a);
    if (lu.isInvertible()) {
      const Eigen::Vector3d c = lu.solve(-m.col(3));
      if (c.allFinite()) return c;
    }
    return Eigen::Vector3d::Zero();
  }
  Eigen::MatrixXd rows(2 + static_cast<Eigen::Index>(p.clip_planes.size()), 3);
  Eigen::VectorXd rhs(rows.rows());
  rows.row(0) = m.row(0).head<3>();
  rhs[0] = p.size.width / 2.0 - m(0, 3);
  rows.row(1) = m.row(1).head<3>();
  rhs[1] = p.size.height / 2.0 - m(1, 3);
  for (size_t i = 0; i < p.clip_planes.size(); ++i) {
    const auto k = static_cast<Eigen::Index>(2 + i);
    rows.row(k) = p.clip_planes[i].head<3>().transpose();
    rhs[k] = -p.clip_planes[i][3];
  }
  const Eigen::Vector3d o = rows.completeOrthogonalDecomposition().solve(rhs);
  return o.allFinite() ? o : Eigen::Vector3d::Zero();
}

constexpr int kLayerBits = 32;         // hypotheses per R32UI layer
constexpr int kCountGroupWidth = 32;   // columns per count workgroup
constexpr int kMaxCountRows = 255;     // rows per count invocation: the most count.comp allows
constexpr int kCountsPerHypothesis = 3;  // |O & P|, |P|, |R & P|, as count.comp writes them
constexpr long kDefaultTargetMiB = 256;  // the render target's most memory, GTRACK_GL_TARGET_MB
static_assert(kMaxCountRows * kCountGroupWidth <= 0xFFFF, "a workgroup's counts must fit the 16-bit halves");

// Rows per count invocation. A CPU driver (llvmpipe) runs few threads and
// wants long columns; a GPU wants many short ones to fill its cores.
// GTRACK_GL_COUNT_ROWS (1-255) overrides the choice, for tuning on a device.
int count_rows_for(const std::string& renderer) {
  if (const char* env = std::getenv("GTRACK_GL_COUNT_ROWS"); env && *env) {
    char* end = nullptr;
    const long v = std::strtol(env, &end, 10);
    if (*end != '\0' || v < 1 || v > kMaxCountRows) {
      throw Error(std::string("GTRACK_GL_COUNT_ROWS='") + env + "': expected a whole number from 1 to " +
                  std::to_string(kMaxCountRows));
    }
    return static_cast<int>(v);
  }
  return software_renderer(renderer) ? kMaxCountRows : 32;
}

// The render target's memory budget, in MiB. A batch that needs more layers
// than the budget (or the driver) allows is drawn and counted in chunks.
// GTRACK_GL_TARGET_MB overrides the default.
long target_budget_mib() {
  if (const char* env = std::getenv("GTRACK_GL_TARGET_MB"); env && *env) {
    char* end = nullptr;
    const long v = std::strtol(env, &end, 10);
    if (*end != '\0' || v < 1 || v > 1'000'000) {
      throw Error(std::string("GTRACK_GL_TARGET_MB='") + env + "': expected a whole number of MiB from 1 to 1000000");
    }
    return v;
  }
  return kDefaultTargetMiB;
}
constexpr int kMaxClipPlanes = 8;  // GL_MAX_CLIP_DISTANCES is at least 8, as the cpu backend allows

// Binding points shared with the shaders.
enum Binding : GLuint { kMesh = 0, kFingers = 1, kLinks = 2, kHypotheses = 3, kBoxes = 4, kCounts = 5 };

static_assert(sizeof(ModelVertex) == 16, "ModelVertex must match the std430 MeshVertex of pose.glsl");

int layers_for(int hypotheses) { return (hypotheses + kLayerBits - 1) / kLayerBits; }

// A buffer of at least 16 bytes (empty storage is not allowed), of which the
// first `bytes` come from `data` when given; nothing past them is read.
GLuint make_buffer(const Api& gl, GLsizeiptr bytes, const void* data, GLbitfield flags) {
  GLuint b = 0;
  gl.CreateBuffers(1, &b);
  const GLsizeiptr size = std::max<GLsizeiptr>(bytes, 16);
  if (data == nullptr || size == bytes) {
    gl.NamedBufferStorage(b, size, data, flags);
  } else {
    std::vector<unsigned char> padded(static_cast<size_t>(size), 0);
    if (bytes > 0) std::memcpy(padded.data(), data, static_cast<size_t>(bytes));
    gl.NamedBufferStorage(b, size, padded.data(), flags);
  }
  return b;
}

void delete_buffer(const Api& gl, GLuint& b) {
  if (b != 0) gl.DeleteBuffers(1, &b);
  b = 0;
}

std::string prelude(int count_rows) {
  std::string p = "#version 450 core\n";
  p += "#define MAX_CLIP_PLANES " + std::to_string(kMaxClipPlanes) + "\n";
  p += "#define COUNT_GROUP_WIDTH " + std::to_string(kCountGroupWidth) + "\n";
  p += "#define COUNT_ROWS " + std::to_string(count_rows) + "\n";
  return p;
}

}  // namespace

GlRenderer::GlRenderer(const RenderOptions& options)
    : context_(EglContext::open(ContextRequest{options.egl_device, options.threads})) {
  gl_.load();

  GLint major = 0, minor = 0;
  gl_.GetIntegerv(GL_MAJOR_VERSION, &major);
  gl_.GetIntegerv(GL_MINOR_VERSION, &minor);
  const std::string who = context_.gl_renderer() + " on " + context_.display_label();
  if (major * 10 + minor < 45) {
    throw Error("gl backend: " + who + " offers OpenGL " + std::to_string(major) + "." + std::to_string(minor) +
                ", 4.5 is needed");
  }
  GLint vertex_buffers = 0, clip_distances = 0;
  gl_.GetIntegerv(GL_MAX_VERTEX_SHADER_STORAGE_BLOCKS, &vertex_buffers);
  gl_.GetIntegerv(GL_MAX_CLIP_DISTANCES, &clip_distances);
  if (vertex_buffers < 4) {
    throw Error("gl backend: " + who + " allows " + std::to_string(vertex_buffers) +
                " storage buffers in a vertex shader, 4 are needed");
  }
  max_clip_planes_ = std::min(kMaxClipPlanes, static_cast<int>(clip_distances));
  // gl_Layer from the vertex shader puts every layer in the same draw.
  std::string layer_extension;
  if (gl_.has_extension("GL_ARB_shader_viewport_layer_array")) {
    layer_extension = "GL_ARB_shader_viewport_layer_array";
  } else if (gl_.has_extension("GL_AMD_vertex_shader_layer")) {
    layer_extension = "GL_AMD_vertex_shader_layer";
  } else {
    throw Error("gl backend: " + who +
                " has neither GL_ARB_shader_viewport_layer_array nor GL_AMD_vertex_shader_layer (gl_Layer in a "
                "vertex shader)");
  }

  count_rows_ = count_rows_for(context_.gl_renderer());
  target_budget_bytes_ = target_budget_mib() << 20;
  GLint max_layers = 0;
  gl_.GetIntegerv(GL_MAX_ARRAY_TEXTURE_LAYERS, &max_layers);
  max_layers_ = std::max(1, static_cast<int>(max_layers));
  const std::string head = prelude(count_rows_);
  // The layer extension is the vertex stage's alone: a strict compiler
  // refuses it in other stages.
  draw_program_ = build_program(gl_, head,
                                {{GL_VERTEX_SHADER, {"pose.glsl", "hypotheses.vert"},
                                  "#extension " + layer_extension + " : require\n"},
                                 {GL_FRAGMENT_SHADER, {"hypotheses.frag"}, ""}});
  try {
    count_program_ = build_program(gl_, head, {{GL_COMPUTE_SHADER, {"count.comp"}, ""}});
  } catch (...) {
    gl_.DeleteProgram(draw_program_);
    throw;
  }
  u_clip_ = gl_.GetUniformLocation(draw_program_, "u_clip");
  u_planes_ = gl_.GetUniformLocation(draw_program_, "u_planes");
  u_draw_dims_ = gl_.GetUniformLocation(draw_program_, "u_dims");
  u_draw_max_links_ = gl_.GetUniformLocation(draw_program_, "u_max_links");
  u_hypotheses_ = gl_.GetUniformLocation(count_program_, "u_hypotheses");

  gl_.CreateVertexArrays(1, &vao_);
  gl_.BindVertexArray(vao_);  // core profile draws need one, even with no attributes
  gl_.CreateFramebuffers(1, &framebuffer_);
  gl_.BindFramebuffer(GL_DRAW_FRAMEBUFFER, framebuffer_);

  // Window y = image row: framebuffer row 0 is image row 0, and "top-left"
  // in the fill rule means the image's top-left.
  gl_.ClipControl(GL_UPPER_LEFT, GL_NEGATIVE_ONE_TO_ONE);
  gl_.Enable(GL_COLOR_LOGIC_OP);
  gl_.LogicOp(GL_OR);
  gl_.PixelStorei(GL_UNPACK_ALIGNMENT, 1);
  gl_.PixelStorei(GL_PACK_ALIGNMENT, 4);
  gl_.check("setting up the context");
  logger().info("gl backend: {} ({}), on {}", context_.gl_renderer(), context_.gl_version(),
                 context_.display_label());
  // Left current here, the context would be tied to this thread: another
  // could neither use the renderer (even once this one has ended) nor delete
  // its objects. The first thread that uses it makes it current.
  context_.release_current();
}

GlRenderer::~GlRenderer() { release(); }

void GlRenderer::release() noexcept {
  try {
    context_.make_current();
  } catch (const std::exception& e) {
    // Current on the thread that used the renderer: the objects go with the
    // context, but only once that thread lets it go.
    logger().warn("gl backend: a renderer whose context cannot be made current here (destroyed on a thread "
                  "other than the one that used it, or its context lost) cannot delete its objects: {}",
                  e.what());
    return;
  }
  if (fence_ != nullptr) {
    gl_.ClientWaitSync(fence_, GL_SYNC_FLUSH_COMMANDS_BIT, 10'000'000'000ull);
    gl_.DeleteSync(fence_);
    fence_ = nullptr;
  }
  if (readback_ != nullptr) gl_.UnmapNamedBuffer(readback_buffer_);
  readback_ = nullptr;
  for (GLuint* b : {&mesh_buffer_, &finger_buffer_, &link_buffer_, &hypothesis_buffer_, &box_buffer_,
                    &count_buffer_, &readback_buffer_}) {
    delete_buffer(gl_, *b);
  }
  for (GLuint* t : {&target_, &observation_}) {
    if (*t != 0) gl_.DeleteTextures(1, t);
    *t = 0;
  }
  if (framebuffer_ != 0) gl_.DeleteFramebuffers(1, &framebuffer_);
  if (vao_ != 0) gl_.DeleteVertexArrays(1, &vao_);
  if (draw_program_ != 0) gl_.DeleteProgram(draw_program_);
  if (count_program_ != 0) gl_.DeleteProgram(count_program_);
  framebuffer_ = vao_ = draw_program_ = count_program_ = 0;
}

void GlRenderer::set_model(const ArticulatedModel& model) {
  // The buffers a pending batch's counts come back through may be replaced.
  if (pending_ >= 0) throw Error("gl backend: set_model() while a batch is pending; call finish() first");
  context_.make_current();
  wait_for_fence();
  const auto& mesh = model.mesh();
  if (mesh.empty()) throw Error("gl backend: the gripper model has no triangles");
  const int fingers = model.fingers();
  const int max_links = std::max(1, model.max_links());
  std::vector<float> finger_data, link_data(static_cast<size_t>(fingers * max_links), 0.0f);
  for (int f = 0; f < fingers; ++f) {
    const FingerShape& shape = model.geometry().fingers[static_cast<size_t>(f)];
    const double phi = shape.direction_deg * (std::numbers::pi / 180.0);
    finger_data.insert(finger_data.end(), {float(shape.base_mm.x()), float(shape.base_mm.y()),
                                           float(std::cos(phi)), float(std::sin(phi))});
    for (size_t j = 0; j < shape.links.size(); ++j) {
      link_data[static_cast<size_t>(f * max_links) + j] = float(shape.links[j].length_mm);
    }
  }
  for (GLuint* b : {&mesh_buffer_, &finger_buffer_, &link_buffer_}) delete_buffer(gl_, *b);
  if (model.dims() != dims_) hypothesis_capacity_ = 0;  // the hypothesis buffer is sized in floats
  mesh_buffer_ = make_buffer(gl_, GLsizeiptr(mesh.size() * sizeof(ModelVertex)), mesh.data(), 0);
  finger_buffer_ = make_buffer(gl_, GLsizeiptr(finger_data.size() * sizeof(float)), finger_data.data(), 0);
  link_buffer_ = make_buffer(gl_, GLsizeiptr(link_data.size() * sizeof(float)), link_data.data(), 0);
  gl_.BindBufferBase(GL_SHADER_STORAGE_BUFFER, kMesh, mesh_buffer_);
  gl_.BindBufferBase(GL_SHADER_STORAGE_BUFFER, kFingers, finger_buffer_);
  gl_.BindBufferBase(GL_SHADER_STORAGE_BUFFER, kLinks, link_buffer_);

  dims_ = model.dims();
  vertices_ = static_cast<int>(mesh.size());
  reach_mm_ = model_reach_mm(model);
  gl_.ProgramUniform1i(draw_program_, u_draw_dims_, dims_);
  gl_.ProgramUniform1i(draw_program_, u_draw_max_links_, max_links);
  gl_.check("uploading the model");
}

void GlRenderer::set_projection(const Projection& projection, double scale) {
  context_.make_current();
  wait_for_fence();
  const Projection p = scaled_projection(projection, scale);
  if (static_cast<int>(p.clip_planes.size()) > max_clip_planes_) {
    throw Error("gl backend: the projection has " + std::to_string(p.clip_planes.size()) +
                " clip planes, at most " + std::to_string(max_clip_planes_) + " are supported");
  }
  const int w = p.size.width, h = p.size.height;
  GLint max_size = 0;
  gl_.GetIntegerv(GL_MAX_TEXTURE_SIZE, &max_size);
  if (w > max_size || h > max_size) {
    throw Error("gl backend: render size " + std::to_string(w) + "x" + std::to_string(h) + " exceeds " +
                std::to_string(max_size) + " pixels a side");
  }

  // Clip coordinates from (u w, v w, w): x_ndc = 2u/W - 1 and, with the
  // upper-left clip origin, y_ndc = 1 - 2v/H. z = 0 keeps only w >= 0.
  const Eigen::Matrix<double, 3, 4>& m = p.world_to_image;
  Eigen::Matrix4d clip = Eigen::Matrix4d::Zero();
  clip.row(0) = (2.0 / w) * m.row(0) - m.row(2);
  clip.row(1) = m.row(2) - (2.0 / h) * m.row(1);
  clip.row(3) = m.row(2);
  // A world point x is x' + origin: clip = clip T(origin) x', and a plane
  // (n, d) is (n, d + n.origin).
  const Eigen::Vector3d origin = render_origin(p);
  Eigen::Matrix4d moved = Eigen::Matrix4d::Identity();
  moved.block<3, 1>(0, 3) = origin;
  const Eigen::Matrix4f clip_f = (clip * moved).cast<float>();
  gl_.ProgramUniformMatrix4fv(draw_program_, u_clip_, 1, GL_FALSE, clip_f.data());

  float planes[kMaxClipPlanes * 4];
  for (int i = 0; i < kMaxClipPlanes; ++i) {
    // Unused planes keep everything (0 x + 1 >= 0) and stay disabled.
    Eigen::Vector4d pl(0, 0, 0, 1);
    if (i < static_cast<int>(p.clip_planes.size())) pl = p.clip_planes[static_cast<size_t>(i)];
    pl[3] += pl.head<3>().dot(origin);
    for (int k = 0; k < 4; ++k) planes[4 * i + k] = float(pl[k]);
    if (i < max_clip_planes_) {
      if (i < static_cast<int>(p.clip_planes.size())) {
        gl_.Enable(GL_CLIP_DISTANCE0 + static_cast<GLenum>(i));
      } else {
        gl_.Disable(GL_CLIP_DISTANCE0 + static_cast<GLenum>(i));
      }
    }
  }
  gl_.ProgramUniform4fv(draw_program_, u_planes_, kMaxClipPlanes, planes);

  const bool resized = p.size.width != projection_.size.width || p.size.height != projection_.size.height;
  projection_ = p;
  origin_ = origin;
  has_projection_ = true;
  gl_.Viewport(0, 0, w, h);
  if (resized || observation_ == 0) {
    if (target_ != 0) gl_.DeleteTextures(1, &target_);
    target_ = 0;
    const int layers = layer_capacity_;
    layer_capacity_ = 0;
    reserve_layers(std::clamp(layers, 1, chunk_layers()));
    if (observation_ != 0) gl_.DeleteTextures(1, &observation_);
    gl_.CreateTextures(GL_TEXTURE_2D, 1, &observation_);
    gl_.TextureStorage2D(observation_, 1, GL_R8UI, w, h);
    // Integer textures are incomplete (and read as 0) with linear filtering.
    gl_.TextureParameteri(observation_, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
    gl_.TextureParameteri(observation_, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
    gl_.BindTextureUnit(1, observation_);
  }
  // A new projection starts without an observation or a rim, at any size, as
  // on the cpu backend. No batch reads the texture: the fence was waited for.
  const GLuint zero = 0;
  gl_.ClearTexSubImage(observation_, 0, 0, 0, 0, w, h, 1, GL_RED_INTEGER, GL_UNSIGNED_BYTE, &zero);
  observation_count_ = 0;
  texture_bits_.release();
  texture_dirty_ = false;
  gl_.check("setting the projection");
}

void GlRenderer::set_observation(const cv::Mat& mask) {
  if (!has_projection_) throw Error("gl backend: set_observation() before set_projection()");
  const ImageSize s = projection_.size;
  if (mask.type() != CV_8UC1 || mask.cols != s.width || mask.rows != s.height) {
    throw Error("gl backend: the observation must be CV_8U at the render size " + std::to_string(s.width) + "x" +
                std::to_string(s.height) + ", got " + std::to_string(mask.cols) + "x" + std::to_string(mask.rows) +
                " of type " + std::to_string(mask.type()));
  }
  // Bit 0 of the texture is O, bit 1 the rim (cleared here). The texture is
  // uploaded once, by the next submit(), whatever rim follows.
  cv::compare(mask, 0, texture_bits_, cv::CMP_NE);
  texture_bits_ &= 1;
  observation_count_ = static_cast<std::uint64_t>(cv::countNonZero(texture_bits_));
  texture_dirty_ = true;
}

void GlRenderer::set_rim(const cv::Mat& rim) {
  if (!has_projection_) throw Error("gl backend: set_rim() before set_projection()");
  const ImageSize s = projection_.size;
  if (!rim.empty() && (rim.type() != CV_8UC1 || rim.cols != s.width || rim.rows != s.height)) {
    throw Error("gl backend: the rim must be CV_8U at the render size " + std::to_string(s.width) + "x" +
                std::to_string(s.height) + ", got " + std::to_string(rim.cols) + "x" + std::to_string(rim.rows) +
                " of type " + std::to_string(rim.type()));
  }
  if (texture_bits_.empty()) texture_bits_ = cv::Mat::zeros(s.height, s.width, CV_8UC1);
  texture_bits_ &= 1;
  if (!rim.empty()) {
    cv::Mat bits;
    cv::compare(rim, 0, bits, cv::CMP_NE);
    texture_bits_ |= bits & 2;
  }
  texture_dirty_ = true;
}

void GlRenderer::require_ready(const char* what, Eigen::Index rows) const {
  if (vertices_ == 0) throw Error(std::string("gl backend: ") + what + " before set_model()");
  if (!has_projection_) throw Error(std::string("gl backend: ") + what + " before set_projection()");
  if (rows != dims_) {
    throw Error(std::string("gl backend: ") + what + ": a hypothesis has " + std::to_string(rows) +
                " values, the model needs " + std::to_string(dims_));
  }
}

void GlRenderer::reserve_hypotheses(int count) {
  if (count <= hypothesis_capacity_) return;
  const int capacity = std::max(count, 2 * hypothesis_capacity_);
  // Nothing is reused if the reallocation below fails part way.
  hypothesis_capacity_ = 0;
  if (readback_ != nullptr) gl_.UnmapNamedBuffer(readback_buffer_);
  readback_ = nullptr;
  for (GLuint* b : {&hypothesis_buffer_, &count_buffer_, &readback_buffer_}) delete_buffer(gl_, *b);
  hypothesis_buffer_ =
      make_buffer(gl_, GLsizeiptr(capacity) * dims_ * GLsizeiptr(sizeof(float)), nullptr, GL_DYNAMIC_STORAGE_BIT);
  // The atomics hit a buffer the GPU owns; only the final 12 N bytes are
  // copied into host-visible memory, mapped once for good.
  const GLsizeiptr count_bytes = GLsizeiptr(capacity) * kCountsPerHypothesis * GLsizeiptr(sizeof(std::uint32_t));
  count_buffer_ = make_buffer(gl_, count_bytes, nullptr, 0);
  const GLbitfield map = GL_MAP_READ_BIT | GL_MAP_PERSISTENT_BIT | GL_MAP_COHERENT_BIT;
  readback_buffer_ = make_buffer(gl_, count_bytes, nullptr, map | GL_CLIENT_STORAGE_BIT);
  readback_ = static_cast<const std::uint32_t*>(gl_.MapNamedBufferRange(readback_buffer_, 0, count_bytes, map));
  if (readback_ == nullptr) throw Error("gl backend: cannot map the count buffer");
  gl_.BindBufferBase(GL_SHADER_STORAGE_BUFFER, kHypotheses, hypothesis_buffer_);
  gl_.BindBufferBase(GL_SHADER_STORAGE_BUFFER, kCounts, count_buffer_);
  gl_.check(("allocating buffers for " + std::to_string(capacity) + " hypotheses").c_str());
  hypothesis_capacity_ = capacity;
}

int GlRenderer::chunk_layers() const {
  const long layer_bytes = 4L * projection_.size.width * projection_.size.height;
  const long by_memory = std::max(1L, target_budget_bytes_ / std::max(1L, layer_bytes));
  return static_cast<int>(std::min<long>(max_layers_, by_memory));
}

void GlRenderer::reserve_layers(int layers) {
  // Grow-only: a batch smaller than the largest so far uses the first layers
  // of the target, and nothing is reallocated from one batch to the next.
  // Doubling stops at the chunk size: submit() never asks for more.
  if (layers <= layer_capacity_ && target_ != 0) return;
  const int cap = chunk_layers();
  if (layers > cap) {
    throw Error("gl backend: " + std::to_string(layers) + " layers asked of a render target that holds at most " +
                std::to_string(cap));
  }
  layers = std::min(std::max(layers, 2 * layer_capacity_), cap);
  layer_capacity_ = 0;  // nothing is reused if the reallocation below fails part way
  if (target_ != 0) gl_.DeleteTextures(1, &target_);
  gl_.CreateTextures(GL_TEXTURE_2D_ARRAY, 1, &target_);
  gl_.TextureStorage3D(target_, 1, GL_R32UI, projection_.size.width, projection_.size.height, layers);
  gl_.TextureParameteri(target_, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
  gl_.TextureParameteri(target_, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
  gl_.NamedFramebufferTexture(framebuffer_, GL_COLOR_ATTACHMENT0, target_, 0);  // layered
  gl_.NamedFramebufferDrawBuffer(framebuffer_, GL_COLOR_ATTACHMENT0);
  const GLenum status = gl_.CheckNamedFramebufferStatus(framebuffer_, GL_DRAW_FRAMEBUFFER);
  if (status != GL_FRAMEBUFFER_COMPLETE) {
    throw Error("gl backend: the layered R32UI render target is incomplete (status " + std::to_string(status) + ")");
  }
  gl_.BindTextureUnit(0, target_);
  delete_buffer(gl_, box_buffer_);
  box_buffer_ = make_buffer(gl_, GLsizeiptr(layers) * GLsizeiptr(sizeof(PixelBox)), nullptr, GL_DYNAMIC_STORAGE_BIT);
  gl_.BindBufferBase(GL_SHADER_STORAGE_BUFFER, kBoxes, box_buffer_);
  gl_.check(("allocating a render target of " + std::to_string(layers) + " layers").c_str());
  layer_capacity_ = layers;
}

void GlRenderer::upload_hypotheses(const double* data, int count) {
  staging_.resize(static_cast<size_t>(count) * static_cast<size_t>(dims_));
  std::transform(data, data + staging_.size(), staging_.begin(), [](double v) { return float(v); });
  for (size_t at = 0; at < staging_.size(); at += static_cast<size_t>(dims_)) {
    for (int k = 0; k < 3; ++k) staging_[at + k] = float(data[at + k] - origin_[k]);
  }
  gl_.NamedBufferSubData(hypothesis_buffer_, 0, GLsizeiptr(staging_.size() * sizeof(float)), staging_.data());
}

void GlRenderer::draw(int count, const PixelBox* counted) {
  // Only the layers this batch draws into are cleared, the target keeping
  // the layers of the largest batch so far; and of a batch whose counts are
  // taken within its boxes, only their union: what lies outside is never
  // read (a coarse search's batch of 20-60 layers clears a few per cent of
  // each instead of the whole).
  const GLuint zero = 0;
  const PixelBox whole{0, 0, projection_.size.width, projection_.size.height};
  const PixelBox& area = counted ? *counted : whole;
  if (!area.empty()) {
    gl_.ClearTexSubImage(target_, 0, area.x0, area.y0, 0, area.width(), area.height(), layers_for(count),
                         GL_RED_INTEGER, GL_UNSIGNED_INT, &zero);
  }
  gl_.UseProgram(draw_program_);
  gl_.DrawArraysInstanced(GL_TRIANGLES, 0, vertices_, count);
}

void GlRenderer::submit_chunk(const Eigen::MatrixXd& hypotheses, int first, int m) {
  const int layers = layers_for(m);
  upload_hypotheses(hypotheses.col(first).data(), m);
  static_assert(sizeof(PixelBox) == 4 * sizeof(GLint), "PixelBox must match the ivec4 boxes of count.comp");
  boxes_.assign(static_cast<size_t>(layers), PixelBox{});
  for (int i = 0; i < m; ++i) {
    const Eigen::Vector3d centre = hypotheses.col(first + i).head<3>();
    boxes_[static_cast<size_t>(i / kLayerBits)].unite(hypothesis_box(projection_, centre, reach_mm_));
  }
  int max_w = 0, max_h = 0;
  PixelBox all;  // empty
  for (const PixelBox& b : boxes_) {
    max_w = std::max(max_w, b.width());
    max_h = std::max(max_h, b.height());
    all.unite(b);
  }
  gl_.NamedBufferSubData(box_buffer_, 0, GLsizeiptr(boxes_.size() * sizeof(PixelBox)), boxes_.data());

  const GLsizeiptr count_bytes = GLsizeiptr(m) * kCountsPerHypothesis * GLsizeiptr(sizeof(std::uint32_t));
  gl_.ClearNamedBufferSubData(count_buffer_, GL_R32UI, 0, count_bytes, GL_RED_INTEGER, GL_UNSIGNED_INT, nullptr);
  draw(m, &all);
  if (max_w > 0 && max_h > 0) {
    gl_.UseProgram(count_program_);
    gl_.ProgramUniform1i(count_program_, u_hypotheses_, m);
    gl_.DispatchCompute(GLuint((max_w + kCountGroupWidth - 1) / kCountGroupWidth),
                        GLuint((max_h + count_rows_ - 1) / count_rows_), GLuint(layers));
  }
  gl_.MemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
  const GLintptr offset = GLintptr(first) * kCountsPerHypothesis * GLintptr(sizeof(std::uint32_t));
  gl_.CopyNamedBufferSubData(count_buffer_, readback_buffer_, 0, offset, count_bytes);
}

void GlRenderer::submit(const Eigen::MatrixXd& hypotheses) {
  require_ready("submit()", hypotheses.rows());
  if (pending_ >= 0) throw Error("gl backend: submit() called again before finish()");
  context_.make_current();
  const int n = static_cast<int>(hypotheses.cols());
  if (n == 0) {
    pending_ = 0;
    return;
  }
  reserve_hypotheses(n);
  // At most chunk_layers() layers are drawn at once: a larger batch (a wide
  // coarse search) is drawn and counted chunk by chunk into the same target,
  // each chunk's counts copied to its place in the read-back buffer, with one
  // fence for all of them.
  const int chunk = chunk_layers() * kLayerBits;
  reserve_layers(layers_for(std::min(n, chunk)));
  if (texture_dirty_) {
    // No batch is pending (finish() waited for the last one): the texture
    // is free to change.
    const ImageSize s = projection_.size;
    gl_.TextureSubImage2D(observation_, 0, 0, 0, s.width, s.height, GL_RED_INTEGER, GL_UNSIGNED_BYTE,
                          texture_bits_.data);
    gl_.check("uploading the observation");
    texture_dirty_ = false;
  }
  for (int first = 0; first < n; first += chunk) {
    const int m = std::min(chunk, n - first);
    submit_chunk(hypotheses, first, m);
  }
  fence_ = gl_.FenceSync(GL_SYNC_GPU_COMMANDS_COMPLETE, 0);
  // Start the work now: the caller computes its other cost terms meanwhile.
  gl_.Flush();
  pending_ = n;
}

void GlRenderer::wait_for_fence() {
  if (fence_ == nullptr) return;
  // A batch takes milliseconds; a GPU that has not finished one in a minute
  // has hung or been reset, and waiting longer would hang the run with it.
  // A software renderer is the CPU doing the work: a batch of hundreds of
  // thousands of hypotheses at full size takes minutes, and it cannot hang.
  const int kMaxWaitSeconds = context_.software() ? 3600 : 60;
  for (int waited = 0;; ++waited) {
    const GLenum r = gl_.ClientWaitSync(fence_, GL_SYNC_FLUSH_COMMANDS_BIT, 1'000'000'000ull);
    if (r == GL_ALREADY_SIGNALED || r == GL_CONDITION_SATISFIED) break;
    if (r == GL_WAIT_FAILED || waited + 1 >= kMaxWaitSeconds) {
      gl_.DeleteSync(fence_);
      fence_ = nullptr;
      pending_ = -1;
      if (r == GL_WAIT_FAILED) gl_.check("waiting for the GPU");
      throw Error(r == GL_WAIT_FAILED ? std::string("gl backend: waiting for the GPU failed")
                                      : "gl backend: the GPU did not finish a batch in " +
                                            std::to_string(kMaxWaitSeconds) + " s (hung or reset)");
    }
  }
  gl_.DeleteSync(fence_);
  fence_ = nullptr;
}

void GlRenderer::finish(std::vector<PairCounts>& out) {
  if (pending_ < 0) throw Error("gl backend: finish() without submit()");
  context_.make_current();
  wait_for_fence();
  const int n = pending_;
  pending_ = -1;
  // Once a batch, when its work is done: an error in drawing or counting it
  // is reported as the batch's, not by the next setup step that checks.
  gl_.check("drawing and counting a batch");
  out.resize(static_cast<size_t>(n));
  for (int i = 0; i < n; ++i) {
    const std::uint32_t* c = readback_ + kCountsPerHypothesis * i;
    out[static_cast<size_t>(i)] = PairCounts{c[0], c[1], c[2]};
  }
}

cv::Mat GlRenderer::render_mask(const Eigen::VectorXd& hypothesis) {
  require_ready("render_mask()", hypothesis.size());
  context_.make_current();
  // Commands run in order: a batch in flight keeps its counts, its masks are
  // simply drawn over once it is done with them.
  reserve_hypotheses(1);
  upload_hypotheses(hypothesis.data(), 1);
  draw(1);
  // Layer 0 holds this one hypothesis alone, in bit 0: read as bytes, the
  // texels are 0 or 1, and a quarter as many bytes cross the bus.
  const int w = projection_.size.width, h = projection_.size.height;
  cv::Mat mask(h, w, CV_8UC1);
  gl_.PixelStorei(GL_PACK_ALIGNMENT, 1);
  gl_.GetTextureSubImage(target_, 0, 0, 0, 0, w, h, 1, GL_RED_INTEGER, GL_UNSIGNED_BYTE,
                         GLsizei(mask.total()), mask.data);
  gl_.PixelStorei(GL_PACK_ALIGNMENT, 4);
  gl_.check("reading a mask back");
  mask *= 255;
  return mask;
}

}  // namespace gl

std::unique_ptr<Renderer> make_gl_renderer(const RenderOptions& options) {
  return std::make_unique<gl::GlRenderer>(options);
}

}  // namespace gtrack
