// Reading a DICOM file's image layout (see dicom.hpp). The parts of the
// standard (PS3.5) it follows: the file meta group in explicit VR little
// endian; the dataset in explicit or implicit VR little endian; sequences
// and items of defined or undefined length (skipped, nested up to 32
// deep); native pixel data of defined length, or encapsulated pixel data
// as items after a basic offset table.
#include "dicom.hpp"

#include <algorithm>
#include <array>
#include <cctype>
#include <charconv>
#include <cstring>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <optional>

#include <fmt/format.h>

#include "gtrack/error.hpp"

namespace gtrack::detail {

namespace fs = std::filesystem;

namespace {

constexpr std::uint32_t kUndefined = 0xFFFFFFFFu;
constexpr int kMaxDepth = 32;

constexpr std::uint32_t tag(std::uint16_t group, std::uint16_t element) {
  return (std::uint32_t(group) << 16) | element;
}
constexpr std::uint32_t kItem = tag(0xFFFE, 0xE000);
constexpr std::uint32_t kItemEnd = tag(0xFFFE, 0xE00D);
constexpr std::uint32_t kSequenceEnd = tag(0xFFFE, 0xE0DD);
constexpr std::uint32_t kPixelData = tag(0x7FE0, 0x0010);

const char* const kExplicitLittle = "1.2.840.10008.1.2.1";
const char* const kImplicitLittle = "1.2.840.10008.1.2";
const char* const kRleLossless = "1.2.840.10008.1.2.5";

struct Header {
  std::uint32_t tag = 0;
  std::array<char, 2> vr{};  // '\0' for implicit VR and for items
  std::uint32_t length = 0;
  std::uint64_t value_at = 0;  // the value's offset in the file
};

std::string trimmed(std::string s) {
  while (!s.empty() && (s.back() == ' ' || s.back() == '\0')) s.pop_back();
  std::size_t i = 0;
  while (i < s.size() && s[i] == ' ') ++i;
  return s.substr(i);
}

class Reader {
 public:
  Reader(std::istream& in, std::string name) : in_(in), name_(std::move(name)) {
    in_.seekg(0, std::ios::end);
    const auto end = in_.tellg();
    size_ = end > 0 ? static_cast<std::uint64_t>(end) : 0;
    in_.clear();
    in_.seekg(0);
  }

  std::uint64_t size() const { return size_; }
  std::uint64_t at() const { return at_; }
  bool at_end() const { return at_ >= size_; }

  void seek(std::uint64_t to) {
    if (to > size_) fail(at_, "a value that ends at byte " + std::to_string(to) + ", past the file's end");
    at_ = to;
  }

  void read(void* out, std::uint64_t n) {
    if (n > size_ - std::min(at_, size_)) fail(at_, std::to_string(n) + " more bytes, the file ends first");
    in_.clear();
    in_.seekg(static_cast<std::streamoff>(at_));
    in_.read(static_cast<char*>(out), static_cast<std::streamsize>(n));
    if (!in_) fail(at_, std::to_string(n) + " bytes that could not be read");
    at_ += n;
  }

  std::uint16_t u16() {
    unsigned char b[2];
    read(b, 2);
    return static_cast<std::uint16_t>(b[0] | (b[1] << 8));
  }
  std::uint32_t u32() {
    unsigned char b[4];
    read(b, 4);
    return std::uint32_t(b[0]) | (std::uint32_t(b[1]) << 8) | (std::uint32_t(b[2]) << 16) | (std::uint32_t(b[3]) << 24);
  }

  // The next element's header. Items and delimiters have no VR in either
  // encoding.
  Header header(bool explicit_vr) {
    Header h;
    const std::uint64_t start = at_;
    const std::uint16_t group = u16();
    h.tag = tag(group, u16());
    if (group == 0xFFFE) {
      h.length = u32();
    } else if (explicit_vr) {
      read(h.vr.data(), 2);
      if (!std::isupper(static_cast<unsigned char>(h.vr[0])) || !std::isupper(static_cast<unsigned char>(h.vr[1]))) {
        fail(start + 4, fmt::format("a value representation (two capital letters) for tag ({:04X},{:04X})", group,
                                    h.tag & 0xFFFF));
      }
      static const std::array<const char*, 13> kLong = {"OB", "OD", "OF", "OL", "OV", "OW", "SQ",
                                                       "SV", "UC", "UN", "UR", "UT", "UV"};
      const bool long_length = std::any_of(kLong.begin(), kLong.end(), [&](const char* v) {
        return v[0] == h.vr[0] && v[1] == h.vr[1];
      });
      if (long_length) {
        u16();  // reserved
        h.length = u32();
      } else {
        h.length = u16();
      }
    } else {
      h.length = u32();
    }
    h.value_at = at_;
    // (Pixel data and fragments may run past a file cut short: said by the
    // layout, which reads the whole frames.)
    if (h.length != kUndefined && h.length > size_ - at_ && h.tag != kPixelData && group != 0xFFFE) {
      fail(start, fmt::format("tag ({:04X},{:04X}) to hold {} bytes; the file has {} after it", h.tag >> 16,
                              h.tag & 0xFFFF, h.length, size_ - at_));
    }
    return h;
  }

