// The pinhole microscope against OpenCV's projection.
#include <gtest/gtest.h>

#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <opencv2/calib3d.hpp>
#include <opencv2/core/persistence.hpp>
#include <opencv2/imgproc.hpp>
#include <random>

#include "support/plugins.hpp"

using gtrack::testing::make_sensor;

TEST(PinholeMicroscope, LinearProjectionMatchesProjectPoints) {
  auto s = make_sensor(
      "plugin = \"pinhole_microscope\"\nwidth = 1024\nheight = 768\nfx = 12000\nfy = 12500\ncx = 500.3\ncy = 380.7");
  const auto p = s->projection();
  EXPECT_EQ(p.size.width, 1024);
  EXPECT_EQ(p.size.height, 768);
  cv::Mat K = (cv::Mat_<double>(3, 3) << 12000, 0, 500.3, 0, 12500, 380.7, 0, 0, 1);
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> xy(-4, 4), z(90, 110);
  for (int i = 0; i < 200; ++i) {
    Eigen::Vector3d X(xy(rng), xy(rng), z(rng));
    std::vector<cv::Point2d> ref;
    cv::projectPoints(std::vector<cv::Point3d>{{X.x(), X.y(), X.z()}}, cv::Vec3d(0, 0, 0), cv::Vec3d(0, 0, 0), K,
                      cv::noArray(), ref);
    Eigen::Vector3d h = p.world_to_image * X.homogeneous();
    // gtrack pixel centres sit at +0.5 of OpenCV's.
    EXPECT_NEAR(h.x() / h.z(), ref[0].x + 0.5, 1e-9);
    EXPECT_NEAR(h.y() / h.z(), ref[0].y + 0.5, 1e-9);
    auto q = s->project(X);
    ASSERT_TRUE(q);
    EXPECT_NEAR(q->x(), ref[0].x + 0.5, 1e-9);
    // The near plane keeps the point.
    ASSERT_EQ(p.clip_planes.size(), 1u);
    EXPECT_GT(p.clip_planes[0].dot(X.homogeneous()), 0);
  }
  EXPECT_FALSE(s->project(Eigen::Vector3d(0, 0, -5)));
}

TEST(PinholeMicroscope, DistortionIsAppliedByProjectAndRemovedByRectify) {
  auto s = make_sensor(
      "plugin = \"pinhole_microscope\"\nwidth = 400\nheight = 400\nfx = 4000\ndistortion = [-0.4, 0.1, 0.001, 0.002]");
  cv::Mat K = (cv::Mat_<double>(3, 3) << 4000, 0, 199.5, 0, 4000, 199.5, 0, 0, 1);
  std::vector<double> D{-0.4, 0.1, 0.001, 0.002};
  Eigen::Vector3d X(1.5, -1.2, 100);
  std::vector<cv::Point2d> ref;
  cv::projectPoints(std::vector<cv::Point3d>{{X.x(), X.y(), X.z()}}, cv::Vec3d(0, 0, 0), cv::Vec3d(0, 0, 0), K, D, ref);
  auto q = s->project(X);
  ASSERT_TRUE(q);
  EXPECT_NEAR(q->x(), ref[0].x + 0.5, 1e-9);
  EXPECT_NEAR(q->y(), ref[0].y + 0.5, 1e-9);
  // A dot drawn where the lens puts it lands, after rectify, where the
  // linear projection says.
  cv::Mat img(400, 400, CV_8U, cv::Scalar(0));
  cv::circle(img, cv::Point(int(std::lround(ref[0].x)), int(std::lround(ref[0].y))), 3, cv::Scalar(255), -1);
  cv::Mat rect = s->rectify(img);
  cv::Moments mo = cv::moments(rect, true);
  ASSERT_GT(mo.m00, 0);
  Eigen::Vector3d h = s->projection().world_to_image * X.homogeneous();
  EXPECT_NEAR(mo.m10 / mo.m00 + 0.5, h.x() / h.z(), 1.0);
  EXPECT_NEAR(mo.m01 / mo.m00 + 0.5, h.y() / h.z(), 1.0);
}

