// gtrack render: the model as the sensor sees it, as a mask and a posed mesh.
#include <algorithm>
#include <cmath>
#include <fmt/format.h>
#include <iostream>
#include <sstream>
#include <opencv2/imgcodecs.hpp>

#include "command.hpp"
#include "gtrack/engine_config.hpp"
#include "gtrack/error.hpp"
#include "gtrack/log.hpp"
#include "gtrack/renderer.hpp"
#include "gtrack/setup.hpp"
#include "gtrack/text_file.hpp"

namespace po = boost::program_options;

namespace {

void write_obj(const std::string& path, const std::vector<Eigen::Vector3d>& tris) {
  std::ostringstream out;
  out.precision(10);  // 0.1 um at 100 mm from the camera
  out << "# gtrack posed gripper mesh, millimetres, world frame\n";
  for (const auto& v : tris) out << "v " << v.x() << " " << v.y() << " " << v.z() << "\n";
  for (size_t i = 0; i < tris.size(); i += 3) out << "f " << i + 1 << " " << i + 2 << " " << i + 3 << "\n";
  gtrack::write_text_file(path, out.str());
}

// Checked before anything is computed or written: the folder exists, and an
// image's extension is one OpenCV can write.
void check_writable(const std::string& path, bool image) {
  gtrack::cli::check_output_folder(path);
  if (image && !cv::haveImageWriter(path)) {
    throw gtrack::InputError(path +
                             ": cannot write images of this kind; expected .png, .jpg, .bmp, .tif, .pgm or .ppm");
  }
}

int run_render(const gtrack::cli::CommonOptions& common, const po::variables_map& vm) {
  gtrack::SetupOptions so;
  so.plugin_paths = common.plugin_paths;
  so.with_stimulus = false;
  gtrack::Setup setup = gtrack::load_setup(vm["config"].as<std::string>(), so);
  // A config is checked whole, as `track` checks it: a typo found now is not
  // a surprise later. Its [render] table gives the backend and its settings.
  const gtrack::EngineConfig config = gtrack::engine_config(setup);
  gtrack::check_root_keys(setup);
  const std::string out = vm["out"].as<std::string>();
  check_writable(out, true);
  if (vm.count("obj")) check_writable(vm["obj"].as<std::string>(), false);
  gtrack::cli::NamedPaths outputs = {{"--out", out}};
  if (vm.count("obj")) outputs.emplace_back("--obj", vm["obj"].as<std::string>());
  gtrack::cli::check_outputs_apart(outputs, {{"--config", vm["config"].as<std::string>()}});

  const auto& model = setup.model();
  const Eigen::VectorXd h = gtrack::parse_parameter_vector(vm["params"].as<std::string>(), model.dims());
  gtrack::RenderOptions ro = config.render;
  gtrack::cli::backend_option(vm, ro.backend);
  ro.scale = vm["scale"].as<double>();
  if (!(ro.scale > 0 && ro.scale <= 1)) throw gtrack::cli::UsageError("--scale must be in (0, 1]");
  // As [render] scale: a mask a few pixels across shows no shape.
  if (const std::string small = gtrack::render_scale_problem(setup.sensor->image_size(), ro.scale); !small.empty()) {
    throw gtrack::cli::UsageError(fmt::format("--scale {:g} ", ro.scale) + small);
  }
  auto renderer = gtrack::make_renderer(ro);
  renderer->set_model(model);
  renderer->set_projection(setup.sensor->projection(), ro.scale);
  // Rendered as asked, but what the tracker would never consider is said.
  const auto& g = model.geometry();
  for (int f = 0; f < model.fingers(); ++f) {
    const double q = h[gtrack::kPoseDims + f];
    if (q < g.joint_min_deg || q > g.joint_max_deg) {
      gtrack::logger().warn("q{} = {} is outside the gripper's joint limits [{}, {}]", f + 1, q, g.joint_min_deg,
                            g.joint_max_deg);
    }
  }
  const cv::Mat mask = renderer->render_mask(h);
  if (cv::countNonZero(mask) == 0) {
    gtrack::logger().warn("the posed model covers no pixel of the image (outside the view, outside an ultrasound "
                          "slice's slab, behind the camera or nearer than its near plane)");
  }
  if (!cv::imwrite(out, mask)) throw gtrack::InputError(out + ": cannot write the image");
  std::cout << "mask " << mask.cols << "x" << mask.rows << " (" << cv::countNonZero(mask) << " pixels, "
            << renderer->name() << " backend) -> " << out << "\n";
  if (vm.count("obj")) {
    std::vector<Eigen::Vector3d> tris;
    model.pose(h, tris);
    write_obj(vm["obj"].as<std::string>(), tris);
    std::cout << "mesh " << tris.size() / 3 << " triangles -> " << vm["obj"].as<std::string>() << "\n";
  }
  return 0;
}

}  // namespace

GTRACK_COMMAND(
    "render", "write the binary mask of the model as the sensor sees it (and the posed mesh as OBJ)",
    [](po::options_description& d) {
      d.add_options()("config,c", po::value<std::string>()->required(), "TOML config naming sensor and gripper")(
          "params,p", po::value<std::string>()->required(), "x,y,z,rx,ry,rz,q1,...,qF in mm and degrees")(
          "out,o", po::value<std::string>()->required(), "mask image to write (.png)")(
          "obj", po::value<std::string>(), "also write the posed mesh as Wavefront OBJ")(
          "backend", po::value<std::string>(), "auto, gl or cpu (default: [render] backend)")(
          "scale", po::value<double>()->default_value(1.0), "render scale relative to the sensor image");
    },
    run_render)
