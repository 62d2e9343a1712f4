// Loading the three plugins a config names.
#include "gtrack/setup.hpp"

#include <Eigen/SVD>
#include <cmath>
#include <optional>
#include <utility>

#include "gtrack/error.hpp"
#include "gtrack/log.hpp"
#include "render/clip.hpp"
#include "tracking/run_config.hpp"

namespace gtrack {

namespace fs = std::filesystem;

namespace {

// The stimulus's reference joint values, where its table gives them, describe
// the same open and folded shapes as the gripper's: a difference makes S(H)
// pull the joints away from the shapes the coarse search and the fallback use.
void warn_on_reference_mismatch(const ConfigTable& stimulus, const GripperGeometry& g) {
  const std::pair<const char*, double> refs[] = {{"unfolded_deg", g.unfolded_deg}, {"folded_deg", g.folded_deg}};
  for (const auto& [key, gripper_value] : refs) {
    if (!stimulus.has(key)) continue;
    double v = 0;
    try {
      v = stimulus.number(key);
    } catch (const ConfigError&) {
      continue;  // not a number: the plugin's own reading of it decides
    }
    if (std::abs(v - gripper_value) > 1e-9) {
      logger().warn("{}: {} differs from the gripper's {} = {}; both describe the same shape and should agree",
                    stimulus.where(key), v, key, gripper_value);
    }
  }
}

// A gripper a few pixels across, or wider than the image, at the sensor's
// scale is mostly a unit mistake (a gripper in metres, micrometres per pixel
// typed as millimetres): said once, with both sizes, instead of every frame
// being lost without a reason.
void warn_on_scale_mismatch(const ConfigTable& root, const Sensor& sensor, const ArticulatedModel& model) {
  const double mm_per_px = sensor.mm_per_pixel();
  const ImageSize size = sensor.image_size();
  if (!(mm_per_px > 0) || size.width <= 0 || size.height <= 0) return;
  const double across_px = 2 * model.radius_mm() / mm_per_px;
  if (across_px >= 4 && across_px <= 4.0 * std::max(size.width, size.height)) return;
  logger().warn("{}: the gripper ({:.4g} mm across, open) is {:.3g} pixels across at the sensor's {:.4g} mm per pixel "
                "in its {}x{} image; check the units of [gripper] and [sensor] (millimetres)",
                root.source(), 2 * model.radius_mm(), across_px, mm_per_px, size.width, size.height);
}

// The renderers draw at projection().size and the frames come at
// image_size(): a sensor plugin whose two differ (its projection's size left
// unset) would render nothing the frames show.
void check_projection_size(const ConfigTable& table, const Sensor& sensor) {
  const auto refuse = [&](const std::string& what, const char* expected) {
    table.fail("plugin", "the sensor plugin's " + what + "; expected " + expected);
  };
  // The numbers the engine builds on (the search box, the model's scale):
  // one that is not finite would surface as a config key the file lacks.
  // A call that throws is said as the plugin's, not as the renderer's.
  const auto call = [&](const char* name, const auto& f) {
    try {
      return f();
    } catch (const std::exception& e) {
      table.fail("plugin", std::string("the sensor plugin's ") + name + " threw: " + e.what());
    } catch (...) {
      table.fail("plugin", std::string("the sensor plugin's ") + name + " threw something that is not a std::exception");
    }
  };
  const Projection projection = call("projection()", [&] { return sensor.projection(); });
  if (projection.clip_planes.size() > static_cast<size_t>(render::kMaxSensorPlanes)) {
    refuse(fmt::format("projection() has {} clip planes", projection.clip_planes.size()),
           fmt::format("at most {}", render::kMaxSensorPlanes).c_str());
  }
  if (!projection.world_to_image.allFinite()) {
    refuse("projection() holds a world_to_image that is not finite", "finite numbers");
  }
  for (const auto& plane : projection.clip_planes) {
    if (!plane.allFinite()) refuse("projection() holds a clip plane that is not finite", "finite numbers");
  }
  const Eigen::Vector3d nominal = call("nominal_position_mm()", [&] { return sensor.nominal_position_mm(); });
  if (!nominal.allFinite()) refuse("nominal_position_mm() is not finite", "finite numbers");
  const double mm = call("mm_per_pixel()", [&] { return sensor.mm_per_pixel(); });
  if (!(std::isfinite(mm) && mm > 0)) refuse(fmt::format("mm_per_pixel() is {}", mm), "a positive number of millimetres");
  // The sensor's centre ray, once: a project() that throws for any point
  // (a plugin left unfinished) is said here, naming the plugin.
  call("project()", [&] { return sensor.project(nominal); });
  // What the renderers draw: the world about the nominal position must
  // image in front of the sensor and onto the plane, not onto a line (a
  // matrix row left zero renders every hypothesis as a line, and every
  // frame is lost without a word).
  const Eigen::Matrix<double, 3, 4>& P = projection.world_to_image;
  const auto image_of = [&](const Eigen::Vector3d& x) -> std::optional<Eigen::Vector2d> {
    const Eigen::Vector3d h = P * x.homogeneous();
    if (!(h.z() > 0)) return std::nullopt;
    return Eigen::Vector2d(h.head<2>() / h.z());
  };
  const auto centre = image_of(nominal);
  if (!centre) {
    refuse("projection() puts nominal_position_mm() behind the sensor (its world_to_image gives it w <= 0)",
           "the nominal position in front of it");
  }
  Eigen::Matrix<double, 2, 3> J;  // pixels per millimetre about the nominal position
  for (int k = 0; k < 3; ++k) {  // a pixel's step
    const auto moved = image_of(nominal + mm * Eigen::Vector3d::Unit(k));
    J.col(k) = moved ? Eigen::Vector2d((*moved - *centre) / mm) : Eigen::Vector2d::Zero();
  }
  const Eigen::Vector2d sv = Eigen::JacobiSVD<Eigen::Matrix<double, 2, 3>>(J).singularValues();
  if (!(sv[1] > 1e-3 * sv[0]) || !(sv[0] > 0)) {
    refuse(fmt::format("projection() images the world about nominal_position_mm() onto a line or a point (at {:.3g} "
                       "and {:.3g} pixels per mm in its two directions)",
                       sv[0], sv[1]),
           "a world_to_image of rank 3 (each image direction its own row)");
  }
  // mm_per_pixel() sizes the search box and synth's motion and occluders:
  // it must be the projection's pixel, between its finest and coarsest
  // direction about the nominal position (a slice's pixels need not be
  // square), within 25 %.
  if (!(mm >= 0.8 / sv[0] && mm <= 1.25 / sv[1])) {
    refuse(fmt::format("mm_per_pixel() is {:.4g} mm, but projection() images {:.4g} to {:.4g} mm a pixel about "
                       "nominal_position_mm()",
                       mm, 1 / sv[0], 1 / sv[1]),
           "the projection's pixel size");
  }
  // project() is projection() and the lens distortion rectify() removes:
  // a point a tenth of the image from the nominal position lands on the same
  // pixel, give or take a fifth of its distance (a project() left unturned
  // or unmirrored when projection() was, and synth draws blank frames).
  {
    const double step = 0.1 * std::min(projection.size.width, projection.size.height) * mm;
    for (int k = 0; k < 3; ++k) {
      const Eigen::Vector3d x = nominal + step * Eigen::Vector3d::Unit(k);
      const auto linear = image_of(x);
      const auto full = call("project()", [&] { return sensor.project(x); });
      if (!linear || !full) continue;  // off a slice's slab, behind the camera
      const double apart = (*full - *linear).norm();
      if (!(apart <= 0.2 * (*linear - *centre).norm() + 2)) {
        refuse(fmt::format("project() and projection() disagree: the point ({:.4g}, {:.4g}, {:.4g}) mm images at "
                           "({:.1f}, {:.1f}) by project() and ({:.1f}, {:.1f}) by projection()",
                           x.x(), x.y(), x.z(), full->x(), full->y(), linear->x(), linear->y()),
               "the same pixel but for lens distortion (project() is projection() with the distortion that rectify() "
               "removes)");
      }
    }
  }
  const ImageSize image = call("image_size()", [&] { return sensor.image_size(); });
  const ImageSize drawn = projection.size;
  if (image.width <= 0 || image.height <= 0 || drawn.width != image.width || drawn.height != image.height) {
    table.fail("plugin", "the sensor's projection().size is " + std::to_string(drawn.width) + "x" +
                             std::to_string(drawn.height) + " and its image_size() " + std::to_string(image.width) +
                             "x" + std::to_string(image.height) + "; expected the same positive size (a plugin "
                             "sets Projection::size to its image size)");
  }
}

}  // namespace

std::vector<fs::path> config_plugin_paths(const ConfigTable& root) {
  const fs::path base = root.base_folder().empty() ? fs::path(".") : root.base_folder();
  std::vector<fs::path> out;
  for (const auto& p : root.strings_or("plugin_path", {})) {
    fs::path dir(p);
    out.push_back(dir.is_absolute() ? dir : base / dir);
  }
  return out;
}

Setup load_setup(const ConfigTable& root, const SetupOptions& options) {
  Setup s;
  s.root = root;
  s.config_file = root.source();
  s.plugin_paths = options.plugin_paths;
  auto loader = std::make_shared<PluginLoader>(options.plugin_paths);
  for (const auto& dir : config_plugin_paths(root)) loader->add_path(dir);
  s.loader = loader;
  for (const char* t : {"sensor", "gripper"}) {
    if (!root.has(t)) {
      root.fail(t, std::string("missing table [") + t + "]; it must name a " + t + " plugin" + root.misspelling_hint(t));
    }
  }
  s.sensor = loader->make_sensor(root.table("sensor"));
  check_projection_size(root.table("sensor"), *s.sensor);
  s.gripper = loader->make_gripper(root.table("gripper"));
  if (s.model().fingers() < 1 || s.model().dims() != kPoseDims + s.model().fingers() || !(s.model().radius_mm() > 0)) {
    root.table("gripper").fail("plugin", "the gripper plugin's model() has no fingers or no size; expected a model "
                                         "built from its geometry (gtrack::ArticulatedModel(geometry), with "
                                         "gtrack::make_radial_gripper or a geometry of its own)");
  }
  warn_on_scale_mismatch(root, *s.sensor, s.model());
  if (options.with_stimulus) {
    // No [stimulus]: a gripper whose fold no stimulus drives (or none is
    // logged); the joints are searched within their limits, with no S term.
    if (root.has("stimulus")) {
      s.stimulus = loader->make_stimulus(root.table("stimulus"));
      warn_on_reference_mismatch(root.table("stimulus"), s.model().geometry());
    }
  } else {
    root.mark_used("stimulus");
  }
  return s;
}

std::string plugin_label(const Setup& setup, PluginKind kind) {
  const std::string label = std::string(to_string(kind)) + " plugin";
  if (!setup.loader) return label;
  for (const PluginRecord& r : setup.loader->loaded()) {
    if (r.kind == kind) return plugin_label(r.kind, r.name, r.file);
  }
  return label;
}

Setup load_setup(const fs::path& config_file, const SetupOptions& options) {
  // A run's copy of its config takes its relative paths from where the
  // original's were taken; a pipe's are taken from the working folder.
  return load_setup(detail::load_config(config_file), options);
}

}  // namespace gtrack