TEST(PinholeMicroscope, BadTablesAreRejected) {
  EXPECT_THROW(make_sensor("plugin = \"pinhole_microscope\"\nwidth = 100\nheight = 100"), gtrack::ConfigError);
  EXPECT_THROW(make_sensor("plugin = \"pinhole_microscope\"\nwidth = 100\nheight = 100\nfx = -3"), gtrack::ConfigError);
  EXPECT_THROW(make_sensor("plugin = \"pinhole_microscope\"\nwidth = 100\nheight = 100\nfx = 3\ndistortion = [1]"),
               gtrack::ConfigError);
}

namespace {

namespace fs = std::filesystem;

// A folder of this process's own, removed when it exits.
fs::path calibration_dir() {
  static const struct Folder {
    fs::path path = fs::temp_directory_path() / ("gtrack_sensor_test_" + std::to_string(::getpid()));
    Folder() { fs::create_directories(path); }
    ~Folder() {
      std::error_code ec;
      fs::remove_all(path, ec);
    }
  } folder;
  fs::create_directories(folder.path);
  return folder.path;
}

std::string error_of(const std::string& toml, const std::string& source = "<test>") {
  try {
    gtrack::testing::loader().make_sensor(gtrack::ConfigTable::parse(toml, source));
  } catch (const gtrack::ConfigError& e) {
    return e.what();
  }
  return "";
}

// The same camera, given by its keys and by a calibration file, projects
// every point to the same pixel, lens distortion included.
void expect_same_camera(const std::shared_ptr<gtrack::Sensor>& a, const std::shared_ptr<gtrack::Sensor>& b) {
  EXPECT_EQ(a->image_size().width, b->image_size().width);
  EXPECT_EQ(a->image_size().height, b->image_size().height);
  EXPECT_TRUE(a->projection().world_to_image.isApprox(b->projection().world_to_image, 1e-12));
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> xy(-4, 4), z(90, 110);
  for (int i = 0; i < 50; ++i) {
    const Eigen::Vector3d X(xy(rng), xy(rng), z(rng));
    const auto p = a->project(X), q = b->project(X);
    ASSERT_TRUE(p && q);
    EXPECT_NEAR(p->x(), q->x(), 1e-9);
    EXPECT_NEAR(p->y(), q->y(), 1e-9);
  }
}

}  // namespace

TEST(PinholeMicroscope, ReadsOpenCvCalibrationFiles) {
  const auto keys = make_sensor(
      "plugin = \"pinhole_microscope\"\nwidth = 640\nheight = 480\nfx = 6400\nfy = 6420\ncx = 321.5\ncy = 238.25\n"
      "distortion = [-0.3, 0.12, 0.001, -0.002, 0.05]");
  const cv::Mat K = (cv::Mat_<double>(3, 3) << 6400, 0, 321.5, 0, 6420, 238.25, 0, 0, 1);
  // calibrateCamera's 14 coefficients, the thin-prism and tilt terms zero.
  cv::Mat D = cv::Mat::zeros(1, 14, CV_64F);
  D.at<double>(0) = -0.3;
  D.at<double>(1) = 0.12;
  D.at<double>(2) = 0.001;
  D.at<double>(3) = -0.002;
  D.at<double>(4) = 0.05;
  for (const char* ext : {"yml", "xml", "json"}) {
    SCOPED_TRACE(ext);
    const fs::path file = calibration_dir() / (std::string("opencv.") + ext);
    {
      cv::FileStorage out(file.string(), cv::FileStorage::WRITE);
      out << "image_width" << 640 << "image_height" << 480 << "camera_matrix" << K << "distortion_coefficients"
          << D;
    }
    // The size comes from the file when the config does not give it.
    expect_same_camera(keys, make_sensor("plugin = \"pinhole_microscope\"\ncalibration = \"" + file.string() + "\""));
  }
  // OpenCV's interactive calibration: other names, the size as a pair.
  const fs::path interactive = calibration_dir() / "interactive.xml";
  {
    cv::FileStorage out(interactive.string(), cv::FileStorage::WRITE);
    out << "cameraResolution" << cv::Size(640, 480) << "cameraMatrix" << K << "dist_coeffs" << D.colRange(0, 5)
        << "cameraMatrix_std_dev" << cv::Mat::zeros(4, 1, CV_64F) << "dist_coeffs_std_dev"
        << cv::Mat::zeros(5, 1, CV_64F);
  }
  expect_same_camera(keys, make_sensor("plugin = \"pinhole_microscope\"\ncalibration = \"" + interactive.string() + "\""));
  // JSON with the matrix as rows.
  const fs::path rows = calibration_dir() / "rows.json";
  std::ofstream(rows) << R"({"image_width": 640, "image_height": 480,
    "camera_matrix": [[6400, 0, 321.5], [0, 6420, 238.25], [0, 0, 1]],
    "distortion_coefficients": [[-0.3, 0.12, 0.001, -0.002, 0.05]]})";
  expect_same_camera(keys, make_sensor("plugin = \"pinhole_microscope\"\ncalibration = \"" + rows.string() + "\""));
}

