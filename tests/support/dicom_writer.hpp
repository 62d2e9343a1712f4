// Writing DICOM files in tests, as a scanner exports them: a multi-frame
// file with native pixels (explicit or implicit VR) or with each frame
// compressed (JPEG, JPEG 2000, RLE lossless), from OpenCV images.
#pragma once

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <string>
#include <utility>
#include <vector>

namespace gtrack::testing {

struct DicomWriteOptions {
  std::string transfer_syntax = "1.2.840.10008.1.2.1";  // explicit VR little endian
  bool preamble = true;          // the 128 bytes, "DICM" and the file meta group
  std::string photometric;       // "" : MONOCHROME2 or RGB by the channels
  int bits_stored = 0;           // 16-bit frames: 0 = 16
  int high_bit = -1;             // -1: bits_stored - 1
  int planar = 0;                // colour, native: 1 = one plane after another
  double frame_time_ms = 0;      // (0018,1063), 0: none
  std::string frame_time_vector;  // (0018,1065), "": none
  std::string compress_as;       // ".jpg", ".jp2" or ".rle": each frame encoded so (transfer syntax to match)
  std::vector<std::string> encoded;  // compressed: these streams as the frames' (the frames give the header)
  std::string video;             // a video stream as the pixel data, in fragments_per_frame fragments (the
                                 // frames give the header; transfer syntax to match)
  int fragments_per_frame = 1;   // compressed: each frame's stream split into this many fragments
  bool offset_table = false;     // compressed: a basic offset table with each frame's offset
  bool strip_jfif = false;       // ".jpg": the JFIF marker taken out, as some scanners write theirs
  bool sequence_before = false;  // an undefined-length sequence before the image tags
  double region_cm_x = 0, region_cm_y = 0;  // > 0: an ultrasound region with this pixel size (cm)
  std::string pixel_spacing;     // (0028,0030) "row\\column" in mm, "": none
};

class DicomWriter {
 public:
  explicit DicomWriter(bool explicit_vr) : explicit_(explicit_vr) {}

  void element(std::uint16_t group, std::uint16_t elem, const char* vr, const std::string& value) {
    std::string v = value;
    if (v.size() % 2) v += (std::string(vr) == "UI" ? '\0' : ' ');
    header(group, elem, vr, static_cast<std::uint32_t>(v.size()));
    out_ += v;
  }
  void us(std::uint16_t group, std::uint16_t elem, std::uint16_t v) {
    header(group, elem, "US", 2);
    u16(v);
  }
  void header(std::uint16_t group, std::uint16_t elem, const char* vr, std::uint32_t length) {
    u16(group);
    u16(elem);
    const std::string r(vr);
    if (!explicit_ || group == 0xFFFE) {
      u32(length);
    } else if (r == "OB" || r == "OW" || r == "SQ" || r == "UN" || r == "UT") {
      out_ += r;
      u16(0);
      u32(length);
    } else {
      out_ += r;
      u16(static_cast<std::uint16_t>(length));
    }
  }
  void raw(const std::string& bytes) { out_ += bytes; }
  void u16(std::uint16_t v) {
    out_ += char(v & 0xFF);
    out_ += char(v >> 8);
  }
  void u32(std::uint32_t v) {
    for (int i = 0; i < 4; ++i) out_ += char((v >> (8 * i)) & 0xFF);
  }
  const std::string& bytes() const { return out_; }

