// gtrack segment: what a config's [observation] bounds take for the gripper
// in a recording, over whole frames at full resolution, to choose the bounds
// before tracking.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fmt/format.h>
#include <iostream>
#include <numbers>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "command.hpp"
#include "gtrack/engine_config.hpp"
#include "gtrack/error.hpp"
#include "gtrack/frame_source.hpp"
#include "gtrack/log.hpp"
#include "gtrack/observation.hpp"
#include "gtrack/renderer.hpp"
#include "gtrack/results.hpp"
#include "gtrack/setup.hpp"

namespace po = boost::program_options;
namespace fs = std::filesystem;

namespace {

// A channel's values over every frame, for its percentiles.
struct Histogram {
  std::array<double, 256> counts{};
  double total = 0;

  void add(const cv::Mat& channel) {
    cv::Mat h;
    const int size = 256;
    const float range[] = {0, 256};
    const float* ranges = range;
    cv::calcHist(&channel, 1, nullptr, cv::Mat(), h, 1, &size, &ranges);
    for (int i = 0; i < 256; ++i) counts[static_cast<size_t>(i)] += h.at<float>(i);
    total += static_cast<double>(channel.total());
  }
  int percentile(double p) const {
    double seen = 0;
    for (int i = 0; i < 256; ++i) {
      seen += counts[static_cast<size_t>(i)];
      if (seen >= p / 100 * total) return i;
    }
    return 255;
  }
  std::string percentiles() const {
    std::string s;
    for (double p : {1, 5, 25, 50, 75, 95, 99}) s += fmt::format("  p{:g} {:3d}", p, percentile(p));
    return s;
  }
};

// The model face-on and flat at the sensor's nominal position, in image
// pixels: what a gripper in full view covers at least, about.
long face_on_pixels(const gtrack::Setup& setup) {
  gtrack::RenderOptions ro;
  ro.backend = "cpu";
  ro.scale = 1;
  auto renderer = gtrack::make_renderer(ro);
  renderer->set_model(setup.model());
  renderer->set_projection(setup.sensor->projection(), 1);
  Eigen::VectorXd h = Eigen::VectorXd::Zero(setup.model().dims());
  h.head<3>() = setup.sensor->nominal_position_mm();
  const auto& g = setup.model().geometry();
  h.tail(setup.model().fingers()).setConstant(std::clamp(0.0, g.joint_min_deg, g.joint_max_deg));
  return cv::countNonZero(renderer->render_mask(h));
}

int run_segment(const gtrack::cli::CommonOptions& common, const po::variables_map& vm) {
  gtrack::SetupOptions so;
  so.plugin_paths = common.plugin_paths;
  so.with_stimulus = false;
  gtrack::Setup setup = gtrack::load_setup(vm["config"].as<std::string>(), so);
  const gtrack::EngineConfig config = gtrack::engine_config(setup);
  gtrack::check_root_keys(setup);
  const gtrack::ObservationConfig& o = config.observation;
  const gtrack::ImageSize size = setup.sensor->image_size();
  const fs::path out = vm["out"].as<std::string>();
  std::error_code ec;
  if (fs::exists(out, ec) && !fs::is_directory(out, ec)) {
    throw gtrack::InputError(out.string() + ": is a file; expected a folder (--out)");
  }
  // Made, with its parents, as track's --out is.
  for (const char* sub : {"masks", "preview"}) {
    fs::create_directories(out / sub, ec);
    if (ec || !fs::is_directory(out / sub)) {
      throw gtrack::InputError((out / sub).string() + ": cannot create the output folder (" +
                               (ec ? ec.message() : std::string("not a folder")) + ") (--out)");
    }
  }

  const std::string input = vm["input"].as<std::string>();
  const gtrack::FrameRange range = gtrack::cli::frame_range_option(vm);
  auto source = gtrack::open_frame_source(input, size, range, config.tracker.fps > 0 ? config.tracker.fps : 30.0);
  source->set_image_bits(config.tracker.image_bits);
  const gtrack::Segmenter segmenter(o, size, size);
  // An earlier run's images would stand among this one's (other --frames,
  // --every): they go once the input has opened, as track's do.
  if (const int stale = gtrack::remove_frame_images(out / "masks") + gtrack::remove_frame_images(out / "preview");
      stale > 0) {
    gtrack::logger().warn("{} holds an earlier run's masks and previews: its {} images are replaced", out.string(),
                          stale);
  }

  const bool luminance = o.color_space == "luminance";
  const std::string bounds =
      luminance ? fmt::format("luminance {:g} to {:g}", o.luminance_min, o.luminance_max)
                : fmt::format("hue {:g} to {:g}, saturation {:g} to {:g}, value {:g} to {:g}", o.hue_min, o.hue_max,
                              o.saturation_min, o.saturation_max, o.value_min, o.value_max);
  const long face_on = face_on_pixels(setup);
  // The coarse search's measure of a blob worth a try: 5 % of a disc of the
  // model's radius (tracking/coarse_search.cpp, at render size there).
  const double radius_px = setup.model().radius_mm() / setup.sensor->mm_per_pixel();
  const double tried_area = 0.05 * std::numbers::pi * radius_px * radius_px;
  std::cout << "segmenting " << source->description() << " with [observation] " << bounds
            << (o.exclude_px.empty() ? std::string() : fmt::format(", {} exclude_px rectangles", o.exclude_px.size()))
            << "; the gripper face-on at the working distance covers about " << face_on << " pixels\n";

  std::array<Histogram, 3> hists;  // luminance; or hue, saturation, value
  int frames = 0;
  double share_sum = 0;
  while (const std::optional<gtrack::Frame> frame = source->next()) {
    const cv::Mat image = setup.sensor->rectify(frame->image);
    const cv::Mat mask = segmenter.segment(image);
    if (luminance) {
      cv::Mat grey;
      cv::cvtColor(image, grey, cv::COLOR_BGR2GRAY);
      hists[0].add(grey);
    } else {
      cv::Mat hsv, channels[3];
      cv::cvtColor(image, hsv, cv::COLOR_BGR2HSV);
      cv::split(hsv, channels);
      for (int c = 0; c < 3; ++c) hists[static_cast<size_t>(c)].add(channels[c]);
    }
    // Blobs the tracker's coarse search would try besides the largest.
    cv::Mat labels, stats, centroids;
    const int n = cv::connectedComponentsWithStats(mask, labels, stats, centroids, 8, CV_32S);
    std::vector<int> areas;
    for (int i = 1; i < n; ++i) areas.push_back(stats.at<int>(i, cv::CC_STAT_AREA));
    std::sort(areas.rbegin(), areas.rend());
    const auto large = std::count_if(areas.begin(), areas.end(), [&](int a) { return a >= tried_area; });
    const int within = cv::countNonZero(mask);
    const double share = static_cast<double>(within) / mask.total();
    share_sum += share;
    std::string largest;
    for (size_t i = 0; i < std::min<size_t>(3, areas.size()); ++i) {
      largest += (i ? ", " : "") + std::to_string(areas[i]);
    }
    std::cout << fmt::format("frame {}: {} pixels within the bounds ({:.2f} % of the image, {:.2f} times the face-on "
                             "gripper), {} blobs, {} of them of {:.0f} pixels or more; the largest {}\n",
                             frame->index, within, 100 * share, face_on > 0 ? double(within) / face_on : 0.0,
                             areas.size(), large, tried_area, largest.empty() ? "none" : largest);
    char name[32];
    std::snprintf(name, sizeof name, "%06d.png", frame->index);
    cv::Mat preview = image.clone();
    preview.setTo(cv::Scalar(255, 0, 255), mask);
    for (const cv::Rect& r : o.exclude_px) cv::rectangle(preview, r, cv::Scalar(128, 128, 128), 2);
    using Written = std::pair<const char*, const cv::Mat*>;
    for (const auto& [folder, image] : {Written{"masks", &mask}, Written{"preview", &preview}}) {
      if (!cv::imwrite((out / folder / name).string(), *image)) {
        throw gtrack::InputError((out / folder / name).string() + ": cannot write the image");
      }
    }
    ++frames;
  }
  if (frames == 0) throw gtrack::InputError(input + ": no frame in the range asked for");
  std::cout << fmt::format("{} frames, {:.2f} % of the image within the bounds on the mean\n", frames,
                           100 * share_sum / frames);
  if (luminance) {
    std::cout << "luminance:" << hists[0].percentiles() << "\n";
  } else {
    std::cout << "hue:       " << hists[0].percentiles() << "\nsaturation:" << hists[1].percentiles()
              << "\nvalue:     " << hists[2].percentiles() << "\n";
  }
  std::cout << "masks (full resolution, exclude_px applied, no search region): " << (out / "masks").string()
            << "\nframes with what is within the bounds in magenta: " << (out / "preview").string() << "\n";
  return 0;
}

}  // namespace

GTRACK_COMMAND(
    "segment", "show what a config's [observation] bounds take for the gripper in whole frames, to choose them",
    [](po::options_description& d) {
      d.add_options()("config,c", po::value<std::string>()->required(), "TOML config (its [observation] bounds)")(
          "input,i", po::value<std::string>()->required(), "video, image folder, TIFF stack or DICOM file")(
          "out,o", po::value<std::string>()->required(), "folder to write masks/ and preview/ into")(
          "frames", po::value<std::string>(),
          "A:B, frames A (inclusive) to B (exclusive); A: and :B open-ended; A alone: that frame")(
          "every", po::value<int>()->default_value(1), "every K-th frame");
    },
    run_segment)
