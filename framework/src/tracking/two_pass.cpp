// The backward pass over a recorded sequence, and the two-pass table.
#include "gtrack/two_pass.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <chrono>
#include <limits>
#include <cmath>
#include <cstdio>
#include <map>
#include <numbers>
#include <optional>
#include <span>

#include "gtrack/error.hpp"
#include "gtrack/frame_source.hpp"
#include "gtrack/log.hpp"
#include "gtrack/results.hpp"
#include "nearest_equivalent.hpp"
#include "pipeline.hpp"

namespace gtrack {

namespace {

// The stimulus as the forward run had it at one frame: seek() makes a fresh
// instance of the configured plugin and feeds it the readings of the
// forward run's frames up to that one. The tracker's own update() calls are
// ignored. The fold bias is turned around: backward in time, a gripper that
// was folding unfolds.
class ReplayedStimulus final : public Stimulus {
 public:
  explicit ReplayedStimulus(const Setup& setup) : loader_(setup.loader), table_(setup.root.table("stimulus")) {}

  void seek(const std::vector<Estimate>& forward, std::size_t k) {
    now_ = loader_->make_stimulus(table_);
    for (std::size_t i = 0; i <= k; ++i) {
      if (forward[i].stimulus) now_->update(*forward[i].stimulus, forward[i].time_s);
    }
  }

  void update(double, double) override {}
  StimulusState state() const override { return now_->state(); }
  double penalty(std::span<const double> joints_deg) const override { return now_->penalty(joints_deg); }
  double fold_fraction() const override { return 1.0 - now_->fold_fraction(); }
  double target_joint_deg(double current_deg) const override { return now_->target_joint_deg(current_deg); }
  std::string reading_label() const override { return now_->reading_label(); }
  std::string reading_unit() const override { return now_->reading_unit(); }

