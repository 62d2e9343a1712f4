// pinhole_microscope: a camera on a microscope, modelled as a pinhole with
// optional lens distortion (OpenCV's model), given in the config or read
// from a calibration file (OpenCV's or ROS's). World = camera frame, OpenCV
// axes: x right, y down, z forward. Distortion is removed from input frames
// (rectify) so that the renderers use the linear projection.
#include <gtrack/plugin.hpp>
#include <opencv2/calib3d.hpp>
#include <opencv2/core/persistence.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <optional>
#include <string>
#include <vector>

namespace {

// A camera calibration as OpenCV and ROS write it (cv::FileStorage: YAML,
// XML or JSON): OpenCV's calibration sample and calibrateCamera users
// ("camera_matrix", "distortion_coefficients", "image_width",
// "image_height"), OpenCV's interactive calibration ("cameraMatrix",
// "dist_coeffs", "cameraResolution"), ROS camera_info files (the same
// names as the sample, each matrix a map of rows, cols and data).
struct Calibration {
  double fx = 0, fy = 0, cx = 0, cy = 0;
  std::vector<double> distortion;  // empty, or 4, 5 or 8 coefficients
  int width = 0, height = 0;       // 0: the file does not say
};

// The numbers of a node: a sequence, a single number, a matrix (a map
// whose "data" is the sequence: !!opencv-matrix and ROS alike), or a
// sequence of rows ([[fx, 0, cx], [0, fy, cy], [0, 0, 1]]), row by row.
std::optional<std::vector<double>> numbers_of(const cv::FileNode& node) {
  const cv::FileNode data = node.isMap() ? node["data"] : node;
  std::vector<double> out;
  if (data.isInt() || data.isReal()) {
    out.push_back(static_cast<double>(data));
  } else if (data.isSeq()) {
    const bool rows = data.size() > 0 && data[0].isSeq();
    for (const cv::FileNode& v : data) {
      if (rows && v.isSeq()) {
        for (const cv::FileNode& x : v) {
          if (!x.isInt() && !x.isReal()) return std::nullopt;
          out.push_back(static_cast<double>(x));
        }
      } else if (!rows && (v.isInt() || v.isReal())) {
        out.push_back(static_cast<double>(v));
      } else {
        return std::nullopt;
      }
    }
  } else {
    return std::nullopt;
  }
  return out;
}

Calibration read_calibration(const gtrack::ConfigTable& t, const char* key) {
  namespace fs = std::filesystem;
  const fs::path file = t.file_path(key);
  const std::string name = file.string();
  std::error_code ec;
  if (!fs::is_regular_file(file, ec)) {
    t.fail(key, name + (fs::exists(file, ec) ? ": not a file" : ": no such file") +
                    "; expected a camera calibration (OpenCV or ROS, YAML, XML or JSON)");
  }
  // Read as text: a ROS file is YAML without the "%YAML:1.0" line that
  // OpenCV's reader requires, which is then put in front.
  std::string text;
  {
    std::ifstream f(file, std::ios::binary);
    std::ostringstream s;
    s << f.rdbuf();
    if (!f) t.fail(key, name + ": cannot read");
    text = s.str();
  }
  const size_t start = text.find_first_not_of(" \t\r\n\xEF\xBB\xBF");
  int format = cv::FileStorage::FORMAT_YAML;
  long prefixed_lines = 0;
  if (start != std::string::npos && text[start] == '<') {
    format = cv::FileStorage::FORMAT_XML;
  } else if (start != std::string::npos && text[start] == '{') {
    format = cv::FileStorage::FORMAT_JSON;
  } else if (text.compare(start == std::string::npos ? 0 : start, 5, "%YAML") != 0) {
    // A file that opens its document ("---") needs only the version line.
    const bool opened = text.compare(start == std::string::npos ? 0 : start, 3, "---") == 0;
    text = (opened ? "%YAML:1.0\n" : "%YAML:1.0\n---\n") + text;
    prefixed_lines = opened ? 1 : 2;
  }
  cv::FileStorage in;
  try {
    in.open(text, cv::FileStorage::READ | cv::FileStorage::MEMORY | format);
  } catch (const cv::Exception& e) {
    // OpenCV's parser puts "(line): what" where the function's name goes.
    const std::string& where = e.func;
    const size_t close = where.find("): ");
    if (!where.empty() && where[0] == '(' && close != std::string::npos) {
      long line = std::strtol(where.c_str() + 1, nullptr, 10) - prefixed_lines;
      t.fail(key, name + ":" + std::to_string(std::max(line, 1L)) + ": " + where.substr(close + 3) +
                      " (not readable as a calibration)");
    }
    t.fail(key, name + ": not readable as a calibration (" + e.err.substr(0, e.err.find('\n')) + ")");
  }
  if (!in.isOpened()) t.fail(key, name + ": not readable as a calibration (OpenCV or ROS, YAML, XML or JSON)");
  if (!in.root().empty() && !in.root().isMap()) {
    t.fail(key, name + ": not a calibration (expected named entries such as camera_matrix, not a list)");
  }
  const auto first_of = [&](std::initializer_list<const char*> names) -> std::pair<std::string, cv::FileNode> {
    for (const char* n : names) {
      cv::FileNode node = in[n];
      if (!node.empty()) return {n, node};
    }
    return {"", cv::FileNode()};
  };
  // A matrix's declared shape (OpenCV's and ROS's "rows" and "cols"), when
  // it has one; its values must fill it.
  const auto shape = [&](const std::pair<std::string, cv::FileNode>& entry,
                         std::size_t values) -> std::optional<std::pair<int, int>> {
    const cv::FileNode& node = entry.second;
    if (!node.isMap() || (node["rows"].empty() && node["cols"].empty())) return std::nullopt;
    const cv::FileNode r = node["rows"], c = node["cols"];
    if (!r.isInt() || !c.isInt() || static_cast<int>(r) < 1 || static_cast<int>(c) < 1) {
      t.fail(key, name + ": '" + entry.first + "' has no positive integer 'rows' and 'cols'");
    }
    const int rows = static_cast<int>(r), cols = static_cast<int>(c);
    if (static_cast<std::size_t>(rows) * static_cast<std::size_t>(cols) != values) {
      t.fail(key, name + ": '" + entry.first + "' is " + std::to_string(rows) + "x" + std::to_string(cols) +
                      " (rows, cols) but holds " + std::to_string(values) + " values");
    }
    return std::make_pair(rows, cols);
  };
  const auto numbers = [&](const std::pair<std::string, cv::FileNode>& entry) {
    const auto v = numbers_of(entry.second);
    if (!v) t.fail(key, name + ": '" + entry.first + "' is not a list or matrix of numbers");
    for (const double x : *v) {
      if (!std::isfinite(x)) t.fail(key, name + ": '" + entry.first + "' holds a value that is not finite");
    }
    return *v;
  };
  Calibration c;
  const auto camera = first_of({"camera_matrix", "cameraMatrix", "K"});
  if (camera.first.empty()) {
    t.fail(key, name + ": no camera matrix; expected 'camera_matrix' (OpenCV, ROS) or 'cameraMatrix'");
  }
  const std::vector<double> k = numbers(camera);
  const auto k_shape = shape(camera, k.size());
  if (k.size() != 9 || (k_shape && k_shape->first != 3)) {
    t.fail(key, name + ": '" + camera.first + "' " +
                    (k_shape ? "is " + std::to_string(k_shape->first) + "x" + std::to_string(k_shape->second)
                             : "has " + std::to_string(k.size()) + " values") +
                    "; expected a 3x3 matrix");
  }
  c.fx = k[0];
  c.cx = k[2];
  c.fy = k[4];
  c.cy = k[5];
  if (!(c.fx > 0 && c.fy > 0) || k[3] != 0 || k[6] != 0 || k[7] != 0 || k[8] != 1) {
    t.fail(key, name + ": '" + camera.first + "' is not a camera matrix [fx 0 cx; 0 fy cy; 0 0 1] with fx, fy > 0");
  }
  if (std::abs(k[1]) > 1e-9 * c.fx) {
    t.fail(key, name + ": '" + camera.first + "' has a skew (" + std::to_string(k[1]) +
                    "), which this sensor does not model");
  }
  if (const auto model = in["distortion_model"]; !model.empty()) {
    const std::string m = model.isString() ? static_cast<std::string>(model) : std::string("?");
    if (m != "plumb_bob" && m != "rational_polynomial") {
      t.fail(key, name + ": distortion_model '" + m +
                      "'; this sensor models OpenCV's plumb_bob and rational_polynomial lenses");
    }
  }
  const auto dist = first_of({"distortion_coefficients", "dist_coeffs", "distCoeffs", "D"});
  // Without one of those, an entry that names a distortion otherwise would
  // be dropped without a word, leaving the lens uncorrected. (Beside one,
  // others are the calibration's own extras: dist_coeffs_std_dev.)
  if (dist.first.empty()) {
    for (const std::string& entry : in.root().keys()) {
      std::string lower = entry;
      std::transform(lower.begin(), lower.end(), lower.begin(), [](unsigned char ch) { return std::tolower(ch); });
      if (lower.find("dist") != std::string::npos && lower != "distortion_model") {
        t.fail(key, name + ": '" + entry + "' is not read; expected the distortion as 'distortion_coefficients' "
                        "(OpenCV, ROS), 'dist_coeffs', 'distCoeffs' or 'D'");
      }
    }
  }
  if (!dist.first.empty()) {
    std::vector<double> d = numbers(dist);
    if (const auto d_shape = shape(dist, d.size()); d_shape && d_shape->first != 1 && d_shape->second != 1) {
      t.fail(key, name + ": '" + dist.first + "' is " + std::to_string(d_shape->first) + "x" +
                      std::to_string(d_shape->second) + "; expected one row or one column of coefficients");
    }
    for (const double x : d) {
      if (std::abs(x) > 1000) t.fail(key, name + ": '" + dist.first + "' holds a coefficient beyond +-1000");
    }
    // Thin-prism and tilt terms (coefficients 9-14) that are zero are no
    // terms at all; 1-8 coefficients are completed with zeros.
    const size_t given = d.size();
    while (d.size() > 8 && d.back() == 0) d.pop_back();
    if (d.size() > 8) {
      t.fail(key, name + ": '" + dist.first + "' has " + std::to_string(given) +
                      " coefficients with thin-prism or tilt terms; this sensor models k1, k2, p1, p2, k3, k4, k5, k6");
    }
    if (!d.empty()) d.resize(d.size() <= 4 ? 4 : d.size() == 5 ? 5 : 8, 0.0);
    c.distortion = d;
  }
  const auto size_number = [&](const char* n) {
    const cv::FileNode node = in[n];
    if (node.empty()) return 0;
    if (!node.isInt() || static_cast<int>(node) < 1 || static_cast<int>(node) > 65536) {
      t.fail(key, name + ": '" + n + "' is not an image size in pixels (an integer in 1-65536)");
    }
    return static_cast<int>(node);
  };
  c.width = size_number("image_width");
  c.height = size_number("image_height");
  if (c.width == 0 && c.height == 0) {
    if (const auto res = first_of({"cameraResolution"}); !res.first.empty()) {
      const std::vector<double> wh = numbers(res);
      if (wh.size() != 2 || !(wh[0] >= 1 && wh[0] <= 65536 && wh[1] >= 1 && wh[1] <= 65536) ||
          wh[0] != std::floor(wh[0]) || wh[1] != std::floor(wh[1])) {
        t.fail(key, name + ": 'cameraResolution' is not [width, height] in pixels");
      }
      c.width = static_cast<int>(wh[0]);
      c.height = static_cast<int>(wh[1]);
    }
  }
  if ((c.width == 0) != (c.height == 0)) {
    t.fail(key, name + ": gives one of image_width and image_height without the other");
  }
  return c;
}

class PinholeMicroscope final : public gtrack::Sensor {
 public:
  explicit PinholeMicroscope(const gtrack::ConfigTable& t) {
    using gtrack::Range;
    if (t.has("calibration")) {
      // The intrinsics from a calibration file: none of them is given twice.
      for (const char* key : {"fx", "fy", "cx", "cy", "distortion"}) {
        if (t.has(key)) {
          t.fail(key, "is set by the calibration file ([sensor] calibration); give one or the other");
        }
      }
      const Calibration c = read_calibration(t, "calibration");
      width_ = static_cast<int>(t.integer_or("width", c.width, Range{1, 65536}));
      height_ = static_cast<int>(t.integer_or("height", c.height, Range{1, 65536}));
      if (c.width > 0 && (width_ != c.width || height_ != c.height)) {
        t.fail(t.has("width") ? "width" : "height",
               "the calibration file was made for " + std::to_string(c.width) + "x" + std::to_string(c.height) +
                   " images, the config says " + std::to_string(width_) + "x" + std::to_string(height_));
      }
      if (width_ <= 0 || height_ <= 0) {
        t.fail(width_ <= 0 ? "width" : "height",
               "missing; expected the image size (the calibration file does not give it)");
      }
      fx_ = c.fx;
      fy_ = c.fy;
      cx_ = c.cx;
      cy_ = c.cy;
      dist_ = c.distortion;
      if (!(cx_ >= -10.0 * width_ && cx_ <= 11.0 * width_ && cy_ >= -10.0 * height_ && cy_ <= 11.0 * height_)) {
        t.fail("calibration", "the principal point (" + std::to_string(cx_) + ", " + std::to_string(cy_) +
                                  ") lies far outside the " + std::to_string(width_) + "x" +
                                  std::to_string(height_) + " image; is the file for another camera?");
      }
    } else {
      t.mark_used("calibration");  // a known key, for the unknown-key message's list and suggestion
      width_ = static_cast<int>(t.integer("width", Range{1, 65536}));
      height_ = static_cast<int>(t.integer("height", Range{1, 65536}));
      // A focal length of 10^8 pixels sees a hundredth of a micrometre per
      // pixel at a metre: past it is a typing mistake; under one pixel, a
      // whole half-space falls within the image's first pixels.
      const Range focal = Range::closed(1.0, 1e8);
      fx_ = t.number("fx", focal);
      fy_ = t.number_or("fy", fx_, focal);
      // cx, cy as calibration tools give them (OpenCV: pixel centres on integers).
      // A principal point far outside the image is a unit or typing mistake.
      cx_ = t.number_or("cx", (width_ - 1) / 2.0, Range::closed(-10.0 * width_, 11.0 * width_));
      cy_ = t.number_or("cy", (height_ - 1) / 2.0, Range::closed(-10.0 * height_, 11.0 * height_));
      // Real lenses stay well inside +-1000, even in the rational model.
      dist_ = t.numbers_or("distortion", {}, std::nullopt, Range::closed(-1000, 1000));
      if (!(dist_.empty() || dist_.size() == 4 || dist_.size() == 5 || dist_.size() == 8)) {
        t.fail("distortion", "expected 4, 5 or 8 coefficients (k1, k2, p1, p2[, k3[, k4, k5, k6]]), got " +
                                 std::to_string(dist_.size()));
      }
    }
    near_ = t.number_or("near_mm", 1.0, Range{0.0, 1e5, true, false});
    working_distance_ = t.number_or("working_distance_mm", 100.0, Range{0.0, 1e5, true, false});  // up to 100 m
    if (near_ >= working_distance_) t.fail("near_mm", "must be less than working_distance_mm");
    K_ = (cv::Mat_<double>(3, 3) << fx_, 0, cx_, 0, fy_, cy_, 0, 0, 1);
    has_distortion_ = false;
    for (double d : dist_) has_distortion_ = has_distortion_ || d != 0.0;
    if (has_distortion_) {
      cv::initUndistortRectifyMap(K_, dist_, cv::Mat(), K_, cv::Size(width_, height_), CV_32FC1, map1_, map2_);
    }
  }

