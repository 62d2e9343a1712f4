// The posed triangles, projected with the full sensor model, filled with
// alpha and outlined, plus the reading and the frame's status as text.
#include "overlay.hpp"

#include <cstdio>
#include <cstring>
#include <utility>
#include <opencv2/imgproc.hpp>

namespace gtrack::detail {

namespace {

// The overlay's font draws ASCII only: the signs of a unit spelt in it.
std::string in_ascii(const std::string& text) {
  static const std::pair<const char*, const char*> kSigns[] = {
      {"\u00B2", "^2"}, {"\u00B3", "^3"}, {"\u00B5", "u"}, {"\u03BC", "u"}, {"\u00B0", "deg "}, {"\u2126", "Ohm"}};
  std::string out;
  for (size_t i = 0; i < text.size();) {
    bool sign = false;
    for (const auto& [utf8, ascii] : kSigns) {
      if (text.compare(i, std::strlen(utf8), utf8) == 0) {
        out += ascii;
        i += std::strlen(utf8);
        sign = true;
        break;
      }
    }
    if (sign) continue;
    const auto c = static_cast<unsigned char>(text[i]);
    if (c < 0x80) {
      out += text[i++];
    } else {
      // Another character: one '?' for its bytes.
      out += '?';
      for (++i; i < text.size() && (static_cast<unsigned char>(text[i]) & 0xC0) == 0x80; ++i) {
      }
    }
  }
  return out;
}

}  // namespace

std::string reading_text(const Stimulus* stimulus, const Estimate& estimate) {
  if (!stimulus || !estimate.stimulus) return {};
  char value[32];
  std::snprintf(value, sizeof value, "%.4g", *estimate.stimulus);
  return in_ascii(stimulus->reading_label() + " = " + value + " " + stimulus->reading_unit());
}

cv::Mat draw_estimate(const cv::Mat& frame, const Sensor& sensor, const ArticulatedModel& model,
                      const std::string& reading, const Estimate& estimate) {
  cv::Mat out = frame.clone();
  const bool lost = estimate.status == TrackStatus::Lost;
  // Green, orange for a lost frame's held estimate, fill and outline alike.
  const cv::Scalar colour = lost ? cv::Scalar(0, 160, 255) : cv::Scalar(0, 220, 0);
  if (estimate.hypothesis.size() == model.dims()) {
    std::vector<Eigen::Vector3d> tris;
    model.pose(estimate.hypothesis, tris);
    cv::Mat fill = cv::Mat::zeros(frame.size(), CV_8U);
    std::vector<std::vector<cv::Point>> outlines;
    // Sub-pixel precision keeps thin links of a small gripper visible.
    constexpr int shift = 4;
    for (size_t i = 0; i + 2 < tris.size(); i += 3) {
      std::vector<cv::Point> poly;
      for (size_t k = 0; k < 3; ++k) {
        const auto p = sensor.project(tris[i + k]);
        if (!p) break;
        // project() puts pixel centres at +0.5, OpenCV's drawing on integers.
        poly.emplace_back(cvRound((p->x() - 0.5) * (1 << shift)), cvRound((p->y() - 0.5) * (1 << shift)));
      }
      if (poly.size() != 3) continue;
      cv::fillConvexPoly(fill, poly, 255, cv::LINE_AA, shift);
      outlines.push_back(std::move(poly));
    }
    cv::Mat tinted = out.clone();
    tinted.setTo(colour, fill);
    cv::addWeighted(out, 0.55, tinted, 0.45, 0, out);
    cv::polylines(out, outlines, true, colour, 1, cv::LINE_AA, shift);
  }
  const double font = std::max(0.5, frame.rows / 900.0);
  const int thick = std::max(1, static_cast<int>(font * 1.5));
  if (!reading.empty()) {
    int base = 0;
    const cv::Size ts = cv::getTextSize(reading, cv::FONT_HERSHEY_SIMPLEX, font, thick, &base);
    const cv::Point at(frame.cols - ts.width - 12, frame.rows - 12);
    cv::putText(out, reading, at, cv::FONT_HERSHEY_SIMPLEX, font, cv::Scalar(0, 0, 0), thick + 2, cv::LINE_AA);
    cv::putText(out, reading, at, cv::FONT_HERSHEY_SIMPLEX, font, cv::Scalar(255, 255, 255), thick, cv::LINE_AA);
  }
  if (lost) {
    cv::putText(out, "lost", cv::Point(12, static_cast<int>(30 * font)), cv::FONT_HERSHEY_SIMPLEX, font,
                cv::Scalar(0, 160, 255), thick, cv::LINE_AA);
  } else if (estimate.tilt_margin && *estimate.tilt_margin < kNarrowTiltMargin) {
    // The outline fits either sign of the tilt: the overlay looks right
    // whichever was taken.
    cv::putText(out, "tilt's sign uncertain", cv::Point(12, static_cast<int>(30 * font)), cv::FONT_HERSHEY_SIMPLEX,
                font, cv::Scalar(0, 220, 255), thick, cv::LINE_AA);
  }
  return out;
}

}  // namespace gtrack::detail