TEST(PinholeMicroscope, ReadsRosCameraInfoWithAPathFromTheConfigsFolder) {
  const fs::path dir = calibration_dir() / "ros";
  fs::create_directories(dir);
  std::ofstream(dir / "camera.yaml") << R"(image_width: 640
image_height: 480
camera_name: microscope
camera_matrix:
  rows: 3
  cols: 3
  data: [6400, 0, 321.5, 0, 6420, 238.25, 0, 0, 1]
distortion_model: plumb_bob
distortion_coefficients:
  rows: 1
  cols: 5
  data: [-0.3, 0.12, 0.001, -0.002, 0.05]
rectification_matrix:
  rows: 3
  cols: 3
  data: [1, 0, 0, 0, 1, 0, 0, 0, 1]
)";
  const auto keys = make_sensor(
      "plugin = \"pinhole_microscope\"\nwidth = 640\nheight = 480\nfx = 6400\nfy = 6420\ncx = 321.5\ncy = 238.25\n"
      "distortion = [-0.3, 0.12, 0.001, -0.002, 0.05]");
  const auto ros = gtrack::testing::loader().make_sensor(gtrack::ConfigTable::parse(
      "plugin = \"pinhole_microscope\"\nwidth = 640\nheight = 480\ncalibration = \"camera.yaml\"",
      (dir / "lab.toml").string()));
  expect_same_camera(keys, ros);
}

