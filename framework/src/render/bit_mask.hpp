// A binary image stored one bit per pixel, 64 pixels per word.
//
// The cpu backend keeps the observation and each worker's hypothesis in this
// form, so that |O & P| and |P| over a row are a handful of AND + popcount
// instructions instead of a byte per pixel. Bit (x % 64) of word x / 64 of a
// row is pixel x; bits past the image width (and the spare word that ends
// each row) are always zero, so whole words can be counted without masking.
#pragma once

#include <algorithm>
#include <cstdint>
#include <opencv2/core.hpp>
#include <vector>

namespace gtrack::render {

class BitMask {
 public:
  BitMask() = default;
  BitMask(int width, int height) { resize(width, height); }

  void resize(int width, int height) {
    width_ = width;
    height_ = height;
    words_ = (width + 63) / 64 + 1;  // a spare word, always zero, lets spans write two words blindly
    bits_.assign(static_cast<size_t>(words_) * height, 0);
  }

  int width() const { return width_; }
  int height() const { return height_; }
  int words_per_row() const { return words_; }

  std::uint64_t* row(int y) { return bits_.data() + static_cast<size_t>(y) * words_; }
  const std::uint64_t* row(int y) const { return bits_.data() + static_cast<size_t>(y) * words_; }

  void clear() { std::fill(bits_.begin(), bits_.end(), 0); }

  // Non-zero pixels of a CV_8U image of the same size become set bits.
  void pack(const cv::Mat& mask);
  // A CV_8U image, 255 where a bit is set.
  cv::Mat unpack() const;
  std::uint64_t count() const;

 private:
  int width_ = 0, height_ = 0, words_ = 0;
  std::vector<std::uint64_t> bits_;
};

}  // namespace gtrack::render