  std::string text(const Header& h, std::uint32_t limit = 4096) {
    if (h.length == kUndefined || h.length > limit) {
      fail_value(h, "a text value of at most " + std::to_string(limit) + " bytes");
    }
    std::string s(h.length, '\0');
    read(s.data(), h.length);
    return trimmed(s);
  }

  // An unsigned short (US) value.
  int us(const Header& h) {
    if (h.length != 2) fail_value(h, "a 2-byte value");
    return u16();
  }

  // An 8-byte double (FD).
  double fd(const Header& h) {
    if (h.length != 8) fail_value(h, "an 8-byte value");
    unsigned char b[8];
    read(b, 8);
    std::uint64_t bits = 0;
    for (int i = 7; i >= 0; --i) bits = (bits << 8) | b[i];
    double v = 0;
    std::memcpy(&v, &bits, sizeof v);
    return v;
  }

  // The values of a decimal or integer string (DS, IS), '\\' apart; a value
  // that is no number is NaN.
  std::vector<double> decimals(const Header& h, std::uint32_t limit = 4096) {
    const std::string s = text(h, limit);
    std::vector<double> out;
    std::size_t at = 0;
    for (;;) {
      const std::size_t end = std::min(s.find('\\', at), s.size());
      std::string v = trimmed(s.substr(at, end - at));
      if (!v.empty() && v.front() == '+') v.erase(0, 1);
      double x = std::numeric_limits<double>::quiet_NaN();
      const auto [stop, ec] = std::from_chars(v.data(), v.data() + v.size(), x);
      if (v.empty() || ec != std::errc() || stop != v.data() + v.size() || !std::isfinite(x)) {
        x = std::numeric_limits<double>::quiet_NaN();
      }
      out.push_back(x);
      if (end >= s.size()) return out;
      at = end + 1;
    }
  }
  std::optional<double> decimal(const Header& h) {
    const double v = decimals(h).front();
    return std::isnan(v) ? std::nullopt : std::optional<double>(v);
  }

  // Past a sequence of undefined length (its header just read): items
  // until the sequence's end. `explicit_vr`: the encoding inside (a
  // sequence of VR UN holds implicit VR).
  void skip_sequence(bool explicit_vr, int depth) {
    if (depth > kMaxDepth) fail(at_, "sequences nested at most " + std::to_string(kMaxDepth) + " deep");
    for (;;) {
      const Header h = header(explicit_vr);
      if (h.tag == kSequenceEnd) return;
      if (h.tag != kItem) {
        fail(h.value_at - 8, fmt::format("an item (FFFE,E000) or the sequence's end (FFFE,E0DD), got ({:04X},{:04X})",
                                         h.tag >> 16, h.tag & 0xFFFF));
      }
      if (h.length != kUndefined) {
        seek(h.value_at + h.length);
        continue;
      }
      // An item of undefined length: elements until the item's end.
      for (;;) {
        const Header e = header(explicit_vr);
        if (e.tag == kItemEnd) break;
        skip_value(e, explicit_vr, depth + 1);
      }
    }
  }

  void skip_value(const Header& h, bool explicit_vr, int depth) {
    if (h.length != kUndefined) {
      seek(h.value_at + h.length);
      return;
    }
    const bool un = h.vr[0] == 'U' && h.vr[1] == 'N';
    skip_sequence(explicit_vr && !un, depth);
  }

  // The items of a sequence (its header just read), each element handed to
  // `on` (which reads or skips its value), at this level only.
  template <class F>
  void items(const Header& sequence, bool explicit_vr, F&& on) {
    const std::uint64_t end = sequence.length == kUndefined ? size_ : sequence.value_at + sequence.length;
    int item = 0;
    while (at_ < end) {
      const Header h = header(explicit_vr);
      if (h.tag == kSequenceEnd) return;
      if (h.tag != kItem) fail(h.value_at - 8, "an item (FFFE,E000) of the sequence");
      const std::uint64_t item_end = h.length == kUndefined ? size_ : h.value_at + h.length;
      while (at_ < item_end) {
        const Header e = header(explicit_vr);
        if (e.tag == kItemEnd) break;
        on(item, e);
      }
      ++item;
    }
  }

  [[noreturn]] void fail(std::uint64_t offset, const std::string& expected) const {
    throw InputError(fmt::format("{}: byte {}: expected {} (not a DICOM file, or one cut short)", name_, offset,
                                 expected));
  }
  // Pixel data not laid out as the transfer syntax says.
  [[noreturn]] void fail_pixels(std::uint64_t offset, const std::string& expected) const {
    throw InputError(fmt::format("{}: byte {}: expected {} (the pixel data is not as its transfer syntax, {}, says)",
                                 name_, offset, expected, transfer_syntax_name(transfer_syntax)));
  }
  std::string transfer_syntax;  // for fail_pixels
  // A value of the wrong form in a file that reads as DICOM.
  [[noreturn]] void fail_value(const Header& h, const std::string& expected) const {
    throw InputError(fmt::format("{}: byte {}: expected {} for tag ({:04X},{:04X})", name_, h.value_at, expected,
                                 h.tag >> 16, h.tag & 0xFFFF));
  }

