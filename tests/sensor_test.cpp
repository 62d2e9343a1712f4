// The pinhole microscope against OpenCV's projection.
#include <gtest/gtest.h>

#include <opencv2/calib3d.hpp>
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