 private:
  std::shared_ptr<PluginLoader> loader_;
  ConfigTable table_;
  std::shared_ptr<Stimulus> now_;
};

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace

std::string smoothing_report(const TwoPassSummary& summary) {
  if (!summary.smoothed) return "orientations not smoothed";
  char text[80];
  std::snprintf(text, sizeof text, "orientations smoothed (%.2f deg on the mean)", summary.smoothing_change_deg);
  return text;
}

double smooth_orientations(const ArticulatedModel& model, std::vector<Estimate>& rows, double sigma) {
  if (!(sigma > 0) || rows.empty()) return 0;
  const std::size_t n = rows.size();
  // Each row as its symmetric equivalent nearest the previous row's.
  std::vector<Eigen::Quaterniond> q(n, Eigen::Quaterniond::Identity());
  std::vector<bool> used(n, false);
  std::vector<Eigen::VectorXd> aligned(n);
  std::optional<std::size_t> previous;
  for (std::size_t i = 0; i < n; ++i) {
    if (rows[i].status == TrackStatus::Lost) continue;
    aligned[i] = previous ? detail::nearest_equivalent(model, rows[i].hypothesis, aligned[*previous]) : rows[i].hypothesis;
    q[i] = Eigen::Quaterniond(rotation_from_euler_deg(aligned[i][3], aligned[i][4], aligned[i][5]));
    used[i] = true;
    previous = i;
  }
  // How much of the image each row rests on: its overlap with the
  // observation, |R&O|, against the table's 90th percentile (a row seen
  // whole and unoccluded), within [kLeast, 1]. A sliver at the image's
  // border or a gripper mostly under an occluder holds its orientation
  // weakly: its weight in the fits is multiplied by the cube of its
  // support, and its own orientation comes mostly from its neighbours'.
  constexpr double kLeast = 0.05;
  const auto reach = static_cast<std::ptrdiff_t>(std::ceil(3 * sigma));
  std::vector<double> overlaps;
  for (std::size_t i = 0; i < n; ++i) {
    if (used[i]) overlaps.push_back(static_cast<double>(rows[i].terms.overlap));
  }
  if (overlaps.empty()) return 0;
  const auto p90 = overlaps.begin() + static_cast<std::ptrdiff_t>(0.9 * static_cast<double>(overlaps.size() - 1));
  std::nth_element(overlaps.begin(), p90, overlaps.end());
  const double full = *p90;
  std::vector<double> support(n, 1.0);  // rows without their overlap (full = 0): all alike
  for (std::size_t i = 0; i < n && full > 0; ++i) {
    if (used[i]) support[i] = std::clamp(static_cast<double>(rows[i].terms.overlap) / full, kLeast, 1.0);
  }
  double change = 0;
  int changed = 0;
  std::vector<Eigen::VectorXd> out(n);
  for (std::size_t i = 0; i < n; ++i) {
    if (!used[i]) continue;
    // The rows around, as rotation vectors relative to this one, fitted by
    // a straight line in the row index (weighted least squares); the line's
    // value here is the correction. A steady turn is kept as it is, also
    // where the window is one-sided (the table's ends, next to lost rows).
    double s0 = 0, s1 = 0, s2 = 0;
    Eigen::Vector3d m0 = Eigen::Vector3d::Zero(), m1 = Eigen::Vector3d::Zero();
    const auto c = static_cast<std::ptrdiff_t>(i);
    for (std::ptrdiff_t j = std::max<std::ptrdiff_t>(0, c - reach);
         j <= std::min<std::ptrdiff_t>(static_cast<std::ptrdiff_t>(n) - 1, c + reach); ++j) {
      if (!used[static_cast<std::size_t>(j)]) continue;
      const double t = static_cast<double>(j - c);
      const double u = support[static_cast<std::size_t>(j)];
      const double w = std::exp(-0.5 * (t / sigma) * (t / sigma)) * u * u * u;
      const Eigen::AngleAxisd d(q[i].conjugate() * q[static_cast<std::size_t>(j)]);
      const Eigen::Vector3d v = d.angle() * d.axis();
      s0 += w;
      s1 += w * t;
      s2 += w * t * t;
      m0 += w * v;
      m1 += w * t * v;
    }
    const double det = s0 * s2 - s1 * s1;
    const Eigen::Vector3d a = det > 1e-9 * s0 * s0 ? Eigen::Vector3d((s2 * m0 - s1 * m1) / det) : Eigen::Vector3d(m0 / s0);
    const Eigen::Quaterniond fitted = a.norm() > 0 ? q[i] * Eigen::Quaterniond(Eigen::AngleAxisd(a.norm(), a.normalized()))
                                                  : q[i];
    Eigen::VectorXd h = aligned[i];
    h.segment<3>(3) = euler_deg_from_rotation(fitted.toRotationMatrix());
    change += a.norm() * 180.0 / std::numbers::pi;
    ++changed;
    out[i] = detail::nearest_equivalent(model, h, rows[i].hypothesis);
  }
  for (std::size_t i = 0; i < n; ++i) {
    if (used[i]) rows[i].hypothesis = out[i];
  }
  return changed ? change / changed : 0;
}

std::vector<int> cheapest_path(const std::vector<std::array<std::array<double, 2>, 2>>& costs) {
  constexpr double kNone = std::numeric_limits<double>::infinity();
  const std::size_t n = costs.size();
  if (n == 0) return {};
  // total[i][c]: the least cost of a path ending in candidate c at frame i;
  // came[i][c]: the candidate of frame i - 1 it came from.
  std::vector<std::array<double, 2>> total(n, {kNone, kNone});
  std::vector<std::array<int, 2>> came(n, {0, 0});
  total[0] = costs[0][0];
  for (std::size_t i = 1; i < n; ++i) {
    for (int to = 0; to < 2; ++to) {
      for (int from = 0; from < 2; ++from) {
        const double t = total[i - 1][from] + costs[i][from][to];
        if (t < total[i][to]) {
          total[i][to] = t;
          came[i][to] = from;
        }
      }
    }
  }
  std::vector<int> path(n, 0);
  path.back() = total.back()[1] < total.back()[0] ? 1 : 0;
  for (std::size_t i = n - 1; i > 0; --i) path[i - 1] = came[i][path[i]];
  return path;
}

TwoPassSummary two_pass(const Setup& setup, const EngineConfig& config, const TrackOptions& options,
                        const std::vector<Estimate>& forward) {
  const auto start = std::chrono::steady_clock::now();
  if (options.input.rfind("camera:", 0) == 0) {
    throw InputError("the backward pass goes back over a recording, not a live camera (" + options.input + ")");
  }
  TwoPassSummary summary;
  if (forward.empty()) return summary;
  const OutputLock lock(options.out_dir);

  // The backward tracker has a Setup of its own: the sensor and the gripper
  // are shared, the stimulus is replayed frame by frame.
  Setup back = setup;
  std::shared_ptr<ReplayedStimulus> replay;
  if (setup.stimulus && setup.loader) {
    replay = std::make_shared<ReplayedStimulus>(setup);
    back.stimulus = replay;
  } else if (setup.stimulus) {
    logger().warn(
        "backward pass: the stimulus plugin cannot be made again (no plugin loader); the pass runs without it");
    back.stimulus = nullptr;
  }
  // It starts from its own coarse search on the last frame, whatever
  // [tracker] initial_pose says of the first.
  EngineConfig back_config = config;
  back_config.tracker.initial_pose.reset();
  Tracker tracker(back, back_config);
  ResultWriter backward_results(options.out_dir / "backward", setup.model().fingers());
  const double lt = config.cost.temporal;
  const auto without_temporal = [lt](const CostTerms& t) { return t.total - lt * t.temporal; };

  logger().info("backward pass over {} frames, from frame {} back to frame {}", forward.size(), forward.back().frame,
                forward.front().frame);
  std::vector<Estimate> backward(forward.size());
  const int n = static_cast<int>(forward.size());
  // Frames are read a block at a time, forward within the block, as many
  // as about 512 MB of images allows (a video: by seeking to the block's
  // first frame, checked against the frames read in order).
  const ImageSize size = setup.sensor->image_size();
  const double frame_bytes = 3.0 * std::max(1, size.width) * std::max(1, size.height);
  const int kBlock = std::clamp(static_cast<int>(512e6 / frame_bytes), 16, 4096);
  const int every = std::max(1, options.range.every);
  const double fps = config.tracker.fps > 0 ? config.tracker.fps : 30.0;
  std::vector<int> indices;
  indices.reserve(forward.size());
  for (const Estimate& f : forward) indices.push_back(f.frame);
  RecordedFrames recording(options.input, size, indices, every, fps);
  recording.set_image_bits(config.tracker.image_bits);
  for (int hi = n; hi > 0 && !summary.cancelled; hi -= kBlock) {
    const int lo = std::max(0, hi - kBlock);
    const std::map<int, cv::Mat> images = recording.read(static_cast<std::size_t>(lo), static_cast<std::size_t>(hi));
    for (int k = hi - 1; k >= lo; --k) {
      if (options.cancel && options.cancel->load()) {
        summary.cancelled = true;
        break;
      }
      const Estimate& f = forward[static_cast<std::size_t>(k)];
      const cv::Mat& image = images.at(f.frame);
      if (replay) replay->seek(forward, static_cast<std::size_t>(k));
      Estimate b = tracker.process(image, f.frame, f.time_s, f.stimulus);
      backward_results.write(b);
      if (b.status == TrackStatus::Lost) ++summary.backward_lost;
      backward[static_cast<std::size_t>(k)] = std::move(b);
    }
  }
  backward_results.close();
  if (summary.cancelled) {
    summary.wall_s = seconds_since(start);
    return summary;
  }

  // The forward run again (the same tracker, seed and stimulus: the same
  // estimates), each backward estimate scored beside it as --score-truth
  // scores a reference: on the forward track's observation and stimulus
  // state, which its search had its full chance on, and (below) with the
  // occlusion allowance each candidate of the previous frame gives.
  Setup again = setup;
  again.stimulus = back.stimulus ? setup.loader->make_stimulus(setup.root.table("stimulus")) : nullptr;
  Tracker forward_again(again, config);
  FrameRange range = options.range;
  range.first = forward.front().frame;
  range.last = forward.back().frame + 1;
  auto source = open_frame_source(options.input, setup.sensor->image_size(), range, fps);
  source->set_image_bits(config.tracker.image_bits);
  source->set_quiet();
  // Read ahead, on a thread of its own, as the forward run was.
  std::atomic<bool> halt_reading{false};
  detail::ReadAhead reader(*source, halt_reading, options.cancel);
  constexpr double kNone = std::numeric_limits<double>::infinity();
  // Per frame, the costs of the two candidates (0 the forward estimate, 1
  // the backward one) on the forward run's conditions, temporal term aside.
  std::vector<std::array<double, 2>> node(forward.size(), {kNone, kNone});
  // Per frame and candidate of the previous frame (the first index), the
  // same costs with the allowance that candidate gives.
  std::vector<std::array<std::array<double, 2>, 2>> edge(forward.size());
  std::vector<Estimate> again_estimates(forward.size());
  const auto candidate = [&](std::size_t i, int which) -> const Estimate& {
    return which == 1 ? backward[i] : again_estimates[i];
  };
  std::size_t k = 0;
  int differ = 0;
  while (k < forward.size()) {
    if (options.cancel && options.cancel->load()) {
      summary.cancelled = true;
      break;
    }
    double waited_s = 0;
    auto frame = reader.next(waited_s);
    if (frame && frame->index < forward[k].frame) continue;
    if (!frame || frame->index != forward[k].frame) {
      throw InputError(options.input + ": frame " + std::to_string(forward[k].frame) +
                       " of the forward run can no longer be read; the two-pass run needs the same input");
    }
    const Estimate& f = forward[k];
    again_estimates[k] = forward_again.process(frame->image, f.frame, f.time_s, f.stimulus);
    const Estimate& e = again_estimates[k];
    if (pose_text(e.hypothesis) != pose_text(f.hypothesis)) ++differ;  // (the forward run may have been read back)
    const Estimate& b = backward[k];
    if (b.status != TrackStatus::Lost) {
      const Eigen::VectorXd b_here = detail::nearest_equivalent(setup.model(), b.hypothesis, e.hypothesis);
      node[k][1] = without_temporal(forward_again.score(b_here));
    }
    if (e.status != TrackStatus::Lost || b.status == TrackStatus::Lost) node[k][0] = without_temporal(e.terms);
    // The same two, each with the occlusion allowance it would have had
    // after either candidate of the previous frame as reported (a path's
    // own story; the forward candidate's reported joints of unseen fingers
    // are filled in, so after it the forward estimate may score a little
    // differently from its own search's allowance):
    // the forward track's allowance comes from its own previous estimate,
    // and where that was wrong under an occluder it makes the right
    // configuration pay for the area the wrong one did not have.
    for (int to = 0; to < 2; ++to) {
      for (int from = 0; from < 2; ++from) {
        edge[k][from][to] = node[k][to];
        if (k == 0 || node[k][to] == kNone || candidate(k - 1, from).status == TrackStatus::Lost) continue;
        const Eigen::VectorXd h =
            to == 0 ? e.hypothesis : detail::nearest_equivalent(setup.model(), b.hypothesis, e.hypothesis);
        edge[k][from][to] = without_temporal(forward_again.score_after(h, candidate(k - 1, from).hypothesis));
      }
    }
    logger().debug("frame {}: two-pass: forward {:.4f}, backward {:.4f}; after forward {:.4f} {:.4f}, after "
                   "backward {:.4f} {:.4f}",
                   f.frame, node[k][0], node[k][1], edge[k][0][0], edge[k][0][1], edge[k][1][0], edge[k][1][1]);
    ++k;
  }
  if (differ > 0) {
    logger().warn("two-pass: the forward run, tracked again, gave other estimates on {} of {} frames", differ, k);
  }
  if (summary.cancelled) {
    summary.wall_s = seconds_since(start);
    return summary;
  }
  // The path through the candidates that minimises their costs plus, from
  // each frame to the next, the temporal term's distance between the two
  // estimates taken, at the same weight λT (a pose prior of zero velocity):
  // where the frame cannot tell the two apart (a flat gripper's tilt
  // mirror), the estimate that continues its neighbours' is taken.
  const auto step = [&](std::size_t i, int from, int to) {
    const Eigen::VectorXd& h = candidate(i, to).hypothesis;
    const Eigen::VectorXd before = detail::nearest_equivalent(setup.model(), candidate(i - 1, from).hypothesis, h);
    return lt * forward_again.temporal_term(h, before);
  };
  std::vector<std::array<std::array<double, 2>, 2>> costs(forward.size());
  for (std::size_t i = 0; i < forward.size(); ++i) {
    for (int from = 0; from < 2; ++from) {
      for (int to = 0; to < 2; ++to) {
        const bool out = node[i][to] == kNone || (i > 0 && node[i - 1][from] == kNone);
        costs[i][from][to] = out ? kNone : edge[i][from][to] + (i > 0 ? step(i, from, to) : 0.0);
      }
    }
  }
  const std::vector<int> path = cheapest_path(costs);
  std::vector<Estimate> taken;
  taken.reserve(forward.size());
  for (std::size_t i = 0; i < forward.size(); ++i) {
    summary.from_backward += path[i];
    taken.push_back(candidate(i, path[i]));
    taken.back().two_pass_source = path[i] == 1 ? "backward" : "forward";
  }
  // Each frame's estimate still carries its search's own scatter, which
  // the neighbouring frames' estimates average out; the orientation, the
  // weakly seen part of it, is averaged over a few frames (docs/tracker.md).
  summary.smoothed = config.tracker.two_pass_smoothing > 0;
  summary.smoothing_change_deg = smooth_orientations(setup.model(), taken, config.tracker.two_pass_smoothing);
  ResultWriter two_pass_results(options.out_dir / "two_pass", setup.model().fingers());
  for (const Estimate& e : taken) two_pass_results.write(e);
  two_pass_results.close();
  summary.frames = static_cast<int>(forward.size());
  summary.wall_s = seconds_since(start);
  return summary;
}

}  // namespace gtrack
