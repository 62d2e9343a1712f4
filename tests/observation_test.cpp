// Segmentation into O on synthetic images: colour bounds, opening, downscale,
// ROI and the temporal prior.
#include <gtest/gtest.h>

#include <opencv2/imgproc.hpp>

#include "gtrack/error.hpp"
#include "gtrack/observation.hpp"

namespace {

cv::Mat grey_frame() { return cv::Mat(200, 200, CV_8UC3, cv::Scalar(128, 128, 128)); }

TEST(Observation, HsvBoundsOpeningAndDownscale) {
  cv::Mat img = grey_frame();
  cv::circle(img, {60, 60}, 20, cv::Scalar(40, 40, 200), cv::FILLED);  // saturated red disc
  img.at<cv::Vec3b>(150, 150) = cv::Vec3b(40, 40, 200);              // one-pixel speckle
  gtrack::ObservationConfig c;
  c.open_kernel_px = 3;
  gtrack::Segmenter seg(c, {200, 200}, {50, 50});
  const cv::Mat full = seg.segment(img);
  EXPECT_EQ(full.at<uchar>(150, 150), 0);  // removed by the opening
  EXPECT_EQ(full.at<uchar>(60, 60), 255);
  EXPECT_NEAR(cv::countNonZero(full), CV_PI * 20 * 20, 60);
  const auto obs = seg.observe(img);
  EXPECT_EQ(obs.mask.size(), cv::Size(50, 50));
  EXPECT_NEAR(static_cast<double>(obs.count), CV_PI * 5 * 5, 8);
  EXPECT_EQ(obs.mask.at<uchar>(15, 15), 255);
}

// The downscale's threshold is the share of a render pixel's area that must
// be observed: the smallest shares take any area at all, never the whole
// image (a share under 0.5/255 had set every pixel).
TEST(Observation, ASmallDownscaleThresholdTakesAnyAreaNotTheWholeImage) {
  cv::Mat img = grey_frame();
  cv::rectangle(img, cv::Rect(40, 40, 41, 41), cv::Scalar(40, 40, 200), cv::FILLED);
  for (const double share : {0.5, 0.01, 0.001, 1e-9}) {
    SCOPED_TRACE(share);
    gtrack::ObservationConfig c;
    c.downscale_threshold = share;
    gtrack::Segmenter seg(c, {200, 200}, {50, 50});
    const auto obs = seg.observe(img);
    // The square's 41 px span 10.25 render pixels: 10 whole, and up to two
    // partly covered rows and columns.
    EXPECT_GE(obs.count, 100u);
    EXPECT_LE(obs.count, 144u);
  }
}

TEST(Observation, HueBoundsSelectAColour) {
  cv::Mat img = grey_frame();
  cv::rectangle(img, {10, 10, 40, 40}, cv::Scalar(200, 40, 40), cv::FILLED);  // blue: H ~ 120
  cv::rectangle(img, {100, 100, 40, 40}, cv::Scalar(40, 200, 40), cv::FILLED);  // green: H ~ 60
  gtrack::ObservationConfig c;
  c.hue_min = 100;
  c.hue_max = 140;
  c.open_kernel_px = 0;  // square corners would be rounded off
  gtrack::Segmenter seg(c, {200, 200}, {200, 200});
  const cv::Mat m = seg.segment(img);
  EXPECT_EQ(cv::countNonZero(m), 40 * 40);
  EXPECT_EQ(m.at<uchar>(20, 20), 255);
}

TEST(Observation, LuminanceForUltrasound) {
  cv::Mat img(100, 100, CV_8UC3, cv::Scalar(30, 30, 30));
  cv::rectangle(img, {20, 20, 10, 10}, cv::Scalar(220, 220, 220), cv::FILLED);
  gtrack::ObservationConfig c;
  c.color_space = "luminance";
  c.luminance_min = 150;
  c.open_kernel_px = 0;
  gtrack::Segmenter seg(c, {100, 100}, {100, 100});
  EXPECT_EQ(seg.observe(img).count, 100u);
}

TEST(Observation, RoiAndPriorDropFarPixels) {
  cv::Mat img = grey_frame();
  cv::circle(img, {60, 60}, 15, cv::Scalar(40, 40, 200), cv::FILLED);    // the gripper
  cv::circle(img, {160, 160}, 15, cv::Scalar(40, 40, 200), cv::FILLED);  // a distractor
  gtrack::ObservationConfig c;
  c.roi_margin_px = 20;
  c.prior_sigma_px = 8;
  gtrack::Segmenter seg(c, {200, 200}, {100, 100});
  const auto all = seg.observe(img);
  gtrack::ObservationPrior prior;
  prior.previous_mask = cv::Mat::zeros(100, 100, CV_8U);
  cv::circle(prior.previous_mask, {30, 30}, 7, 255, cv::FILLED);  // last model, render size
  const auto near = seg.observe(img, &prior);
  EXPECT_GT(all.count, near.count);
  EXPECT_EQ(near.mask.at<uchar>(80, 80), 0);
  EXPECT_EQ(near.mask.at<uchar>(30, 30), 255);
  EXPECT_LT(near.roi.width, 200);
  // Without the ROI the prior alone still drops the distractor.
  c.roi = false;
  gtrack::Segmenter no_roi(c, {200, 200}, {100, 100});
  const auto prior_only = no_roi.observe(img, &prior);
  EXPECT_EQ(prior_only.mask.at<uchar>(80, 80), 0);
  EXPECT_EQ(prior_only.count, near.count);
  EXPECT_EQ(prior_only.detected, all.count);
}

// Rectangles the recording burns in (a scale bar, a scanner's text) are
// never observed, whatever their colour; the rest is as before.
TEST(Observation, ExcludedRectanglesAreNeverObserved) {
  cv::Mat img = grey_frame();
  cv::circle(img, {60, 60}, 20, cv::Scalar(40, 40, 200), cv::FILLED);
  cv::rectangle(img, cv::Rect(150, 180, 40, 12), cv::Scalar(40, 40, 200), cv::FILLED);  // a red scale bar
  gtrack::ObservationConfig c;
  gtrack::Segmenter all(c, {200, 200}, {50, 50});
  EXPECT_EQ(all.segment(img).at<uchar>(185, 170), 255);
  c.exclude_px = {cv::Rect(145, 175, 55, 25)};
  gtrack::Segmenter seg(c, {200, 200}, {50, 50});
  const cv::Mat full = seg.segment(img);
  EXPECT_EQ(cv::countNonZero(full(cv::Rect(145, 175, 55, 25))), 0);
  cv::Mat expected = all.segment(img);
  expected(cv::Rect(145, 175, 55, 25)).setTo(0);
  EXPECT_EQ(cv::countNonZero(full != expected), 0);
}

TEST(Observation, NothingDetectedIsEmpty) {
  gtrack::Segmenter seg(gtrack::ObservationConfig{}, {200, 200}, {50, 50});
  EXPECT_TRUE(seg.observe(grey_frame()).empty());
}

// A frame of the right size but not 8-bit BGR is refused, naming what it is.
TEST(Observation, AFrameOfOtherChannelsIsRefusedNamingThem) {
  gtrack::Segmenter seg(gtrack::ObservationConfig{}, {200, 200}, {50, 50});
  const auto error_of = [&](const cv::Mat& frame) -> std::string {
    try {
      seg.observe(frame);
    } catch (const gtrack::InputError& e) {
      return e.what();
    }
    return "accepted";
  };
  EXPECT_NE(error_of(cv::Mat(200, 200, CV_8UC1, cv::Scalar(0))).find("got 200x200 with 1 channel of 8 bits"),
            std::string::npos);
  EXPECT_NE(error_of(cv::Mat(200, 200, CV_16UC4, cv::Scalar::all(0))).find("got 200x200 with 4 channels of 16 bits"),
            std::string::npos);
  EXPECT_NE(error_of(cv::Mat(100, 200, CV_8UC3)).find("expected a 200x200 BGR image"), std::string::npos);
}

}  // namespace
