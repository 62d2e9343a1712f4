// The `cpu` backend: poses, projects and fills every hypothesis of a batch
// on a small thread pool, into one bit-packed mask per worker, and counts
// against the bit-packed observation with AND + popcount.
//
// The mesh is filled face by face (faces.hpp) rather than triangle by
// triangle; only faces that a plane or the guard band cuts go through
// clipping. Work per hypothesis is confined to the box its polygons touch:
// the mask is cleared there while counting, so it never needs a full clear.
// Every buffer belongs to one worker and is sized when the model is set, so
// batches allocate nothing.
#include <memory>
#include <string>

#include "gtrack/error.hpp"
#include "gtrack/renderer.hpp"
#include "render/bit_mask.hpp"
#include "render/clip.hpp"
#include "render/faces.hpp"
#include "render/model_poser.hpp"
#include "render/span_raster.hpp"
#include "render/worker_pool.hpp"

namespace gtrack {

namespace {

using render::BitMask;
using render::Box;

// Per worker; aligned so that two workers never share a cache line.
struct alignas(64) Scratch {
  render::ProjectedMesh mesh;
  std::vector<int> cut;                   // faces that need clipping
  std::vector<Eigen::Vector3d> vertices;  // model frame, only when some face needs clipping
  std::vector<ScreenPolygon> polygons;
  Projection model_projection;
  BitMask mask;
};

class CpuRenderer final : public Renderer {
 public:
  explicit CpuRenderer(const RenderOptions& options) : pool_(options.threads) {
    scratch_ = std::make_unique<Scratch[]>(pool_.size());
  }

  std::string name() const override { return "cpu"; }

  void set_model(const ArticulatedModel& model) override {
    poser_ = render::ModelPoser(model);
    faces_ = render::Faces(model);
    // Every worker's buffers at their largest now, so that no batch
    // allocates, even the first one a worker happens to take part in.
    const size_t corners = faces_.corners().size(), faces = faces_.faces().size();
    const size_t vertices = model.mesh().size(), triangles = vertices / 3;
    for (int w = 0; w < pool_.size(); ++w) {
      Scratch& s = scratch_[w];
      s.mesh.image.reserve(corners);
      s.mesh.inside_planes.reserve(corners);
      s.cut.reserve(faces);
      s.vertices.reserve(vertices);
      s.polygons.reserve(2 * triangles);  // a clipped triangle splits in two at most
    }
  }

  void set_projection(const Projection& projection, double scale) override {
    // Checked here: nothing on the workers' path may throw.
    if (projection.clip_planes.size() > static_cast<size_t>(render::kMaxSensorPlanes)) {
      throw Error("cpu renderer: a projection may have at most " + std::to_string(render::kMaxSensorPlanes) +
                  " clip planes, got " + std::to_string(projection.clip_planes.size()));
    }
    projection_ = scaled_projection(projection, scale);
    const ImageSize s = projection_.size;
    observation_.resize(s.width, s.height);
    observation_count_ = 0;
    rim_.resize(s.width, s.height);
    has_rim_ = false;
    for (int w = 0; w < pool_.size(); ++w) {
      scratch_[w].mask.resize(s.width, s.height);
      scratch_[w].model_projection.clip_planes.reserve(projection_.clip_planes.size());
    }
    has_projection_ = true;
  }

  ImageSize render_size() const override { return projection_.size; }

  void set_observation(const cv::Mat& mask) override {
    require_projection();
    const ImageSize s = projection_.size;
    if (mask.type() != CV_8UC1 || mask.cols != s.width || mask.rows != s.height) {
      throw Error("cpu renderer: the observation must be CV_8U " + std::to_string(s.width) + "x" +
                  std::to_string(s.height) + " (the render size), got " + std::to_string(mask.cols) + "x" +
                  std::to_string(mask.rows) + " of type " + std::to_string(mask.type()));
    }
    observation_.pack(mask);
    observation_count_ = observation_.count();
    has_rim_ = false;
  }

  void set_rim(const cv::Mat& rim) override {
    require_projection();
    has_rim_ = false;
    if (rim.empty()) return;
    const ImageSize s = projection_.size;
    if (rim.type() != CV_8UC1 || rim.cols != s.width || rim.rows != s.height) {
      throw Error("cpu renderer: the rim must be CV_8U " + std::to_string(s.width) + "x" + std::to_string(s.height) +
                  " (the render size), got " + std::to_string(rim.cols) + "x" + std::to_string(rim.rows) +
                  " of type " + std::to_string(rim.type()));
    }
    rim_.pack(rim);
    has_rim_ = true;
  }

  std::uint64_t observation_count() const override { return observation_count_; }

  void submit(const Eigen::MatrixXd& hypotheses) override {
    require_ready(hypotheses.rows());
    const int n = static_cast<int>(hypotheses.cols());
    results_.resize(n);
    auto job = [&](int worker, int i) {
      Scratch& s = scratch_[worker];
      Box box;
      fill(hypotheses.col(i).data(), s, box);
      results_[i] = has_rim_ ? render::count_and_clear(s.mask, observation_, rim_, box)
                             : render::count_and_clear(s.mask, observation_, box);
    };
    pool_.run(n, job);
  }

  void finish(std::vector<PairCounts>& out) override { out.assign(results_.begin(), results_.end()); }

  cv::Mat render_mask(const Eigen::VectorXd& hypothesis) override {
    require_ready(hypothesis.size());
    Scratch& s = scratch_[0];
    Box box;
    fill(hypothesis.data(), s, box);
    cv::Mat out = s.mask.unpack();
    s.mask.clear();
    return out;
  }

 private:
  void fill(const double* h, Scratch& s, Box& box) const {
    render::ModelPoser::to_model_frame(h, projection_, s.model_projection);
    poser_.project(h, s.model_projection, faces_.corners(), s.mesh);
    const render::Frustum frustum = render::frustum_of(s.model_projection);
    s.cut.clear();
    for (const auto& f : faces_.faces()) {
      if (faces_.inside(f, s.mesh, frustum)) {
        render::fill_projected(&s.mesh.image[f.first_corner], f.corners, s.mask, box);
      } else {
        s.cut.push_back(static_cast<int>(&f - faces_.faces().data()));
      }
    }
    if (s.cut.empty()) return;
    poser_.pose_model(h, s.vertices);
    s.polygons.clear();
    for (int f : s.cut) faces_.clip(faces_.faces()[f], s.vertices, s.model_projection, frustum, s.polygons);
    render::fill_polygons(s.polygons, s.mask, box);
  }

  void require_projection() const {
    if (!has_projection_) throw Error("cpu renderer: set_projection() must come before rendering");
  }
  void require_ready(Eigen::Index dims) const {
    require_projection();
    if (poser_.empty()) throw Error("cpu renderer: set_model() must come before rendering");
    if (dims != poser_.dims()) {
      throw Error("cpu renderer: a hypothesis has " + std::to_string(dims) + " values, the model needs " +
                  std::to_string(poser_.dims()));
    }
  }

  render::WorkerPool pool_;
  std::unique_ptr<Scratch[]> scratch_;
  render::ModelPoser poser_;
  render::Faces faces_;
  Projection projection_;
  bool has_projection_ = false;
  BitMask observation_;
  std::uint64_t observation_count_ = 0;
  BitMask rim_;
  bool has_rim_ = false;
  std::vector<PairCounts> results_;
};

}  // namespace

std::unique_ptr<Renderer> make_cpu_renderer(const RenderOptions& options) {
  return std::make_unique<CpuRenderer>(options);
}

}  // namespace gtrack
