// Planning a synthetic sequence: the truth of every frame, before any image.
//
// Motion is built from smooth random paths (smooth_path.hpp) so that speeds
// stay within what a gripper steered by magnets does; excursions out of the
// field of view are blended in with smoothsteps; the joints come from the
// Stimulus plugin's own hysteresis (target_joint_deg) through a first-order
// lag per finger, so they fold late when heating and unfold late when
// cooling, as the material does. Occlusion episodes cover the configured
// share of frames; how much of the shape an occluder hides is a target that
// the renderer meets by sizing the blob (render_frame).
#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>
#include <sstream>

#include <fmt/format.h>

#include "gtrack/engine_config.hpp"
#include "gtrack/error.hpp"
#include "gtrack/log.hpp"
#include "gtrack/model.hpp"
#include "gtrack/stimulus_log.hpp"
#include "gtrack/synth.hpp"
#include "synth/appearance.hpp"
#include "synth/smooth_path.hpp"

namespace gtrack {

namespace {

using synth::SmoothPath;
using synth::smoothstep;

struct Exit {
  double t_mid, half_s;    // centre time and half duration (out and back)
  Eigen::Vector2d target;  // palm centre (mm) when furthest out
};

std::vector<Exit> plan_exits(const SynthPreset& p, double duration, const Eigen::Vector2d& half_view, double radius,
                             const Eigen::Vector2d& centre, std::mt19937_64& rng) {
  std::vector<Exit> exits;
  int n = static_cast<int>(std::lround(p.exits_per_minute * duration / 60.0));
  if (duration >= 4.0) n = std::max(n, 1);
  if (duration < 4.0) n = 0;  // too short to leave and come back
  std::uniform_real_distribution<double> u(0, 1);
  for (int k = 0; k < n; ++k) {
    Exit e;
    e.half_s = 0.9;
    // Evenly spread after the first 1.5 s (the tracker's start).
    const double lo = 1.5 + e.half_s, hi = duration - e.half_s - 0.5;
    e.t_mid = lo + (hi - lo) * (k + 0.5) / n;
    const int side = static_cast<int>(u(rng) * 4) % 4;
    const double along = (u(rng) - 0.5) * 0.6;
    const double ox = half_view.x() + p.exit_depth * radius, oy = half_view.y() + p.exit_depth * radius;
    switch (side) {
      case 0: e.target = {ox, along * half_view.y()}; break;
      case 1: e.target = {-ox, along * half_view.y()}; break;
      case 2: e.target = {along * half_view.x(), oy}; break;
      default: e.target = {along * half_view.x(), -oy}; break;
    }
    e.target += centre;
    exits.push_back(e);
  }
  return exits;
}

// Temperature: low, heat to high, hold, cool back, with soft corners.
std::vector<double> stimulus_profile(const SynthPreset& p, const std::vector<double>& times, double duration,
                                     std::mt19937_64& rng) {
  const double period = std::clamp(duration, 2.5, p.stimulus_period_s);
  std::normal_distribution<double> noise(0, p.stimulus_noise);
  std::vector<double> out;
  const double mid = 0.5 * (p.stimulus_low + p.stimulus_high), half = 0.5 * (p.stimulus_high - p.stimulus_low);
  for (double t : times) {
    const double s = std::clamp(1.4 * -std::cos(2 * std::numbers::pi * t / period), -1.0, 1.0);
    out.push_back(mid + half * s + noise(rng));
  }
  return out;
}

std::vector<OccluderPlan> plan_occlusions(const SynthPreset& p, int frames, double fps, std::mt19937_64& rng) {
  std::vector<OccluderPlan> plan(frames);
  if (p.occluded_frames <= 0) return plan;
  std::uniform_real_distribution<double> u(0, 1);
  const double mean_len = 1.2 * fps;
  const double mean_gap = mean_len * (1 - p.occluded_frames) / std::max(1e-3, p.occluded_frames);
  int f = static_cast<int>(u(rng) * mean_gap);
  while (f < frames) {
    const int len = std::max(3, static_cast<int>(mean_len * (0.4 + 1.2 * u(rng))));
    const double peak = p.max_occlusion * (0.45 + 0.55 * u(rng));
    const double angle0 = 2 * std::numbers::pi * u(rng), drift = (u(rng) - 0.5) * 0.08;
    const double dist = 0.15 + 0.5 * u(rng);
    const double phase = 1000 * u(rng);
    const bool tissue = u(rng) < 0.6;
    for (int k = 0; k < len && f + k < frames; ++k) {
      OccluderPlan& o = plan[f + k];
      o.active = true;
      // Fast rise, long plateau, fast fall.
      o.target = std::min(p.max_occlusion, peak * std::sqrt(std::sin(std::numbers::pi * (k + 0.5) / len)));
      const double a = angle0 + drift * k;
      o.offset_px = dist * Eigen::Vector2d(std::cos(a), std::sin(a));  // in gripper radii; scaled when drawn
      o.shape_phase = phase + 0.02 * k;
      o.tissue_coloured = tissue;
    }
    f += len + std::max(1, static_cast<int>(mean_gap * (0.5 + u(rng))));
  }
  return plan;
}

// The config's optional [synth] table: the stimulus profile in the units of
// the setup's stimulus plugin (a light, a field or a pH in place of the
// presets' temperature), so that any plugin's fold and unfold band can be
// crossed. Every key is optional; the preset gives the rest.
void apply_synth_table(SynthPreset& p, const ConfigTable& t) {
  std::ostringstream r;
  r << p.stimulus_low << " and " << p.stimulus_high;
  const std::string preset_range = r.str();
  p.stimulus_low = t.number_or("stimulus_low", p.stimulus_low);
  p.stimulus_high = t.number_or("stimulus_high", p.stimulus_high);
  p.stimulus_period_s = t.number_or("stimulus_period_s", p.stimulus_period_s, Range::positive());
  p.stimulus_noise = t.number_or("stimulus_noise", p.stimulus_noise, Range::non_negative());
  // The one motion range set in millimetres (the others scale with the view
  // and the gripper): a gripper much smaller than the preset's moves less
  // along the line of sight.
  p.depth_amplitude_mm = t.number_or("depth_amplitude_mm", p.depth_amplitude_mm, Range::closed(0, 50));
  t.check_all_used();  // a misspelt key first: it explains the comparison below
  if (!(p.stimulus_low < p.stimulus_high)) {
    t.fail(t.has("stimulus_high") ? "stimulus_high" : "stimulus_low",
           "stimulus_high must be greater than stimulus_low (the preset's are " + preset_range + ")");
  }
}

// A lab's log against the frames to draw: one none of whose rows falls
// within them is refused (every frame would take its first or last
// reading), one that covers only some is warned about once. A time within
// half a frame of the log's ends is the frame's own row, written with few
// decimals.
void check_log_covers(const StimulusLog& log, const std::vector<double>& times) {
  const bool by_time = log.key() == StimulusLog::Key::Time;
  const int n = static_cast<int>(times.size());
  const double slack = by_time && n > 1 ? 0.5 * (times[1] - times[0]) : 0;
  const auto key = [&](int i) { return by_time ? times[static_cast<size_t>(i)] : static_cast<double>(i); };
  int outside = 0;
  for (int i = 0; i < n; ++i) outside += key(i) < log.first_key() - slack || key(i) > log.last_key() + slack;
  if (outside == 0) return;
  const std::string rows = by_time ? fmt::format("t = {:.3f} to {:.3f} s{}", log.first_key(), log.last_key(),
                                                 log.shift_note())
                                   : fmt::format("frames {:g} to {:g}", log.first_key(), log.last_key());
  const std::string frames = by_time ? fmt::format("t = {:.3f} to {:.3f} s", times.front(), times.back())
                                     : fmt::format("frames 0 to {}", n - 1);
  if (outside == n) {
    throw InputError(fmt::format(
        "{}: its rows cover {}, and none of the {} frames to draw ({}) falls within them; expected {}", log.source(),
        rows, n, frames,
        by_time ? "seconds from the sequence's first frame (a logger started before the camera: --stimulus-offset "
                  "with the log's time at the first frame)"
                : "frame indices from 0"));
  }
  logger().warn("{}: {} of the {} frames to draw ({}) are outside its rows, which cover {}; they take its nearest "
                "reading",
                log.source(), outside, n, frames, rows);
}

}  // namespace

SynthPlan plan_sequence(const Setup& setup, const SynthOptions& options) {
  if (options.frames < 1) throw Error("a synthetic sequence needs at least one frame");
  if (!(options.occlusion_scale >= 0 && options.occlusion_scale <= 1)) {
    throw Error("the occlusion scale must be in [0, 1]");
  }
  if (!setup.root.has("stimulus")) {
    setup.root.fail("stimulus", "missing table [stimulus]: a synthetic sequence's fold follows a stimulus plugin's "
                                "readings; expected a table naming one (temperature_hysteresis, threshold_hysteresis)");
  }
  if (!setup.loader) throw Error("a synthetic sequence needs the setup's plugin loader, to make its stimulus anew");
  SynthPlan plan;
  plan.preset = synth_preset(options.preset);
  plan.options = options;
  apply_synth_table(plan.preset, setup.root.table("synth"));
  // The config's camera rate, when it gives one, is the sequence's.
  if (const double fps = tracker_fps(setup.root.table("tracker")); fps > 0) plan.preset.frame_rate_hz = fps;
  const SynthPreset& p = plan.preset;
  const ArticulatedModel& model = setup.model();
  const Sensor& sensor = *setup.sensor;
  plan.lens_map = synth::lens_map(sensor);
  std::mt19937_64 rng(options.seed * 0x9E3779B97F4A7C15ull + 17);
  std::uniform_real_distribution<double> u(0, 1);

  const int n = options.frames;
  const double fps = p.frame_rate_hz, duration = n / fps;
  std::vector<double> times(n);
  for (int i = 0; i < n; ++i) times[i] = i / fps;

  const Eigen::Vector3d nominal = sensor.nominal_position_mm();
  // Motion and tilts are planned in the sensor's own frame, so that a probe
  // or a camera turned in the world sees the sequence an upright one does.
  const SensorFrame frame = sensor_frame(sensor);
  const double radius = model.radius_mm();
  const ImageSize size = sensor.image_size();
  const Eigen::Vector2d pixel = pixel_size_mm(sensor);
  const Eigen::Vector2d half_view(0.5 * size.width * pixel.x(), 0.5 * size.height * pixel.y());
  const Eigen::Vector2d room = (half_view.array() - radius).max(0.25 * radius).matrix();

  // A slice's slab: a depth motion past half its thickness takes the palm
  // out of the imaging plane, and the frames show little of the gripper.
  if (const auto slab = slab_thickness_mm(sensor.projection()); slab && p.depth_amplitude_mm > 0.5 * *slab) {
    const double half = 0.5 * *slab;
    logger().warn("{}: [synth] depth_amplitude_mm {:g} moves the gripper up to {:g} mm out of the imaging plane, past "
                  "the slab's half thickness of {:g} mm: frames will image little of it (set [synth] "
                  "depth_amplitude_mm to at most {:g})",
                  setup.root.source().empty() ? std::string("the config") : setup.root.source(), p.depth_amplitude_mm,
                  p.depth_amplitude_mm, half, half);
  }

  const double base_hz = 1.0 / p.motion_period_s;
  const auto px = SmoothPath(rng, base_hz).sample(times), py = SmoothPath(rng, base_hz).sample(times);
  const auto pz = SmoothPath(rng, base_hz).sample(times);
  const auto prx = SmoothPath(rng, base_hz).sample(times), pry = SmoothPath(rng, base_hz).sample(times);
  const auto prz = SmoothPath(rng, base_hz).sample(times);
  const auto exits = plan_exits(p, duration, half_view, radius, nominal.head<2>(), rng);
  auto temperature = stimulus_profile(p, times, duration, rng);  // drawn with a log too: the seed's rest stays
  std::optional<StimulusLog> lab_log;
  if (options.stimulus_log) {
    lab_log = StimulusLog::load(*options.stimulus_log, {}, options.stimulus_column);
    if (options.stimulus_offset_s != 0) lab_log->shift_time(options.stimulus_offset_s);
    for (int i = 0; i < n; ++i) temperature[i] = lab_log->value_at(i, times[i]).value_or(lab_log->nearest(i, times[i]));
    check_log_covers(*lab_log, times);
  }
  auto occluders = plan_occlusions(p, n, fps, rng);
  for (OccluderPlan& o : occluders) {
    o.target *= options.occlusion_scale;
    if (o.target <= 0) o.active = false;
  }

  const double rz0 = 360 * u(rng) - 180, spin_sign = u(rng) < 0.5 ? -1 : 1;

  // The material's response, from a stimulus instance of our own so that
  // the setup's (the tracker's) stays untouched.
  auto stimulus = setup.loader->make_stimulus(setup.root.table("stimulus"));
  // The profile's ends are readings the plugin must take (a temperature in
  // kelvin is refused), said of their [synth] keys; so is the noise that
  // takes a reading past them.
  const ConfigTable& synth_table = setup.root.table("synth");
  // (Each end by an instance of its own, as a first reading: a plugin that
  // checks the time or the rate between readings sees no second one.)
  for (const auto& [key, value] : {std::pair{"stimulus_low", p.stimulus_low}, {"stimulus_high", p.stimulus_high}}) {
    if (lab_log) break;  // the log's rows are the readings
    try {
      setup.loader->make_stimulus(setup.root.table("stimulus"))->update(value, 0);
    } catch (const std::exception& e) {
      synth_table.fail(key, fmt::format("the stimulus plugin refused the reading {:g}, the profile's {} end, as a first "
                                        "reading at t = 0: {}",
                                        value, key == std::string("stimulus_low") ? "low" : "high", e.what()));
    }
  }
  const int F = model.fingers(), L = model.max_links();
  std::vector<double> lag(F), q(F, model.geometry().unfolded_deg);
  for (int f = 0; f < F; ++f) lag[f] = p.joint_lag_s * (1 + p.joint_lag_spread * (2 * u(rng) - 1));
  std::normal_distribution<double> hinge_noise(0, std::max(0.0, options.joint_noise_deg));
  const auto& G = model.geometry();

  for (int i = 0; i < n; ++i) {
    const double t = times[i];
    SynthFrame fr;
    fr.frame = i;
    fr.time_s = t;
    fr.stimulus = temperature[i];
    Eigen::VectorXd h(model.dims());
    Eigen::Vector2d xy = nominal.head<2>() + p.inplane_amplitude * Eigen::Vector2d(room.x() * px[i], room.y() * py[i]);
    for (const Exit& e : exits) {
      const double w = smoothstep(e.t_mid - e.half_s, e.t_mid - 0.2 * e.half_s, t) *
                       (1 - smoothstep(e.t_mid + 0.2 * e.half_s, e.t_mid + e.half_s, t));
      xy = (1 - w) * xy + w * e.target;
    }
    // Tilts grow in over the first seconds, so the first frame is a fair start.
    const double ramp = 0.3 + 0.7 * smoothstep(0, 1.5, t);
    h[0] = xy.x();
    h[1] = xy.y();
    h[2] = nominal.z() + p.depth_amplitude_mm * pz[i];
    h[3] = ramp * p.tilt_amplitude_deg * prx[i];
    h[4] = ramp * p.tilt_amplitude_deg * pry[i];
    double rz = rz0 + spin_sign * p.spin_deg_per_s * t + 0.25 * p.spin_deg_per_s * p.motion_period_s * prz[i];
    h[5] = std::remainder(rz, 360.0);
    h = frame.to_world(h);

    try {
      stimulus->update(temperature[i], t);
    } catch (const std::exception& e) {
      if (lab_log) {
        throw InputError(fmt::format("{}: frame {} (t = {:.3f} s): the stimulus plugin refused the reading {:g}: {}",
                                     lab_log->source(), i, t, temperature[i], e.what()));
      }
      synth_table.fail("stimulus_noise",
                       fmt::format("{} (frame {}, t = {:.3f} s: the profile's reading {:g}, its noise of sigma {:g} "
                                   "included; keep stimulus_low and stimulus_high three sigma inside what the plugin "
                                   "takes, or set stimulus_noise lower)",
                                   e.what(), i, t, temperature[i], p.stimulus_noise));
    }
    if (i > 0) {
      for (int f = 0; f < F; ++f) {
        const double target = stimulus->target_joint_deg(q[f]);
        q[f] += (target - q[f]) * (1 - std::exp(-(1.0 / fps) / lag[f]));
        q[f] = std::clamp(q[f], G.joint_min_deg, G.joint_max_deg);
      }
    }
    fr.hinge_deg.assign(F * L, 0.0);
    for (int f = 0; f < F; ++f) {
      h[kPoseDims + f] = q[f];
      for (int j = 0; j < L; ++j) fr.hinge_deg[f * L + j] = q[f] + (options.joint_noise_deg > 0 ? hinge_noise(rng) : 0);
    }
    fr.truth = h;
    fr.occluder = occluders[i];
    plan.frames.push_back(std::move(fr));
  }
  return plan;
}

}  // namespace gtrack