TEST(PinholeMicroscope, BadCalibrationFilesAreOneLineNamingFileAndKey) {
  const fs::path dir = calibration_dir();
  const std::string head = "plugin = \"pinhole_microscope\"\ncalibration = \"";
  const auto expect_error = [&](const std::string& toml, const std::string& what) {
    const std::string e = error_of(toml);
    EXPECT_NE(e.find(what), std::string::npos) << (e.empty() ? "accepted" : e);
    EXPECT_EQ(e.find('\n'), std::string::npos) << e;
  };
  const fs::path good = dir / "good.yml";
  {
    cv::FileStorage out(good.string(), cv::FileStorage::WRITE);
    out << "image_width" << 640 << "image_height" << 480 << "camera_matrix"
        << cv::Mat(cv::Matx33d(6400, 0, 320, 0, 6400, 240, 0, 0, 1));
  }
  expect_error(head + (dir / "none.yml").string() + "\"", "key 'calibration': " + (dir / "none.yml").string() + ": no such file");
  expect_error(head + good.string() + "\"\nfx = 100", "key 'fx': is set by the calibration file");
  expect_error(head + good.string() + "\"\nwidth = 1024\nheight = 1024",
               "the calibration file was made for 640x480 images, the config says 1024x1024");
  const auto write = [&](const std::string& name, const std::string& text) {
    std::ofstream(dir / name) << text;
    return head + (dir / name).string() + "\"";
  };
  expect_error(write("garbage.yml", "%YAML:1.0\n---\ncamera_matrix: [1, 2\n"),
               "garbage.yml:3: Missing , between the elements (not readable as a calibration)");
  // A ROS file has no "%YAML" line: the line named is still the file's own.
  expect_error(write("garbage_ros.yaml", "image_width: 640\ncamera_matrix: [1, 2\n"), "garbage_ros.yaml:2: ");
  expect_error(write("list.yml", "%YAML:1.0\n---\n- 1\n- 2\n"), "list.yml: not a calibration (expected named entries");
  expect_error(write("nomatrix.yml", "%YAML:1.0\n---\nimage_width: 640\n"), "no camera matrix");
  expect_error(write("short.yml", "%YAML:1.0\n---\ncamera_matrix: [6400, 0, 320, 0, 6400]\n"),
               "'camera_matrix' has 5 values; expected a 3x3 matrix");
  // A matrix's rows and cols must hold its values, and be 3x3 and one row
  // or column (OpenCV refuses such a file when it reads it as a matrix).
  const std::string ros_k = "camera_matrix:\n  rows: 2\n  cols: 3\n  data: [6400, 0, 320, 0, 6400, 240, 0, 0, 1]\n";
  expect_error(write("rows.yaml", "image_width: 640\nimage_height: 480\n" + ros_k),
               "rows.yaml: 'camera_matrix' is 2x3 (rows, cols) but holds 9 values");
  expect_error(write("k9x1.yaml", "camera_matrix:\n  rows: 9\n  cols: 1\n  data: [6400, 0, 320, 0, 6400, 240, 0, 0, 1]\n"),
               "'camera_matrix' is 9x1; expected a 3x3 matrix");
  const std::string k = "camera_matrix: !!opencv-matrix\n  rows: 3\n  cols: 3\n  dt: d\n"
                        "  data: [6400, 0, 320, 0, 6400, 240, 0, 0, 1]\n";
  expect_error(write("dcols.yml", "%YAML:1.0\n---\n" + k +
                                      "distortion_coefficients: !!opencv-matrix\n  rows: 1\n  cols: 4\n  dt: d\n"
                                      "  data: [0.1, 0, 0, 0, 0]\n"),
               "'distortion_coefficients' is 1x4 (rows, cols) but holds 5 values");
  expect_error(write("d2x2.yml", "%YAML:1.0\n---\n" + k +
                                     "distortion_coefficients: !!opencv-matrix\n  rows: 2\n  cols: 2\n  dt: d\n"
                                     "  data: [0.1, 0, 0, 0]\n"),
               "'distortion_coefficients' is 2x2; expected one row or one column of coefficients");
  expect_error(write("skew.yml", "%YAML:1.0\n---\ncamera_matrix: [6400, 3, 320, 0, 6400, 240, 0, 0, 1]\n"),
               "has a skew");
  expect_error(write("fisheye.yml", "%YAML:1.0\n---\ncamera_matrix: [6400, 0, 320, 0, 6400, 240, 0, 0, 1]\n"
                                    "distortion_model: equidistant\ndistortion_coefficients: [0.1, 0, 0, 0]\n"),
               "distortion_model 'equidistant'");
  expect_error(write("tilt.yml", "%YAML:1.0\n---\ncamera_matrix: [6400, 0, 320, 0, 6400, 240, 0, 0, 1]\n"
                                 "distortion_coefficients: [0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0.01, 0]\n"),
               "has 14 coefficients with thin-prism or tilt terms");
  // A distortion under a name that is not read would leave the lens
  // uncorrected without a word.
  expect_error(write("dist_coeff.yml", "%YAML:1.0\n---\ncamera_matrix: [6400, 0, 320, 0, 6400, 240, 0, 0, 1]\n"
                                       "dist_coeff: [0.1, 0, 0, 0]\n"),
               "dist_coeff.yml: 'dist_coeff' is not read; expected the distortion as 'distortion_coefficients'");
  expect_error(write("ragged.json", R"({"camera_matrix": [[6400, 0, 320], 0, [0, 0, 1]]})"),
               "'camera_matrix' is not a list or matrix of numbers");
  // A ROS file that opens its document with "---": its own lines are named.
  expect_error(write("dashes.yaml", "---\nimage_width: 640\ncamera_matrix: [1, 2\n"), "dashes.yaml:3: ");
  expect_error(write("nosize.yml", "%YAML:1.0\n---\ncamera_matrix: [6400, 0, 320, 0, 6400, 240, 0, 0, 1]\n"),
               "key 'width': missing; expected the image size");
  expect_error(head + (dir / "nosize.yml").string() + "\"\nwidth = 640", "key 'height': missing; expected the image size");
}
