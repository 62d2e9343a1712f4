// Conversions between BitMask and OpenCV images (not on the hot path).
#include "render/bit_mask.hpp"

#include <bit>

namespace gtrack::render {

void BitMask::pack(const cv::Mat& mask) {
  CV_Assert(mask.type() == CV_8UC1 && mask.cols == width_ && mask.rows == height_);
  for (int y = 0; y < height_; ++y) {
    const std::uint8_t* src = mask.ptr<std::uint8_t>(y);
    std::uint64_t* dst = row(y);
    for (int w = 0; w < words_; ++w) dst[w] = 0;
    for (int x = 0; x < width_; ++x) {
      if (src[x]) dst[x >> 6] |= std::uint64_t{1} << (x & 63);
    }
  }
}

cv::Mat BitMask::unpack() const {
  cv::Mat out(height_, width_, CV_8UC1);
  for (int y = 0; y < height_; ++y) {
    const std::uint64_t* src = row(y);
    std::uint8_t* dst = out.ptr<std::uint8_t>(y);
    for (int x = 0; x < width_; ++x) dst[x] = (src[x >> 6] >> (x & 63)) & 1 ? 255 : 0;
  }
  return out;
}

std::uint64_t BitMask::count() const {
  std::uint64_t n = 0;
  for (std::uint64_t w : bits_) n += static_cast<std::uint64_t>(std::popcount(w));
  return n;
}

}  // namespace gtrack::render