  gtrack::ImageSize image_size() const override { return {width_, height_}; }

  gtrack::Projection projection() const override {
    gtrack::Projection p;
    p.size = {width_, height_};
    // gtrack puts pixel centres at +0.5, OpenCV on integers.
    p.world_to_image << fx_, 0, cx_ + 0.5, 0, 0, fy_, cy_ + 0.5, 0, 0, 0, 1, 0;
    p.clip_planes.push_back(Eigen::Vector4d(0, 0, 1, -near_));  // z >= near
    return p;
  }

  std::optional<Eigen::Vector2d> project(const Eigen::Vector3d& X) const override {
    if (X.z() < near_) return std::nullopt;
    std::vector<cv::Point3d> in{{X.x(), X.y(), X.z()}};
    std::vector<cv::Point2d> out;
    cv::projectPoints(in, cv::Vec3d(0, 0, 0), cv::Vec3d(0, 0, 0), K_, dist_, out);
    // OpenCV puts pixel centres on integers; gtrack puts them at +0.5.
    return Eigen::Vector2d(out[0].x + 0.5, out[0].y + 0.5);
  }

  cv::Mat rectify(const cv::Mat& frame) const override {
    if (!has_distortion_) return frame;
    cv::Mat out;
    cv::remap(frame, out, map1_, map2_, cv::INTER_LINEAR);
    return out;
  }

  Eigen::Vector3d nominal_position_mm() const override { return {0, 0, working_distance_}; }
  double mm_per_pixel() const override { return working_distance_ / fx_; }

 private:
  int width_, height_;
  double fx_, fy_, cx_, cy_, near_, working_distance_;
  std::vector<double> dist_;
  bool has_distortion_;
  cv::Mat K_, map1_, map2_;
};

}  // namespace

GTRACK_PLUGIN(PinholeMicroscope, gtrack::Sensor, "pinhole_microscope", "1.0.0",
              "microscope camera: pinhole with optional distortion, world = camera frame")
