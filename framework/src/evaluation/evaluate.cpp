// Aggregating per-frame errors: in view, out of view, lost, recovery.
#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <optional>

#include "gtrack/error.hpp"
#include "gtrack/evaluation.hpp"

namespace gtrack {

namespace {

// An estimate off the gripper: its endpoints further than the threshold,
// in 3D or across the viewing axis as the options say.
bool off_track(const FrameErrors& e, const EvalOptions& options) {
  return (options.off_track_in_plane ? e.endpoint_inplane_um : e.endpoint_um) > options.off_track_endpoint_um;
}

ErrorStats stats(const std::vector<double>& v) {
  ErrorStats s;
  s.count = static_cast<int>(v.size());
  if (v.empty()) return s;
  double sum = 0, sq = 0;
  for (double x : v) {
    sum += x;
    s.max = std::max(s.max, x);
  }
  s.mean = sum / v.size();
  for (double x : v) sq += (x - s.mean) * (x - s.mean);
  s.std = std::sqrt(sq / v.size());
  std::vector<double> sorted = v;
  const size_t mid = sorted.size() / 2;
  std::nth_element(sorted.begin(), sorted.begin() + static_cast<std::ptrdiff_t>(mid), sorted.end());
  s.median = sorted[mid];
  if (sorted.size() % 2 == 0) {
    s.median = 0.5 * (s.median + *std::max_element(sorted.begin(), sorted.begin() + static_cast<std::ptrdiff_t>(mid)));
  }
  return s;
}

// Share of the model inside the image, judged from its endpoints and palm
// centre (when the truth file does not say).
double in_view_from_sensor(const ArticulatedModel& model, const Sensor& sensor, const Eigen::VectorXd& h) {
  auto pts = model.link_endpoints(h);
  pts.push_back(h.head<3>());
  const ImageSize size = sensor.image_size();
  int inside = 0;
  for (const auto& p : pts) {
    const auto uv = sensor.project(p);
    if (uv && uv->x() >= 0 && uv->y() >= 0 && uv->x() < size.width && uv->y() < size.height) ++inside;
  }
  return static_cast<double>(inside) / pts.size();
}

}  // namespace

ErrorStats pooled(const std::vector<ErrorStats>& parts) {
  ErrorStats out;
  double sum = 0, squares = 0;
  for (const ErrorStats& p : parts) {
    if (p.count == 0) continue;
    out.max = out.count ? std::max(out.max, p.max) : p.max;
    out.count += p.count;
    sum += p.count * p.mean;
    squares += p.count * (p.std * p.std + p.mean * p.mean);
  }
  if (out.count > 0) {
    out.mean = sum / out.count;
    out.std = std::sqrt(std::max(0.0, squares / out.count - out.mean * out.mean));
  }
  out.median = std::numeric_limits<double>::quiet_NaN();
  return out;
}

void ErrorSet::add(const FrameErrors& e) {
  const double v[9] = {e.position_um, e.inplane_um,  e.depth_um,    e.orientation_deg, e.joint_deg,
                       e.endpoint_um, e.axis_deg[0], e.axis_deg[1], e.axis_deg[2]};
  for (int i = 0; i < 9; ++i) values_[i].push_back(v[i]);
}

void ErrorSet::finish() {
  ErrorStats* out[9] = {&position_um, &position_inplane_um, &depth_um,    &orientation_deg, &joint_deg,
                        &endpoint_um, &axis_deg[0],         &axis_deg[1], &axis_deg[2]};
  for (int i = 0; i < 9; ++i) *out[i] = stats(values_[i]);
}

Evaluation evaluate(const ArticulatedModel& model, const PoseTable& truth, const PoseTable& estimates,
                    const EvalOptions& options, const Sensor* sensor) {
  if (truth.fingers != model.fingers()) {
    throw InputError("the ground truth has " + std::to_string(truth.fingers) + " joint columns, the model has " +
                     std::to_string(model.fingers()) + " fingers");
  }
  Evaluation ev;
  ev.options = options;
  std::map<int, const PoseRow*> by_frame;
  for (const auto& r : estimates.rows) by_frame[r.frame] = &r;
  const bool dims_match = estimates.fingers == model.fingers();
  const std::optional<Projection> projection = sensor ? std::optional<Projection>(sensor->projection()) : std::nullopt;
  const Eigen::Vector3d axis = projection ? viewing_axis(*projection) : Eigen::Vector3d::UnitZ();
  const SensorFrame frame = sensor ? sensor_frame(*sensor) : SensorFrame{};
  std::vector<double> unmirrored;  // orientation errors of in-view frames that are no tilt mirror
  double mirrored_sum = 0, branch_sum = 0, orientation_sum = 0;

  // Frame by frame, whatever the table's order: a return into view and the
  // recovery after it are read from consecutive frames.
  std::vector<const PoseRow*> in_order;
  for (const PoseRow& t : truth.rows) in_order.push_back(&t);
  std::stable_sort(in_order.begin(), in_order.end(), [](const PoseRow* a, const PoseRow* b) { return a->frame < b->frame; });
  for (const PoseRow* row : in_order) {
    const PoseRow& t = *row;
    FrameEvaluation fe;
    fe.frame = t.frame;
    auto iv = t.extra.find("in_view");
    fe.in_view = iv != t.extra.end() ? iv->second : sensor ? in_view_from_sensor(model, *sensor, t.h) : 1.0;
    fe.out_of_view = fe.in_view < options.out_of_view_below;
    auto it = by_frame.find(t.frame);
    fe.has_estimate = it != by_frame.end() && dims_match;
    if (fe.has_estimate) {
      fe.status = it->second->status;
      fe.lost = fe.status == "lost" || !it->second->h.allFinite();
    } else {
      fe.lost = true;
      ++ev.missing_frames;
    }
    if (fe.status == "search") ++ev.search_frames;
    ++ev.frames;
    (fe.out_of_view ? ev.out_of_view_frames : ev.in_view_frames)++;
    if (fe.lost) {
      ++ev.lost_frames;
      if (!fe.out_of_view) ++ev.lost_in_view_frames;
    } else {
      const Eigen::Vector3d sight =
          projection ? line_of_sight(*projection, t.h.head<3>()) : Eigen::Vector3d::UnitZ();
      // Compared in the sensor's own frame, so that the per-axis errors are
      // about the image's axes and the line of sight (the others do not
      // depend on the frame).
      fe.errors = compare_to_truth(model, frame.from_world(t.h), frame.from_world(it->second->h),
                                   frame.axes.transpose() * sight, frame.axes.transpose() * axis);
      if (fe.out_of_view) {
        ev.out_of_view.add(fe.errors);
      } else {
        ev.in_view.add(fe.errors);
        ++ev.evaluated_frames;
        orientation_sum += fe.errors.orientation_deg;
        if (fe.errors.tilt_branch) {
          ++ev.tilt_branch_frames;
          branch_sum += fe.errors.orientation_deg;
        }
        if (fe.errors.tilt_mirror) {
          ++ev.tilt_mirror_frames;
          mirrored_sum += fe.errors.orientation_deg;
        } else {
          unmirrored.push_back(fe.errors.orientation_deg);
        }
        if (off_track(fe.errors, options)) ++ev.off_track_frames;
      }
    }
    ev.per_frame.push_back(std::move(fe));
  }
  ev.in_view.finish();
  ev.out_of_view.finish();
  ev.tilt_mirror_orientation_share = orientation_sum > 0 ? mirrored_sum / orientation_sum : 0;
  ev.orientation_without_tilt_mirror_deg = stats(unmirrored);
  ev.tilt_branch_orientation_share = orientation_sum > 0 ? branch_sum / orientation_sum : 0;

  // Recovery: after each stretch out of view, frames until the estimate is
  // back on the gripper.
  const auto& pf = ev.per_frame;
  for (size_t i = 1; i < pf.size(); ++i) {
    if (!(pf[i - 1].out_of_view && !pf[i].out_of_view)) continue;
    RecoveryEpisode ep;
    ep.returned_at = pf[i].frame;
    size_t j = i;
    for (; j < pf.size() && !pf[j].out_of_view; ++j) {
      const bool on = !pf[j].lost && !off_track(pf[j].errors, options);
      if (on) {
        ep.recovered = true;
        break;
      }
    }
    ep.frames_to_recover = static_cast<int>(j - i);
    ev.frames_lost_after_return += ep.frames_to_recover;
    ev.recovery.push_back(ep);
  }
  return ev;
}

}  // namespace gtrack
