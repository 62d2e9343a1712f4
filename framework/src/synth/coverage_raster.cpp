#include "synth/coverage_raster.hpp"

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>

namespace gtrack::synth {

SampleGrid::SampleGrid(cv::Rect r, int s) : roi(r), ss(s), buf(cv::Mat::zeros(r.height * s, r.width * s, CV_8U)) {}

void SampleGrid::fill_convex(const Eigen::Vector2d* v, int n, std::uint8_t value) {
  if (n < 3 || buf.empty()) return;
  Eigen::Vector2d p[16];
  n = std::min(n, 16);
  double y_lo = 1e300, y_hi = -1e300;
  for (int i = 0; i < n; ++i) {
    p[i] = (v[i] - Eigen::Vector2d(roi.x, roi.y)) * ss;
    y_lo = std::min(y_lo, p[i].y());
    y_hi = std::max(y_hi, p[i].y());
  }
  const int r0 = std::max(0, static_cast<int>(std::ceil(y_lo - 0.5)));
  const int r1 = std::min(buf.rows - 1, static_cast<int>(std::ceil(y_hi - 0.5)) - 1);
  for (int r = r0; r <= r1; ++r) {
    const double yc = r + 0.5;
    double xl = 1e300, xr = -1e300;
    for (int i = 0; i < n; ++i) {
      const Eigen::Vector2d& a = p[i];
      const Eigen::Vector2d& b = p[(i + 1) % n];
      if ((a.y() - yc) * (b.y() - yc) > 0 || a.y() == b.y()) continue;
      const double x = a.x() + (yc - a.y()) * (b.x() - a.x()) / (b.y() - a.y());
      xl = std::min(xl, x);
      xr = std::max(xr, x);
    }
    if (!(xl < xr)) continue;
    const int c0 = std::max(0, static_cast<int>(std::ceil(xl - 0.5)));
    const int c1 = std::min(buf.cols, static_cast<int>(std::ceil(xr - 0.5)));
    if (c0 < c1) std::fill(buf.ptr<std::uint8_t>(r) + c0, buf.ptr<std::uint8_t>(r) + c1, value);
  }
}

void SampleGrid::resolve(cv::Mat& coverage, cv::Mat* mean_value) const {
  cv::Mat set = (buf > 0) / 255;
  cv::Mat setf;
  set.convertTo(setf, CV_32F);
  cv::resize(setf, coverage, roi.size(), 0, 0, cv::INTER_AREA);
  if (mean_value) {
    cv::Mat vf, sum;
    buf.convertTo(vf, CV_32F);
    cv::resize(vf, sum, roi.size(), 0, 0, cv::INTER_AREA);
    *mean_value = sum / cv::max(coverage, 1e-6f);
  }
}

cv::Rect bounding_rect(const Eigen::Vector2d* v, int n) {
  double x0 = 1e300, y0 = 1e300, x1 = -1e300, y1 = -1e300;
  for (int i = 0; i < n; ++i) {
    x0 = std::min(x0, v[i].x());
    y0 = std::min(y0, v[i].y());
    x1 = std::max(x1, v[i].x());
    y1 = std::max(y1, v[i].y());
  }
  if (n == 0) return {};
  const int ix0 = static_cast<int>(std::floor(x0)), iy0 = static_cast<int>(std::floor(y0));
  return {ix0, iy0, static_cast<int>(std::ceil(x1)) - ix0 + 1, static_cast<int>(std::ceil(y1)) - iy0 + 1};
}

}  // namespace gtrack::synth
