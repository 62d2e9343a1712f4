// Reading the engine's tables: [observation] [pso] [cost] [render] [search] [tracker].
#include "gtrack/engine_config.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <fmt/format.h>
#include <limits>

#include "gtrack/error.hpp"
#include "gtrack/setup.hpp"

namespace gtrack {

namespace {

const std::vector<std::string> kEngineTables = {"observation", "pso", "cost", "render", "search", "tracker"};
// Tables other subcommands read from the same file; `track` ignores them.
const std::vector<std::string> kOtherTables = {"synth", "sweep", "bench", "demo", "eval"};

ObservationConfig read_observation(const ConfigTable& t, const Sensor& sensor) {
  ObservationConfig o;
  o.color_space = observation_color_space(t, sensor);
  const Range hue = Range::closed(0, 180), byte = Range::closed(0, 255);
  o.hue_min = t.number_or("hue_min", o.hue_min, hue);
  o.hue_max = t.number_or("hue_max", o.hue_max, hue);
  o.saturation_min = t.number_or("saturation_min", o.saturation_min, byte);
  o.saturation_max = t.number_or("saturation_max", o.saturation_max, byte);
  o.value_min = t.number_or("value_min", o.value_min, byte);
  o.value_max = t.number_or("value_max", o.value_max, byte);
  o.luminance_min = t.number_or("luminance_min", o.luminance_min, byte);
  o.luminance_max = t.number_or("luminance_max", o.luminance_max, byte);
  o.open_kernel_px = static_cast<int>(t.integer_or("open_kernel_px", o.open_kernel_px, Range::closed(0, 101)));
  o.downscale_threshold =
      t.number_or("downscale_threshold", o.downscale_threshold, {0.0, 1.0, true, false});
  o.roi = t.boolean_or("roi", o.roi);
  o.roi_margin_px = t.number_or("roi_margin_px", o.roi_margin_px, Range::closed(0, 65536));
  o.prior = t.boolean_or("prior", o.prior);
  o.prior_sigma_px = t.number_or("prior_sigma_px", o.prior_sigma_px, Range::positive());
  o.prior_threshold = t.number_or("prior_threshold", o.prior_threshold, {0.0, 1.0, true, true});
  if (o.saturation_min > o.saturation_max) t.fail("saturation_min", "must not exceed saturation_max");
  if (o.value_min > o.value_max) t.fail("value_min", "must not exceed value_max");
  if (o.luminance_min > o.luminance_max) t.fail("luminance_min", "must not exceed luminance_max");
  const ImageSize size = sensor.image_size();
  const auto rectangles = t.has("exclude_px") ? t.number_rows("exclude_px", 4, Range::closed(0, 65536))
                                               : std::vector<std::vector<double>>{};
  for (const auto& r : rectangles) {
    if (r[0] != std::floor(r[0]) || r[1] != std::floor(r[1]) || r[2] != std::floor(r[2]) || r[3] != std::floor(r[3]) ||
        r[2] < 1 || r[3] < 1 || r[0] + r[2] > size.width || r[1] + r[3] > size.height) {
      t.fail("exclude_px", fmt::format("[{:g}, {:g}, {:g}, {:g}]: expected [x, y, width, height] in whole pixels, "
                                       "width and height at least 1, within the {}x{} image",
                                       r[0], r[1], r[2], r[3], size.width, size.height));
    }
    o.exclude_px.emplace_back(static_cast<int>(r[0]), static_cast<int>(r[1]), static_cast<int>(r[2]),
                              static_cast<int>(r[3]));
  }
  return o;
}

PsoConfig read_pso(const ConfigTable& t) {
  PsoConfig p;
  p.particles = static_cast<int>(t.integer_or("particles", p.particles, Range::closed(2, 1 << 16)));
  p.generations = static_cast<int>(t.integer_or("generations", p.generations, Range::closed(1, 1 << 16)));
  p.inertia = t.number_or("inertia", p.inertia, Range::closed(0, 1.5));
  p.c = t.number_or("c", p.c, Range::closed(0, 10));
  p.randomize_every = static_cast<int>(t.integer_or("randomize_every", p.randomize_every, Range::non_negative()));
  p.randomize_fraction = t.number_or("randomize_fraction", p.randomize_fraction, {0.0, 1.0, true, false});
  p.max_velocity_fraction = t.number_or("max_velocity_fraction", p.max_velocity_fraction, Range::non_negative());
  p.seed = static_cast<std::uint64_t>(t.integer_or("seed", static_cast<long long>(p.seed), Range::non_negative()));
  return p;
}

CostWeights read_cost(const ConfigTable& t) {
  CostWeights c;
  // Weights past 1e6 make the terms' sum overflow what the tables can show;
  // a sigma under 0.01 deg makes a term of any change infinite.
  const Range weight = Range::closed(0, 1e6);
  c.dice = t.number_or("lambda_dice", c.dice, {0.0, 1e6, true, false});  // 0: the image would not count
  c.kinematic = t.number_or("lambda_kinematic", c.kinematic, weight);
  c.stimulus = t.number_or("lambda_stimulus", c.stimulus, weight);
  c.temporal = t.number_or("lambda_temporal", c.temporal, weight);
  c.temporal_joint_sigma_deg =
      t.number_or("temporal_joint_sigma_deg", c.temporal_joint_sigma_deg, Range::closed(0.0, 180.0));
  if (c.temporal_joint_sigma_deg > 0 && c.temporal_joint_sigma_deg < 0.01) {
    t.fail("temporal_joint_sigma_deg", fmt::format("value {:g} is out of range; expected 0 (the joints left out) or a "
                                                   "number in [0.01, 180]",
                                                   c.temporal_joint_sigma_deg));
  }
  c.coherence = t.number_or("lambda_coherence", c.coherence, weight);
  c.coherence_sigma_deg = t.number_or("coherence_sigma_deg", c.coherence_sigma_deg, Range::closed(0.01, 180.0));
  c.occlusion_discount = t.number_or("occlusion_discount", c.occlusion_discount, Range::closed(0.0, 1.0));
  c.occlusion_budget = t.number_or("occlusion_budget", c.occlusion_budget, Range::closed(0.0, 4.0));
  c.occlusion_tolerance = t.number_or("occlusion_tolerance", c.occlusion_tolerance, Range::closed(0.0, 1.0));
  c.occlusion_growth_weight =
      t.number_or("occlusion_growth_weight", c.occlusion_growth_weight, Range::closed(0.0, 1.0));
  c.occlusion_rim_px =
      static_cast<int>(t.integer_or("occlusion_rim_px", c.occlusion_rim_px, Range::closed(0, 16)));
  return c;
}

RenderOptions read_render(const ConfigTable& t, const Sensor& sensor) {
  RenderOptions r;
  r.backend = t.choice_or("backend", r.backend, {"auto", "gl", "cpu"});
  r.scale = t.number_or("scale", r.scale, {0.0, 1.0, true, false});
  if (const std::string small = render_scale_problem(sensor.image_size(), r.scale); !small.empty()) t.fail("scale", small);
  r.threads = static_cast<int>(t.integer_or("threads", r.threads, Range::closed(0, 1024)));
  r.egl_device = t.string_or("egl_device", r.egl_device);
  // Whether the device exists is the gl backend's to say; the form is known here.
  const std::string& d = r.egl_device;
  std::string lower = d;
  for (char& c : lower) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  if (!(d.empty() || lower == "surfaceless" ||
        (d.size() <= 6 && std::all_of(d.begin(), d.end(), [](char c) { return c >= '0' && c <= '9'; })))) {
    t.fail("egl_device", "'" + shown(d, 60) + "'; expected a device index (0, 1, ...), \"surfaceless\" or \"\" (any)");
  }
  return r;
}

Eigen::Vector3d vec3(const ConfigTable& t, const char* key, const Eigen::Vector3d& fallback) {
  const auto v = t.numbers_or(key, {fallback.x(), fallback.y(), fallback.z()}, 3);
  return {v[0], v[1], v[2]};
}

// Corner `k` (0..7) of the box [lo, hi].
Eigen::Vector3d box_corner(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi, int k) {
  return {(k & 1) ? hi.x() : lo.x(), (k & 2) ? hi.y() : lo.y(), (k & 4) ? hi.z() : lo.z()};
}

// Whether the box [lo, hi] may hold a point the sensor images: false when all
// its corners lie outside one of the half-spaces whose intersection is the
// view (in front of the camera, inside each image border, each clip plane).
bool box_meets_view(const Projection& p, const Eigen::Vector3d& lo, const Eigen::Vector3d& hi) {
  const Eigen::RowVector4d u = p.world_to_image.row(0), v = p.world_to_image.row(1), w = p.world_to_image.row(2);
  std::vector<Eigen::RowVector4d> halves = {w, u, p.size.width * w - u, v, p.size.height * w - v};
  for (const auto& c : p.clip_planes) halves.push_back(c.transpose());
  for (const auto& plane : halves) {
    bool any_inside = false;
    for (int corner = 0; corner < 8 && !any_inside; ++corner) {
      any_inside = plane.dot(box_corner(lo, hi, corner).homogeneous()) >= 0;
    }
    if (!any_inside) return false;
  }
  return true;
}

std::string vec_text(const Eigen::Vector3d& v) {
  char buf[96];
  const auto shown = [](double x) { return std::abs(x) < 1e-9 ? 0.0 : x; };  // no 2.2e-16 or -0
  std::snprintf(buf, sizeof buf, "[%g, %g, %g]", shown(v.x()), shown(v.y()), shown(v.z()));
  return buf;
}

SearchConfig read_search(const ConfigTable& t, const Sensor& sensor, const SensorFrame& frame, double radius) {
  // Default box: the field of view around the nominal position, grown by the
  // model's radius so that a gripper half out of view is still reachable.
  const ImageSize size = sensor.image_size();
  const Eigen::Vector2d pixel = pixel_size_mm(sensor);
  const double half = 0.5 * std::max(size.width * pixel.x(), size.height * pixel.y()) + radius;
  const Eigen::Vector3d nominal = sensor.nominal_position_mm();
  SearchConfig s;
  s.position_min_mm = vec3(t, "position_min_mm", nominal.array() - half);
  s.position_max_mm = vec3(t, "position_max_mm", nominal.array() + half);
  // A bound past a full turn either way is no bound on an angle.
  const auto angles = [&](const char* key, const Eigen::Vector3d& fallback) {
    const auto v = t.numbers_or(key, {fallback.x(), fallback.y(), fallback.z()}, 3, Range::closed(-360, 360));
    return Eigen::Vector3d(v[0], v[1], v[2]);
  };
  s.rotation_min_deg = angles("rotation_min_deg", s.rotation_min_deg);
  s.rotation_max_deg = angles("rotation_max_deg", s.rotation_max_deg);
  for (int i = 0; i < 3; ++i) {
    if (!(s.position_min_mm[i] < s.position_max_mm[i])) t.fail("position_min_mm", "must be below position_max_mm");
    if (!(s.rotation_min_deg[i] < s.rotation_max_deg[i])) t.fail("rotation_min_deg", "must be below rotation_max_deg");
  }
  const Projection projection = sensor.projection();
  if (!box_meets_view(projection, s.position_min_mm.array() - radius, s.position_max_mm.array() + radius)) {
    t.fail("position_min_mm", "the box up to position_max_mm lies wholly outside the sensor's view, the model's "
                              "radius included, so no gripper in it can be seen; expected a box about the field of "
                              "view, such as the default around " +
                                  vec_text(sensor.nominal_position_mm()) + " mm");
  }
  // The search runs in the sensor's own frame (SensorFrame), which turns
  // about the nominal position: the default box is the same cube there. A
  // box given in the world bounds the search there by the box about its
  // corners, and the positions searched are kept within the world's box.
  if (!frame.is_world() && (t.has("position_min_mm") || t.has("position_max_mm"))) {
    s.world_box = ParameterSpace::PositionBox{frame.axes, frame.origin, s.position_min_mm, s.position_max_mm};
    Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
    for (int corner = 0; corner < 8; ++corner) {
      const Eigen::Vector3d c = frame.point_from_world(box_corner(s.world_box->lower, s.world_box->upper, corner));
      lo = lo.cwiseMin(c);
      hi = hi.cwiseMax(c);
    }
    s.position_min_mm = lo;
    s.position_max_mm = hi;
  }
  return s;
}

// Why a configuration, `given` in the world and `h` in the sensor's frame,
// lies outside `space`: its first value out of its bounds, in the terms the
// config gives them (positions in the world, angles in the sensor's frame).
std::string outside(const ParameterSpace& space, const SensorFrame& frame, const Eigen::VectorXd& given,
                    const Eigen::VectorXd& h) {
  const auto out_of = [&](int d, double v, double lo, double hi, const std::string& where) {
    char text[160];
    std::snprintf(text, sizeof text, "%s is %g, outside [%g, %g]", space.names[d].c_str(), v, lo, hi);
    return text + (" (" + where + ")");
  };
  for (int d = 0; d < 3; ++d) {
    if (const auto& box = space.position_box) {
      if (given[d] < box->lower[d] || given[d] > box->upper[d]) {
        return out_of(d, given[d], box->lower[d], box->upper[d], "[search] bounds");
      }
    } else if (h[d] < space.lower[d] || h[d] > space.upper[d]) {
      if (frame.is_world()) return out_of(d, h[d], space.lower[d], space.upper[d], "[search] bounds");
      return "its position lies outside the default [search] box, the cube about the sensor's nominal position " +
             vec_text(frame.origin) + " mm in the sensor's frame";
    }
  }
  for (int d = 3; d < space.dims(); ++d) {
    if (space.periodic[d] || (h[d] >= space.lower[d] && h[d] <= space.upper[d])) continue;
    if (d >= kPoseDims) return out_of(d, h[d], space.lower[d], space.upper[d], "the gripper's joint limits");
    if (frame.is_world()) return out_of(d, h[d], space.lower[d], space.upper[d], "[search] bounds");
    return out_of(d, h[d], space.lower[d], space.upper[d],
                  "the angles taken in the sensor's frame, where this pose is rx, ry, rz = " +
                      vec_text(h.segment<3>(3)) + " deg; see [search] rotation_min_deg, rotation_max_deg");
  }
  return "a value is not a finite number";
}

TrackerConfig read_tracker(const ConfigTable& t, const ArticulatedModel& model, const ParameterSpace& space,
                           const SensorFrame& frame) {
  TrackerConfig c;
  const double r = model.radius_mm();
  // Depth is the weakly observed direction (near-orthographic views): a
  // quarter of the in-plane spread, so that a flat cost in depth does not
  // let it random-walk from frame to frame.
  const std::vector<double> spread_default = {0.1 * r, 0.1 * r, 0.025 * r, 10, 10, 10, 10};
  const auto spread = t.numbers_or("init_spread", spread_default, 7, Range::closed(0, 360));
  // A spread so small that the temporal term, which it scales, makes any
  // change infinite: 0 (held) or at least 0.1 um and 0.001 deg.
  static const char* const kSpreadNames[7] = {"x", "y", "z", "rx", "ry", "rz", "the joints"};
  for (int i = 0; i < 7; ++i) {
    const double least = i < 3 ? 1e-4 : 1e-3;
    if (spread[i] > 0 && spread[i] < least) {
      t.fail("init_spread", fmt::format("value {:g} for {} is out of range; expected 0 or at least {:g} {}", spread[i],
                                        kSpreadNames[i], least, i < 3 ? "mm" : "deg"));
    }
    c.init_spread[i] = spread[i];
  }
  const auto pose = t.numbers_or("initial_pose", {});
  if (!pose.empty()) {
    if (static_cast<int>(pose.size()) != model.dims()) {
      t.fail("initial_pose", "expected " + std::to_string(model.dims()) +
                                 " values x,y,z (mm), rx,ry,rz (deg), q1..qF (deg), got " +
                                 std::to_string(pose.size()));
    }
    const Eigen::VectorXd given = Eigen::Map<const Eigen::VectorXd>(pose.data(), model.dims());
    const Eigen::VectorXd h = frame.from_world(given);
    if (!space.contains(h)) {
      t.fail("initial_pose", "lies outside what the tracker searches: " + outside(space, frame, given, h));
    }
    c.initial_pose = h;
  }
  c.fps = tracker_fps(t);
  c.image_bits = static_cast<int>(t.integer_or("image_bits", c.image_bits, Range::closed(8, 16)));
  if (t.has("default_stimulus")) c.default_stimulus = t.number("default_stimulus", Range::closed(-1e9, 1e9));
  c.lost_dice = t.number_or("lost_dice", c.lost_dice, {0.0, 1.0, true, false});
  c.reinit_after_lost = static_cast<int>(t.integer_or("reinit_after_lost", c.reinit_after_lost, Range::closed(1, 1e6)));
  c.coarse_rz_steps = static_cast<int>(t.integer_or("coarse_rz_steps", c.coarse_rz_steps, Range::closed(1, 360)));
  c.coarse_candidates = static_cast<int>(t.integer_or("coarse_candidates", c.coarse_candidates, Range::closed(1, 64)));
  c.coarse_wide_tilts = t.boolean_or("coarse_wide_tilts", c.coarse_wide_tilts);
  c.coarse_border_steps =
      static_cast<int>(t.integer_or("coarse_border_steps", c.coarse_border_steps, Range::closed(0, 8)));
  c.mirror_check = t.boolean_or("mirror_check", c.mirror_check);
  c.redetect_dice = t.number_or("redetect_dice", c.redetect_dice, Range::closed(0.0, 1.0));
  c.redetect_tilt_directions = static_cast<int>(
      t.integer_or("redetect_tilt_directions", c.redetect_tilt_directions, Range::closed(0, 36)));
  c.mirror_particles = static_cast<int>(t.integer_or("mirror_particles", c.mirror_particles, Range::closed(0, 1 << 16)));
  c.refine_spread = t.number_or("refine_spread", c.refine_spread, Range::closed(0.0, 10.0));
  c.refine_optimizer = t.choice_or("refine_optimizer", c.refine_optimizer, {"cmaes", "pso"});
  c.unseen_joint_tolerance =
      t.number_or("unseen_joint_tolerance", c.unseen_joint_tolerance, Range::closed(0.0, 1.0));
  c.two_pass_smoothing = t.number_or("two_pass_smoothing", c.two_pass_smoothing, Range::closed(0.0, 100.0));
  c.progress_every = static_cast<int>(t.integer_or("progress_every", c.progress_every, Range::closed(1, 1e9)));
  c.overlay = t.boolean_or("overlay", c.overlay);
  return c;
}

}  // namespace

std::string observation_color_space(const ConfigTable& observation, const Sensor& sensor) {
  const std::string dflt = sensor.segmentation_defaults().color_space == "luminance" ? "luminance" : "hsv";
  return observation.choice_or("color_space", dflt, {"hsv", "luminance"});
}

double tracker_fps(const ConfigTable& tracker) {
  // 0: the source's own rate. Microscope and ultrasound cameras run from a
  // frame a minute to a few hundred thousand a second.
  const double fps = tracker.number_or("fps", TrackerConfig{}.fps, Range::closed(0, 1e6));
  if (fps > 0 && fps < 1e-3) tracker.fail("fps", "expected 0 (the source's rate) or a rate of at least 0.001 frames/s");
  return fps;
}

EngineConfig engine_config(const Setup& setup) {
  const ConfigTable& root = setup.root;
  const ArticulatedModel& model = setup.model();
  // The frame the search runs in: [search] and initial_pose are taken into it.
  const SensorFrame frame = sensor_frame(*setup.sensor);
  EngineConfig e;
  {
    const ConfigTable t = root.table("observation");
    e.observation = read_observation(t, *setup.sensor);
    t.check_all_used();
  }
  {
    const ConfigTable t = root.table("pso");
    e.pso = read_pso(t);
    t.check_all_used();
  }
  {
    const ConfigTable t = root.table("cost");
    e.cost = read_cost(t);
    t.check_all_used();
  }
  {
    const ConfigTable t = root.table("render");
    e.render = read_render(t, *setup.sensor);
    t.check_all_used();
  }
  {
    const ConfigTable t = root.table("search");
    e.search = read_search(t, *setup.sensor, frame, model.radius_mm());
    t.check_all_used();
  }
  const auto& g = model.geometry();
  const bool full_turn = std::abs(e.search.rotation_max_deg.z() - e.search.rotation_min_deg.z() - 360.0) < 1e-9;
  e.space = ParameterSpace::make(model.fingers(), e.search.position_min_mm, e.search.position_max_mm,
                                 e.search.rotation_min_deg, e.search.rotation_max_deg, g.joint_min_deg,
                                 g.joint_max_deg, full_turn);
  e.space.position_box = e.search.world_box;
  {
    const ConfigTable t = root.table("tracker");
    e.tracker = read_tracker(t, model, e.space, frame);
    t.check_all_used();
  }
  return e;
}

void check_root_keys(const Setup& setup) {
  const ConfigTable& root = setup.root;
  for (const auto& k : kEngineTables) root.mark_used(k);
  for (const auto& k : kOtherTables) root.mark_used(k);
  for (const char* k : {"plugin_path", "sensor", "gripper", "stimulus"}) root.mark_used(k);
  root.check_all_used();
}

}  // namespace gtrack