 private:
  std::istream& in_;
  std::string name_;
  std::uint64_t size_ = 0;
  std::uint64_t at_ = 0;
};

// A video transfer syntax's fragmentable form (1.2.840.10008.1.2.4.100.1
// to .108.1) as the syntax it is a form of; any other UID as it is.
std::string unfragmented(const std::string& uid) {
  const bool fragmentable = uid.rfind("1.2.840.10008.1.2.4.10", 0) == 0 && uid.size() > 2 &&
                            uid.compare(uid.size() - 2, 2, ".1") == 0;
  return fragmentable ? uid.substr(0, uid.size() - 2) : uid;
}

}  // namespace

std::string transfer_syntax_name(const std::string& uid) {
  static const std::array<std::pair<const char*, const char*>, 25> kNames = {{
      {"1.2.840.10008.1.2", "implicit VR little endian"},
      {"1.2.840.10008.1.2.1", "explicit VR little endian"},
      {"1.2.840.10008.1.2.1.99", "deflated explicit VR little endian"},
      {"1.2.840.10008.1.2.2", "explicit VR big endian"},
      {"1.2.840.10008.1.2.4.50", "JPEG baseline"},
      {"1.2.840.10008.1.2.4.51", "JPEG extended"},
      {"1.2.840.10008.1.2.4.57", "JPEG lossless"},
      {"1.2.840.10008.1.2.4.70", "JPEG lossless, first-order prediction"},
      {"1.2.840.10008.1.2.4.80", "JPEG-LS lossless"},
      {"1.2.840.10008.1.2.4.81", "JPEG-LS near-lossless"},
      {"1.2.840.10008.1.2.4.90", "JPEG 2000 lossless"},
      {"1.2.840.10008.1.2.4.91", "JPEG 2000"},
      {"1.2.840.10008.1.2.4.100", "MPEG-2 video"},
      {"1.2.840.10008.1.2.4.101", "MPEG-2 video, high level"},
      {"1.2.840.10008.1.2.4.102", "MPEG-4 AVC/H.264 video"},
      {"1.2.840.10008.1.2.4.103", "MPEG-4 AVC/H.264 video, BD-compatible"},
      {"1.2.840.10008.1.2.4.104", "MPEG-4 AVC/H.264 video, 2D"},
      {"1.2.840.10008.1.2.4.105", "MPEG-4 AVC/H.264 video, 3D"},
      {"1.2.840.10008.1.2.4.106", "MPEG-4 AVC/H.264 video, stereo"},
      {"1.2.840.10008.1.2.4.107", "HEVC/H.265 video"},
      {"1.2.840.10008.1.2.4.108", "HEVC/H.265 video, main 10"},
      {"1.2.840.10008.1.2.4.201", "high-throughput JPEG 2000 lossless"},
      {"1.2.840.10008.1.2.4.202", "high-throughput JPEG 2000, RPCL lossless"},
      {"1.2.840.10008.1.2.4.203", "high-throughput JPEG 2000"},
      {"1.2.840.10008.1.2.5", "RLE lossless"},
  }};
  const std::string base = unfragmented(uid);
  for (const auto& [u, n] : kNames) {
    if (base == u) return (base == uid ? "" : "fragmentable ") + std::string(n) + " (" + uid + ")";
  }
  return "transfer syntax " + uid;
}

bool has_dicom_extension(const std::string& path) {
  std::string ext = fs::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  return ext == ".dcm" || ext == ".dicom";
}

bool is_dicom_file(const std::string& spec) {
  std::error_code ec;
  if (!fs::is_regular_file(spec, ec)) return false;
  const fs::path p(spec);
  if (p.filename() == "DICOMDIR") return false;  // an index of other files
  if (has_dicom_extension(spec)) return true;
  std::ifstream in(spec, std::ios::binary);
  char magic[132] = {};
  return in.read(magic, sizeof magic) && std::string_view(magic + 128, 4) == "DICM";
}

std::vector<std::pair<std::uint64_t, std::uint64_t>> DicomLayout::frame_spans(int k) const {
  if (k < 0 || k >= frames) return {};
  if (!encapsulated) return {{pixels_at + frame_size * static_cast<std::uint64_t>(k), frame_size}};
  if (video) return k == 0 ? fragments : decltype(fragments){};
  const std::size_t a = first_fragment.at(static_cast<std::size_t>(k));
  const std::size_t b =
      static_cast<std::size_t>(k) + 1 < first_fragment.size() ? first_fragment[static_cast<std::size_t>(k) + 1]
                                                              : fragments.size();
  return {fragments.begin() + static_cast<std::ptrdiff_t>(a), fragments.begin() + static_cast<std::ptrdiff_t>(b)};
}

std::vector<unsigned char> decode_rle_frame(const std::vector<unsigned char>& data, const DicomLayout& layout,
                                            const std::string& what) {
  // PS3.5 annex G: a 64-byte header (the segment count, then 15 offsets
  // from the frame's start), then each segment, a PackBits stream of one
  // byte of one sample for every pixel: the most significant byte first,
  // sample after sample.
  const auto u32 = [&](std::size_t at) {
    return std::uint32_t(data[at]) | (std::uint32_t(data[at + 1]) << 8) | (std::uint32_t(data[at + 2]) << 16) |
           (std::uint32_t(data[at + 3]) << 24);
  };
  const int bytes_per_sample = layout.bits_allocated / 8;
  const std::uint32_t segments = static_cast<std::uint32_t>(layout.samples * bytes_per_sample);
  if (data.size() < 64) {
    throw InputError(fmt::format("{}: its RLE data holds {} bytes; expected a 64-byte header and its segments", what,
                                 data.size()));
  }
  if (u32(0) != segments) {
    throw InputError(fmt::format("{}: its RLE header gives {} segments; expected {} ({} sample(s) of {} bits)", what,
                                 u32(0), segments, layout.samples, layout.bits_allocated));
  }
  const std::uint64_t pixels = std::uint64_t(layout.rows) * std::uint64_t(layout.columns);
  // A run of 128 bytes takes 2: no frame decodes to more than 64 times its
  // size (checked before the frame is made).
  if (pixels * segments > 64 * std::uint64_t(data.size())) {
    throw InputError(fmt::format("{}: its RLE data holds {} bytes, which decode to at most {}; expected {} ({}x{} "
                                 "pixels, {} segment(s))",
                                 what, data.size(), 64 * std::uint64_t(data.size()), pixels * segments,
                                 layout.columns, layout.rows, segments));
  }
  std::vector<unsigned char> out(pixels * segments);
  for (std::uint32_t s = 0; s < segments; ++s) {
    const std::uint64_t begin = u32(4 + 4 * s);
    const std::uint64_t end = s + 1 < segments ? u32(8 + 4 * s) : data.size();
    if (begin < 64 || end < begin || end > data.size()) {
      throw InputError(fmt::format("{}: its RLE segment {} runs from byte {} to {} of {}; expected it after the "
                                   "64-byte header, before the next segment, within the data",
                                   what, s + 1, begin, end, data.size()));
    }
    // Sample c's byte b (0: the most significant) of each pixel; native
    // order is little endian, each sample's plane after the other.
    const std::uint32_t c = s / static_cast<std::uint32_t>(bytes_per_sample);
    const std::uint32_t b = s % static_cast<std::uint32_t>(bytes_per_sample);
    unsigned char* plane = out.data() + c * pixels * static_cast<std::uint64_t>(bytes_per_sample);
    const std::uint64_t step = static_cast<std::uint64_t>(bytes_per_sample);
    const std::uint64_t lane = static_cast<std::uint64_t>(bytes_per_sample) - 1 - b;
    std::uint64_t n = 0;  // pixels decoded
    std::uint64_t at = begin;
    while (n < pixels && at < end) {
      const int control = static_cast<signed char>(data[at++]);
      if (control >= 0) {
        // control + 1 bytes as they are.
        const std::uint64_t count = std::min<std::uint64_t>({std::uint64_t(control) + 1, end - at, pixels - n});
        for (std::uint64_t i = 0; i < count; ++i) plane[(n + i) * step + lane] = data[at + i];
        n += count;
        at += std::uint64_t(control) + 1;
      } else if (control != -128 && at < end) {
        // The next byte, 1 - control times.
        const std::uint64_t count = std::min<std::uint64_t>(std::uint64_t(1 - control), pixels - n);
        for (std::uint64_t i = 0; i < count; ++i) plane[(n + i) * step + lane] = data[at];
        n += count;
        ++at;
      }
    }
    if (n < pixels) {
      throw InputError(fmt::format("{}: its RLE segment {} decodes to {} bytes; expected {} ({}x{} pixels)", what,
                                   s + 1, n, pixels, layout.columns, layout.rows));
    }
  }
  return out;
}

std::vector<unsigned char> jpeg_marked_rgb(std::vector<unsigned char> stream) {
  if (stream.size() < 4 || stream[0] != 0xFF || stream[1] != 0xD8) return stream;
  // The markers up to the frame header: JFIF (APP0) or Adobe (APP14) say
  // how the decoder takes three components; without them, the ids do.
  std::size_t at = 2;
  while (at + 4 <= stream.size() && stream[at] == 0xFF) {
    const unsigned char m = stream[at + 1];
    const std::size_t length = (std::size_t(stream[at + 2]) << 8) | stream[at + 3];
    if (m == 0xE0 && at + 9 <= stream.size() && std::equal(stream.begin() + at + 4, stream.begin() + at + 9, "JFIF")) {
      return stream;
    }
    if (m == 0xEE && at + 9 <= stream.size() && std::equal(stream.begin() + at + 4, stream.begin() + at + 9, "Adobe")) {
      return stream;
    }
    const bool frame_header = m >= 0xC0 && m <= 0xCF && m != 0xC4 && m != 0xC8 && m != 0xCC;
    if (frame_header) {
      // Components: count at +9, then (id, sampling, table) triples.
      if (at + 10 > stream.size() || stream[at + 9] != 3 || at + 10 + 9 > stream.size()) return stream;
      const unsigned char* ids = stream.data() + at + 10;
      if (ids[0] == 'R' && ids[3] == 'G' && ids[6] == 'B') return stream;
      break;
    }
    if (m == 0xDA || length < 2) return stream;  // scan data before a frame header: not ours to mend
    at += 2 + length;
  }
  // Adobe APP14, transform 0 (RGB), after SOI.
  static const unsigned char kAdobe[] = {0xFF, 0xEE, 0x00, 0x0E, 'A', 'd', 'o', 'b', 'e',
                                         0x00, 0x64, 0x00, 0x00, 0x00, 0x00, 0x00};
  stream.insert(stream.begin() + 2, std::begin(kAdobe), std::end(kAdobe));
  return stream;
}

DicomLayout read_dicom_layout(std::istream& in, const std::string& name) {
  Reader r(in, name);
  DicomLayout out;
  out.transfer_syntax = kImplicitLittle;  // a bare dataset, without the file meta group
  char magic[132] = {};
  bool bare = true;
  if (r.size() >= sizeof magic) {
    r.read(magic, sizeof magic);
    if (std::string_view(magic + 128, 4) == "DICM") {
      bare = false;
      // The file meta group: explicit VR little endian, group 0002 only.
      for (;;) {
        const std::uint64_t start = r.at();
        if (r.at_end()) r.fail(start, "the dataset after the file meta group");
        const std::uint16_t group = r.u16();
        r.seek(start);
        if (group != 0x0002) break;
        const Header h = r.header(true);
        if (h.tag == tag(0x0002, 0x0010)) {
          out.transfer_syntax = r.text(h);
        } else {
          r.skip_value(h, true, 1);
        }
      }
    }
  }
  if (bare) {
    // A bare dataset: explicit VR when its first element has one.
    r.seek(0);
    if (r.size() >= 6) {
      char head[6];
      r.read(head, 6);
      if (std::isupper(static_cast<unsigned char>(head[4])) && std::isupper(static_cast<unsigned char>(head[5]))) {
        out.transfer_syntax = kExplicitLittle;
      }
      r.seek(0);
    }
  }
  const std::string& ts = out.transfer_syntax;
  const bool explicit_vr = ts != kImplicitLittle;
  const bool native = ts == kImplicitLittle || ts == kExplicitLittle;
  static const std::array<const char*, 5> kCompressed = {"1.2.840.10008.1.2.4.50", "1.2.840.10008.1.2.4.51",
                                                         "1.2.840.10008.1.2.4.90", "1.2.840.10008.1.2.4.91",
                                                         kRleLossless};
  // MPEG-2, H.264 and HEVC (1.2.840.10008.1.2.4.100 to .108): the pixel
  // data is one video stream, handed to the video decoder whole.
  static const std::array<const char*, 9> kVideo = {
      "1.2.840.10008.1.2.4.100", "1.2.840.10008.1.2.4.101", "1.2.840.10008.1.2.4.102",
      "1.2.840.10008.1.2.4.103", "1.2.840.10008.1.2.4.104", "1.2.840.10008.1.2.4.105",
      "1.2.840.10008.1.2.4.106", "1.2.840.10008.1.2.4.107", "1.2.840.10008.1.2.4.108"};
  const bool video = std::find(kVideo.begin(), kVideo.end(), unfragmented(ts)) != kVideo.end();
  if (!native && !video && std::find(kCompressed.begin(), kCompressed.end(), ts) == kCompressed.end()) {
    throw DicomRefusal(name + ": its pixels are stored as " + transfer_syntax_name(ts) +
                     "; expected native pixels (explicit or implicit VR little endian), JPEG (baseline or extended), "
                     "JPEG 2000, RLE lossless, MPEG-2, H.264 or HEVC (convert it, e.g. gdcmconv --raw in.dcm "
                     "out.dcm)");
  }
  out.encapsulated = !native;
  out.rle = ts == kRleLossless;
  out.video = video;
  r.transfer_syntax = ts;

  double frame_time_ms = 0, cine_rate = 0, display_rate = 0;
  // Pixel Spacing, else Imager Pixel Spacing: row spacing (y), then column
  // spacing (x), in mm; taken when no ultrasound region gives the size.
  std::vector<double> pixel_spacing, imager_spacing;
  std::vector<double> frame_time_vector;
  std::vector<std::uint64_t> extended_offsets;
  std::optional<Header> pixels;
  while (!r.at_end()) {
    const Header h = r.header(explicit_vr);
    if (h.tag == kPixelData) {
      pixels = h;
      break;
    }
    switch (h.tag) {
      case tag(0x0028, 0x0010): out.rows = r.us(h); break;
      case tag(0x0028, 0x0011): out.columns = r.us(h); break;
      case tag(0x0028, 0x0002): out.samples = r.us(h); break;
      case tag(0x0028, 0x0100): out.bits_allocated = r.us(h); break;
      case tag(0x0028, 0x0101): out.bits_stored = r.us(h); break;
      case tag(0x0028, 0x0102): out.high_bit = r.us(h); break;
      case tag(0x0028, 0x0103): {
        if (r.us(h) != 0) {
          throw DicomRefusal(name + ": signed samples (0028,0103 PixelRepresentation 1); expected unsigned ones, as "
                                  "B-mode images are");
        }
        break;
      }
      case tag(0x0028, 0x0006): out.planar = r.us(h); break;
      case tag(0x0028, 0x0004): out.photometric = r.text(h); break;
      case tag(0x0028, 0x0008): {
        const double n = r.decimal(h).value_or(-1);
        if (!(n >= 1 && n <= 1e6 && n == std::floor(n))) r.fail_value(h, "a number of frames from 1 to 10^6");
        out.frames = static_cast<int>(n);
        break;
      }
      case tag(0x0018, 0x1063): frame_time_ms = r.decimal(h).value_or(0); break;
      case tag(0x0018, 0x1065): frame_time_vector = r.decimals(h, 1u << 24); break;
      case tag(0x0018, 0x0040): cine_rate = r.decimal(h).value_or(0); break;
      case tag(0x0028, 0x0030): pixel_spacing = r.decimals(h); break;
      case tag(0x0018, 0x1164): imager_spacing = r.decimals(h); break;
      case tag(0x0008, 0x2144): display_rate = r.decimal(h).value_or(0); break;
      case tag(0x7FE0, 0x0001): {
        // Extended offset table: 8-byte offsets, one per frame.
        if (h.length == kUndefined || h.length % 8 != 0 || h.length > (8u << 20)) {
          r.fail_value(h, "8-byte offsets, at most 2^20");
        }
        for (std::uint32_t i = 0; i < h.length; i += 8) {
          const std::uint64_t lo = r.u32();
          extended_offsets.push_back(lo | (std::uint64_t(r.u32()) << 32));
        }
        break;
      }
      case tag(0x0018, 0x6011): {
        // Sequence of ultrasound regions: the first 2D one's pixel size, in
        // cm on both axes.
        const bool un = h.vr[0] == 'U' && h.vr[1] == 'N';  // a sequence of VR UN holds implicit VR
        struct Region {
          int format = -1, units_x = 0, units_y = 0;
          double dx = 0, dy = 0;
        };
        std::vector<Region> regions;
        r.items(h, explicit_vr && !un, [&](int item, const Header& e) {
          if (static_cast<int>(regions.size()) <= item) regions.resize(static_cast<std::size_t>(item) + 1);
          Region& g = regions[static_cast<std::size_t>(item)];
          switch (e.tag) {
            case tag(0x0018, 0x6012): g.format = r.us(e); break;
            case tag(0x0018, 0x6024): g.units_x = r.us(e); break;
            case tag(0x0018, 0x6026): g.units_y = r.us(e); break;
            case tag(0x0018, 0x602C): g.dx = r.fd(e); break;
            case tag(0x0018, 0x602E): g.dy = r.fd(e); break;
            default: r.skip_value(e, explicit_vr && !un, 2);
          }
        });
        for (const Region& g : regions) {
          // Format 1: 2D (tissue); absent: taken as 2D. Units 3: cm.
          const bool spatial = (g.format == 1 || g.format == -1) && g.units_x == 3 && (g.units_y == 3 || g.units_y == 0);
          if (spatial && g.dx > 0 && g.dy > 0 && std::isfinite(g.dx) && std::isfinite(g.dy)) {
            out.pixel_mm = std::make_pair(10 * g.dx, 10 * g.dy);
            break;
          }
        }
        break;
      }
      default: r.skip_value(h, explicit_vr, 1);
    }
  }
  if (!out.pixel_mm) {
    for (const auto& spacing : {pixel_spacing, imager_spacing}) {
      if (spacing.size() == 2 && spacing[0] > 0 && spacing[1] > 0 && std::isfinite(spacing[0]) &&
          std::isfinite(spacing[1])) {
        out.pixel_mm = std::make_pair(spacing[1], spacing[0]);
        break;
      }
    }
  }
  if (!pixels) throw InputError(name + ": holds no pixel data (7FE0,0010); expected an image");
  if (out.rows <= 0 || out.columns <= 0) {
    throw DicomRefusal(name + ": rows and columns (0028,0010-0011) are " + std::to_string(out.rows) + " and " +
                     std::to_string(out.columns) + "; expected an image of 1 to 65535 each");
  }
  if (out.samples != 1 && out.samples != 3) {
    throw DicomRefusal(name + ": " + std::to_string(out.samples) +
                     " samples per pixel (0028,0002); expected 1 (grey) or 3 (colour)");
  }
  const std::string& pi = out.photometric;
  if (pi == "PALETTE COLOR") {
    throw DicomRefusal(name + ": palette colour pixels (0028,0004 PALETTE COLOR); expected grey or colour ones");
  }
  if (frame_time_ms > 0) {
    out.fps = 1000.0 / frame_time_ms;
  } else if (frame_time_vector.size() > 1) {
    // The time from each frame to the next; the first entry is 0.
    double sum = 0;
    for (std::size_t i = 1; i < frame_time_vector.size(); ++i) sum += frame_time_vector[i];
    const double mean = sum / static_cast<double>(frame_time_vector.size() - 1);
    if (mean > 0) out.fps = 1000.0 / mean;
  } else if (cine_rate > 0) {
    out.fps = cine_rate;
  } else if (display_rate > 0) {
    out.fps = display_rate;
  }
  if (!std::isfinite(out.fps) || out.fps > 1e6) out.fps = 0;
  const auto cut = [&](int whole, const std::string& why) {
    if (whole <= 0) throw InputError(name + ": " + why + "; expected at least one whole frame (a file cut short?)");
    out.cut_short = why + "; its first " + std::to_string(whole) + " frame" + (whole == 1 ? "" : "s") + " are read";
    out.frames = whole;
  };

  if (!out.encapsulated || out.rle) {
    // Native or RLE: samples the decoder lays out itself, checked here.
    if (out.bits_allocated != 8 && out.bits_allocated != 16) {
      throw DicomRefusal(name + ": " + std::to_string(out.bits_allocated) +
                       " bits allocated per sample (0028,0100); expected 8 or 16");
    }
    const bool grey = out.samples == 1 && (pi.empty() || pi == "MONOCHROME1" || pi == "MONOCHROME2");
    const bool colour = out.samples == 3 && (pi == "RGB" || pi == "YBR_FULL" || pi == "YBR_FULL_422");
    if (!grey && !colour) {
      throw DicomRefusal(name + ": " + std::to_string(out.samples) + " sample(s) per pixel in photometric "
                       "interpretation '" + pi + "' (0028,0004); expected MONOCHROME1 or MONOCHROME2 (grey), or "
                       "RGB, YBR_FULL or YBR_FULL_422 (colour)");
    }
    // YBR_FULL_422: two pixels in four bytes (Y, Y, Cb, Cr); RLE keeps every
    // pixel's three samples (PS3.5 8.2.2), so it has no such frames.
    const bool ybr_422 = pi == "YBR_FULL_422";
    if (ybr_422 && out.rle) {
      throw DicomRefusal(name + ": RLE lossless frames in photometric interpretation YBR_FULL_422 (0028,0004); "
                                "expected MONOCHROME1, MONOCHROME2, RGB or YBR_FULL, as RLE keeps every sample");
    }
    if (ybr_422 && (out.bits_allocated != 8 || out.columns % 2 != 0)) {
      throw DicomRefusal(name + ": YBR_FULL_422 pixels of " + std::to_string(out.bits_allocated) + " bits in rows of " +
                       std::to_string(out.columns) + "; expected 8 bits and an even number of columns");
    }
    if (out.bits_stored > out.bits_allocated || out.high_bit >= out.bits_allocated ||
        (out.high_bit >= 0 && out.bits_stored > 0 && out.high_bit + 1 < out.bits_stored)) {
      throw DicomRefusal(name + ": " + std::to_string(out.bits_stored) + " bits stored with high bit " +
                       std::to_string(out.high_bit) + " (0028,0101-0102) in " + std::to_string(out.bits_allocated) +
                       " allocated; expected the stored bits within the allocated ones");
    }
    out.frame_size = std::uint64_t(out.rows) * std::uint64_t(out.columns) * std::uint64_t(ybr_422 ? 2 : out.samples) *
                     std::uint64_t(out.bits_allocated / 8);
  }
  if (!out.encapsulated) {
    if (pixels->length == kUndefined) r.fail_pixels(pixels->value_at, "native pixel data of a defined length");
    out.pixels_at = pixels->value_at;
    const std::uint64_t needed = out.frame_size * std::uint64_t(out.frames);
    const std::uint64_t held = std::min<std::uint64_t>(pixels->length, r.size() - pixels->value_at);
    if (held < needed) {
      cut(static_cast<int>(held / out.frame_size),
          fmt::format("its pixel data holds {} bytes; {} frame(s) of {}x{}, {} sample(s) of {} bits need {}", held,
                      out.frames, out.columns, out.rows, out.samples, out.bits_allocated, needed));
    }
    return out;
  }

  // Encapsulated: a basic offset table item, then the fragments, then the
  // sequence's end.
  if (pixels->length != kUndefined) r.fail_pixels(pixels->value_at, "encapsulated pixel data of undefined length");
  std::vector<std::uint64_t> offsets;
  bool first = true;
  std::string ended;
  bool at_boundary = false;
  for (;;) {
    if (r.size() - r.at() < 8) {
      // At a fragment's end: the fragments so far are whole (only the end
      // mark may be missing).
      at_boundary = true;
      ended = "its compressed pixel data ends before its end mark (FFFE,E0DD)";
      break;
    }
    const Header h = r.header(false);
    if (h.tag == kSequenceEnd) break;
    if (h.tag != kItem || h.length == kUndefined) {
      r.fail_pixels(h.value_at - 8, "a fragment item (FFFE,E000) of defined length, or the pixel data's end (FFFE,E0DD)");
    }
    if (h.length > r.size() - h.value_at) {
      ended = "its compressed pixel data ends within a fragment";
      // A video's stream is decoded up to where it stops.
      if (out.video && !first && r.size() > h.value_at) out.fragments.emplace_back(h.value_at, r.size() - h.value_at);
      break;
    }
    if (first) {
      if (h.length / 4 > 1'000'000) r.fail_pixels(h.value_at, "a basic offset table of at most 10^6 entries");
      for (std::uint32_t i = 0; i + 4 <= h.length; i += 4) offsets.push_back(r.u32());
      r.seek(h.value_at + h.length);
      first = false;
      continue;
    }
    if (out.fragments.size() >= 10'000'000) r.fail_pixels(h.value_at, "at most 10^7 fragments");
    out.fragments.emplace_back(h.value_at, h.length);
    r.seek(h.value_at + h.length);
  }
  if (offsets.empty()) offsets = extended_offsets;
  if (out.fragments.empty()) throw InputError(name + ": its compressed pixel data holds no fragment; expected a frame");
  if (out.video) {
    // One stream in every fragment, whatever the frames: the decoder finds
    // them, up to where a stream cut short stops (whole fragments with
    // only the end mark missing are the whole stream, or its frames fall
    // short of the file's count, which the source says).
    out.first_fragment = {0};
    if (!ended.empty() && !at_boundary) out.cut_short = ended + "; the frames of its video stream up to there are read";
    return out;
  }
  const std::size_t frames = static_cast<std::size_t>(out.frames);
  if (out.frames == 1) {
    out.first_fragment = {0};
  } else if (out.fragments.size() == frames) {
    for (std::size_t k = 0; k < frames; ++k) out.first_fragment.push_back(k);
  } else if (offsets.size() == frames) {
    // The offset table gives each frame's first fragment, counted from the
    // first fragment's item header (8 bytes before its value).
    const std::uint64_t base = out.fragments.front().first - 8;
    std::size_t f = 0;
    for (std::size_t k = 0; k < frames; ++k) {
      if (k > 0 && offsets[k] <= offsets[k - 1]) {
        throw InputError(name + ": its offset table is not in increasing order; expected one offset per frame");
      }
      while (f < out.fragments.size() && out.fragments[f].first - 8 < base + offsets[k]) ++f;
      if (f >= out.fragments.size() && !ended.empty()) break;  // cut short: the frames before
      if (f >= out.fragments.size() || out.fragments[f].first - 8 != base + offsets[k]) {
        throw InputError(name + ": frame " + std::to_string(k) + "'s offset in its offset table is no fragment's");
      }
      out.first_fragment.push_back(f);
    }
  } else {
    // No table: each frame starts with a fragment that starts a stream
    // (JPEG's FF D8 FF, a JPEG 2000 codestream's FF 4F FF 51, or a JP2
    // file's signature box).
    static const unsigned char kJpeg[] = {0xFF, 0xD8, 0xFF}, kJ2k[] = {0xFF, 0x4F, 0xFF, 0x51},
                               kJp2[] = {0x00, 0x00, 0x00, 0x0C, 0x6A, 0x50, 0x20, 0x20};
    for (std::size_t f = 0; f < out.fragments.size(); ++f) {
      unsigned char head[8] = {};
      const std::uint64_t n = std::min<std::uint64_t>(8, out.fragments[f].second);
      r.seek(out.fragments[f].first);
      r.read(head, n);
      const auto starts_with = [&](const unsigned char* sig, std::size_t len) {
        return n >= len && std::equal(sig, sig + len, head);
      };
      // RLE: its header's segment count (1 to 15) and first offset (64).
      const bool rle_header = out.rle && n == 8 && head[0] >= 1 && head[0] <= 15 && head[1] == 0 && head[2] == 0 &&
                              head[3] == 0 && head[4] == 64 && head[5] == 0 && head[6] == 0 && head[7] == 0;
      if (f == 0 || starts_with(kJpeg, 3) || starts_with(kJ2k, 4) || starts_with(kJp2, 8) || rle_header) {
        out.first_fragment.push_back(f);
      }
    }
    if (out.first_fragment.size() != frames && (ended.empty() || out.first_fragment.size() > frames)) {
      throw InputError(fmt::format("{}: {} frames in {} compressed fragments, of which {} start a stream, and no "
                                   "offset table; expected a stream per frame",
                                   name, out.frames, out.fragments.size(), out.first_fragment.size()));
    }
  }
  if (!ended.empty() && at_boundary && out.first_fragment.size() == frames &&
      (out.fragments.size() == frames || offsets.size() == frames || out.frames == 1)) {
    // Every frame is there, each whole by the count or the table: only the
    // end mark is missing.
    ended.clear();
  }
  if (!ended.empty()) {
    // A file cut short: the frames whose fragments are all there (the last
    // one begun may lack some).
    cut(std::max(0, static_cast<int>(out.first_fragment.size()) - 1), ended);
    out.fragments.resize(out.first_fragment[static_cast<std::size_t>(out.frames)]);
    out.first_fragment.resize(static_cast<std::size_t>(out.frames));
  }
  return out;
}

}  // namespace gtrack::detail