 private:
  bool explicit_;
  std::string out_;
};

// PackBits (PS3.5 G.3.1), a row at a time: runs of 3 to 128 equal bytes
// replicated, the rest given as they are, 128 bytes at most a run.
inline std::string packbits(const std::vector<unsigned char>& bytes, std::size_t row) {
  std::string out;
  for (std::size_t start = 0; start < bytes.size(); start += row) {
    const std::size_t end = std::min(bytes.size(), start + row);
    std::size_t i = start;
    std::string literal;
    const auto flush = [&] {
      if (literal.empty()) return;
      out += char(literal.size() - 1);
      out += literal;
      literal.clear();
    };
    while (i < end) {
      std::size_t run = 1;
      while (i + run < end && run < 128 && bytes[i + run] == bytes[i]) ++run;
      if (run >= 3) {
        flush();
        out += char(static_cast<signed char>(1 - static_cast<int>(run)));
        out += char(bytes[i]);
        i += run;
      } else {
        literal += char(bytes[i++]);
        if (literal.size() == 128) flush();
      }
    }
    flush();
  }
  return out;
}

// A frame as RLE lossless (PS3.5 annex G): the header, then a segment per
// byte of each sample, the most significant first.
inline std::string rle_frame(const cv::Mat& frame) {
  cv::Mat m;
  if (frame.channels() == 3) {
    cv::cvtColor(frame, m, cv::COLOR_BGR2RGB);
  } else {
    m = frame;
  }
  std::vector<cv::Mat> samples;
  cv::split(m, samples);
  const int bytes_per_sample = static_cast<int>(m.elemSize1());
  std::vector<std::string> segments;
  for (const cv::Mat& c : samples) {
    for (int b = bytes_per_sample - 1; b >= 0; --b) {
      std::vector<unsigned char> lane;
      for (int y = 0; y < c.rows; ++y) {
        for (int x = 0; x < c.cols; ++x) {
          const unsigned v = c.depth() == CV_16U ? c.at<std::uint16_t>(y, x) : c.at<std::uint8_t>(y, x);
          lane.push_back(static_cast<unsigned char>((v >> (8 * b)) & 0xFF));
        }
      }
      std::string seg = packbits(lane, static_cast<std::size_t>(c.cols));
      if (seg.size() % 2) seg += '\x80';  // a no-op as padding
      segments.push_back(seg);
    }
  }
  std::string header;
  const auto u32 = [&](std::uint32_t v) {
    for (int i = 0; i < 4; ++i) header += char((v >> (8 * i)) & 0xFF);
  };
  u32(static_cast<std::uint32_t>(segments.size()));
  std::uint32_t at = 64;
  for (std::size_t i = 0; i < 15; ++i) {
    u32(i < segments.size() ? at : 0);
    if (i < segments.size()) at += static_cast<std::uint32_t>(segments[i].size());
  }
  for (const std::string& seg : segments) header += seg;
  return header;
}

// Writes `frames` (all of one size and type: 8 or 16 bits, grey or BGR).
inline void write_dicom(const std::filesystem::path& file, const std::vector<cv::Mat>& frames,
                        const DicomWriteOptions& o = {}) {
  const cv::Mat& first = frames.at(0);
  const bool colour = first.channels() == 3;
  const bool explicit_vr = o.transfer_syntax != "1.2.840.10008.1.2";
  std::string out;
  if (o.preamble) {
    DicomWriter meta(true);
    meta.element(0x0002, 0x0001, "OB", std::string("\0\1", 2));
    meta.element(0x0002, 0x0002, "UI", "1.2.840.10008.5.1.4.1.1.3.1");
    meta.element(0x0002, 0x0003, "UI", "1.2.3.4.5.6");
    meta.element(0x0002, 0x0010, "UI", o.transfer_syntax);
    DicomWriter group(true);
    group.header(0x0002, 0x0000, "UL", 4);
    group.u32(static_cast<std::uint32_t>(meta.bytes().size()));
    out = std::string(128, '\0') + "DICM" + group.bytes() + meta.bytes();
  }
  DicomWriter d(explicit_vr);
  d.element(0x0008, 0x0060, "CS", "US");
  if (o.sequence_before) {
    // A sequence of undefined length holding an item of undefined length.
    d.header(0x0018, 0x6011, "SQ", 0xFFFFFFFFu);
    d.header(0xFFFE, 0xE000, "", 0xFFFFFFFFu);
    d.us(0x0018, 0x6024, 3);
    d.header(0xFFFE, 0xE00D, "", 0);
    d.header(0xFFFE, 0xE0DD, "", 0);
  }
  if (o.region_cm_x > 0) {
    // The sequence of ultrasound regions, of defined length: one region.
    DicomWriter item(explicit_vr);
    item.us(0x0018, 0x6024, 3);  // cm
    for (const auto& [elem, v] : {std::pair<std::uint16_t, double>{0x602C, o.region_cm_x}, {0x602E, o.region_cm_y}}) {
      item.header(0x0018, elem, "FD", 8);
      std::uint64_t bits = 0;
      std::memcpy(&bits, &v, 8);
      for (int i = 0; i < 8; ++i) item.raw(std::string(1, char((bits >> (8 * i)) & 0xFF)));
    }
    d.header(0x0018, 0x6011, "SQ", static_cast<std::uint32_t>(item.bytes().size() + 8));
    d.header(0xFFFE, 0xE000, "", static_cast<std::uint32_t>(item.bytes().size()));
    d.raw(item.bytes());
  }
  if (o.frame_time_ms > 0) d.element(0x0018, 0x1063, "DS", std::to_string(o.frame_time_ms));
  if (!o.pixel_spacing.empty()) d.element(0x0028, 0x0030, "DS", o.pixel_spacing);
  if (!o.frame_time_vector.empty()) d.element(0x0018, 0x1065, "DS", o.frame_time_vector);
  d.us(0x0028, 0x0002, colour ? 3 : 1);
  d.element(0x0028, 0x0004, "CS", o.photometric.empty() ? (colour ? "RGB" : "MONOCHROME2") : o.photometric);
  if (colour) d.us(0x0028, 0x0006, static_cast<std::uint16_t>(o.planar));
  d.element(0x0028, 0x0008, "IS", std::to_string(frames.size()));
  d.us(0x0028, 0x0010, static_cast<std::uint16_t>(first.rows));
  d.us(0x0028, 0x0011, static_cast<std::uint16_t>(first.cols));
  const int bits = first.depth() == CV_16U ? 16 : 8;
  d.us(0x0028, 0x0100, static_cast<std::uint16_t>(bits));
  d.us(0x0028, 0x0101, static_cast<std::uint16_t>(o.bits_stored > 0 ? o.bits_stored : bits));
  d.us(0x0028, 0x0102,
       static_cast<std::uint16_t>(o.high_bit >= 0 ? o.high_bit : (o.bits_stored > 0 ? o.bits_stored : bits) - 1));
  d.us(0x0028, 0x0103, 0);
  if (o.compress_as.empty() && o.video.empty() && o.encoded.empty()) {
    std::string pixels;
    for (const cv::Mat& f : frames) {
      if (colour && o.photometric == "YBR_FULL_422") {
        // Two pixels in four bytes: Y0, Y1, and the pair's first Cb and Cr.
        cv::Mat ycc;
        cv::cvtColor(f, ycc, cv::COLOR_BGR2YCrCb);
        for (int y = 0; y < ycc.rows; ++y) {
          for (int x = 0; x + 1 < ycc.cols; x += 2) {
            const cv::Vec3b a = ycc.at<cv::Vec3b>(y, x), b = ycc.at<cv::Vec3b>(y, x + 1);
            pixels += {char(a[0]), char(b[0]), char(a[2]), char(a[1])};
          }
        }
        continue;
      }
      cv::Mat m;  // a new buffer: the caller's frame stays as it was
      if (colour) {
        cv::cvtColor(f, m, cv::COLOR_BGR2RGB);
      } else {
        m = f;
      }
      if (colour && o.planar == 1) {
        std::vector<cv::Mat> planes;
        cv::split(m, planes);
        for (const cv::Mat& p : planes) pixels.append(reinterpret_cast<const char*>(p.data), p.total() * p.elemSize());
      } else {
        pixels.append(reinterpret_cast<const char*>(m.data), m.total() * m.elemSize());
      }
    }
    if (pixels.size() % 2) pixels += '\0';
    d.header(0x7FE0, 0x0010, bits == 16 ? "OW" : "OB", static_cast<std::uint32_t>(pixels.size()));
    d.raw(pixels);
  } else {
    std::vector<std::vector<std::string>> parts;
    if (!o.video.empty()) {
      std::string s = o.video;
      if (s.size() % 2) s += '\0';
      std::vector<std::string> pieces;
      const std::size_t step = (s.size() / o.fragments_per_frame + 1) & ~std::size_t(1);
      for (std::size_t at = 0; at < s.size(); at += step) pieces.push_back(s.substr(at, step));
      parts.push_back(pieces);
    }
    for (std::size_t k = 0; k < frames.size() && o.video.empty(); ++k) {
      const cv::Mat& f = frames[k];
      std::vector<unsigned char> encoded;
      if (k < o.encoded.size()) {
        encoded.assign(o.encoded[k].begin(), o.encoded[k].end());
      } else if (o.compress_as == ".rle") {
        const std::string rle = rle_frame(f);
        encoded.assign(rle.begin(), rle.end());
      } else {
        cv::imencode(o.compress_as, f, encoded);
      }
      if (o.strip_jfif && encoded.size() > 6 && encoded[2] == 0xFF && encoded[3] == 0xE0) {
        const std::size_t app0 = 2 + 2 + ((std::size_t(encoded[4]) << 8) | encoded[5]);
        encoded.erase(encoded.begin() + 2, encoded.begin() + static_cast<std::ptrdiff_t>(app0));
      }
      std::string s(encoded.begin(), encoded.end());
      if (s.size() % 2) s += '\0';
      std::vector<std::string> pieces;
      const std::size_t step = (s.size() / o.fragments_per_frame + 1) & ~std::size_t(1);
      for (std::size_t at = 0; at < s.size(); at += step) pieces.push_back(s.substr(at, step));
      parts.push_back(pieces);
    }
    d.header(0x7FE0, 0x0010, "OB", 0xFFFFFFFFu);
    std::string table;
    std::uint32_t offset = 0;
    for (const auto& pieces : parts) {
      for (int i = 0; i < 4; ++i) table += char((offset >> (8 * i)) & 0xFF);
      for (const auto& p : pieces) offset += 8 + static_cast<std::uint32_t>(p.size());
    }
    if (!o.offset_table) table.clear();
    d.header(0xFFFE, 0xE000, "", static_cast<std::uint32_t>(table.size()));
    d.raw(table);
    for (const auto& pieces : parts) {
      for (const auto& p : pieces) {
        d.header(0xFFFE, 0xE000, "", static_cast<std::uint32_t>(p.size()));
        d.raw(p);
      }
    }
    d.header(0xFFFE, 0xE0DD, "", 0);
  }
  std::ofstream(file, std::ios::binary) << out << d.bytes();
}

}  // namespace gtrack::testing
