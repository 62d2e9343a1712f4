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
    if (h.length != kUndefined && h.length > size_ - at_) {
      fail(start, fmt::format("tag ({:04X},{:04X}) to hold {} bytes; the file has {} after it", h.tag >> 16,
                              h.tag & 0xFFFF, h.length, size_ - at_));
    }
    return h;
  }

  std::string text(const Header& h) {
    if (h.length == kUndefined || h.length > 4096) fail(h.value_at, "a short text value");
    std::string s(h.length, '\0');
    read(s.data(), h.length);
    return trimmed(s);
  }

  // An unsigned short (US) value.
  int us(const Header& h) {
    if (h.length != 2) fail(h.value_at, fmt::format("a 2-byte value for tag ({:04X},{:04X})", h.tag >> 16, h.tag & 0xFFFF));
    return u16();
  }

  // A decimal or integer string (DS, IS): its first value, or none.
  std::optional<double> decimal(const Header& h) {
    std::string s = text(h);
    s = s.substr(0, s.find('\\'));
    double v = 0;
    const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
    if (s.empty() || ec != std::errc() || end != s.data() + s.size() || !std::isfinite(v)) return std::nullopt;
    return v;
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

  // An 8-byte double (FD).
  double fd(const Header& h) {
    if (h.length != 8) fail(h.value_at, fmt::format("an 8-byte value for tag ({:04X},{:04X})", h.tag >> 16, h.tag & 0xFFFF));
    unsigned char b[8];
    read(b, 8);
    std::uint64_t bits = 0;
    for (int i = 7; i >= 0; --i) bits = (bits << 8) | b[i];
    double v = 0;
    std::memcpy(&v, &bits, sizeof v);
    return v;
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

 private:
  std::istream& in_;
  std::string name_;
  std::uint64_t size_ = 0;
  std::uint64_t at_ = 0;
};

}  // namespace

std::string transfer_syntax_name(const std::string& uid) {
  static const std::array<std::pair<const char*, const char*>, 12> kNames = {{
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
  }};
  for (const auto& [u, n] : kNames) {
    if (uid == u) return std::string(n) + " (" + uid + ")";
  }
  if (uid == "1.2.840.10008.1.2.5") return "RLE lossless (" + uid + ")";
  return uid;
}

bool is_dicom_file(const std::string& spec) {
  std::error_code ec;
  if (!fs::is_regular_file(spec, ec)) return false;
  std::string ext = fs::path(spec).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  if (ext == ".dcm" || ext == ".dicom") return true;
  std::ifstream in(spec, std::ios::binary);
  char magic[132] = {};
  return in.read(magic, sizeof magic) && std::string_view(magic + 128, 4) == "DICM";
}

DicomLayout read_dicom_layout(std::istream& in, const std::string& name) {
  Reader r(in, name);
  DicomLayout out;
  out.transfer_syntax = kImplicitLittle;  // a bare dataset, without the file meta group
  char magic[132] = {};
  if (r.size() >= sizeof magic) {
    r.read(magic, sizeof magic);
    if (std::string_view(magic + 128, 4) == "DICM") {
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
    } else {
      r.seek(0);
    }
  }
  const std::string& ts = out.transfer_syntax;
  const bool explicit_vr = ts != kImplicitLittle;
  const bool native = ts == kImplicitLittle || ts == kExplicitLittle;
  static const std::array<const char*, 6> kCompressed = {"1.2.840.10008.1.2.4.50", "1.2.840.10008.1.2.4.51",
                                                         "1.2.840.10008.1.2.4.90", "1.2.840.10008.1.2.4.91",
                                                         "1.2.840.10008.1.2.4.57", "1.2.840.10008.1.2.4.70"};
  if (!native && std::find(kCompressed.begin(), kCompressed.end(), ts) == kCompressed.end()) {
    throw InputError(name + ": its pixels are stored as " + transfer_syntax_name(ts) +
                     "; expected native pixels (explicit or implicit VR little endian), JPEG or JPEG 2000 (convert "
                     "it, e.g. gdcmconv --raw in.dcm out.dcm)");
  }
  out.encapsulated = !native;

  double frame_time_ms = 0, cine_rate = 0, display_rate = 0;
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
      case tag(0x0028, 0x0103): out.is_signed = r.us(h) != 0; break;
      case tag(0x0028, 0x0006): out.planar = r.us(h); break;
      case tag(0x0028, 0x0004): out.photometric = r.text(h); break;
      case tag(0x0028, 0x0008): {
        const double n = r.decimal(h).value_or(-1);
        if (!(n >= 1 && n <= 1e7)) r.fail(h.value_at, "a number of frames (0028,0008) from 1 to 10^7");
        out.frames = static_cast<int>(n);
        break;
      }
      case tag(0x0018, 0x1063): frame_time_ms = r.decimal(h).value_or(0); break;
      case tag(0x0018, 0x0040): cine_rate = r.decimal(h).value_or(0); break;
      case tag(0x0008, 0x2144): display_rate = r.decimal(h).value_or(0); break;
      case tag(0x0018, 0x6011): {
        // Sequence of ultrasound regions: the first one's pixel size.
        int units = 0;
        double dx = 0, dy = 0;
        const bool un = h.vr[0] == 'U' && h.vr[1] == 'N';  // a sequence of VR UN holds implicit VR
        r.items(h, explicit_vr && !un, [&](int item, const Header& e) {
          if (item == 0 && e.tag == tag(0x0018, 0x6024)) {
            units = r.us(e);
          } else if (item == 0 && e.tag == tag(0x0018, 0x602C)) {
            dx = r.fd(e);
          } else if (item == 0 && e.tag == tag(0x0018, 0x602E)) {
            dy = r.fd(e);
          } else {
            r.skip_value(e, explicit_vr && !un, 2);
          }
        });
        if (units == 3 && dx > 0 && dy > 0 && std::isfinite(dx) && std::isfinite(dy)) {  // cm
          out.region_mm_x = 10 * dx;
          out.region_mm_y = 10 * dy;
        }
        break;
      }
      default: r.skip_value(h, explicit_vr, 1);
    }
  }
  if (!pixels) throw InputError(name + ": holds no pixel data (7FE0,0010); expected an image");
  if (out.rows <= 0 || out.columns <= 0 || out.rows > 65535 || out.columns > 65535) {
    throw InputError(name + ": rows and columns (0028,0010-0011) are " + std::to_string(out.rows) + " and " +
                     std::to_string(out.columns) + "; expected an image of 1 to 65535 each");
  }
  if (out.samples != 1 && out.samples != 3) {
    throw InputError(name + ": " + std::to_string(out.samples) +
                     " samples per pixel (0028,0002); expected 1 (grey) or 3 (colour)");
  }
  if (frame_time_ms > 0) {
    out.fps = 1000.0 / frame_time_ms;
  } else if (cine_rate > 0) {
    out.fps = cine_rate;
  } else if (display_rate > 0) {
    out.fps = display_rate;
  }
  if (!std::isfinite(out.fps) || out.fps > 1e6) out.fps = 0;

  if (!out.encapsulated) {
    if (out.bits_allocated != 8 && out.bits_allocated != 16) {
      throw InputError(name + ": " + std::to_string(out.bits_allocated) +
                       " bits allocated per sample (0028,0100); expected 8 or 16");
    }
    if (pixels->length == kUndefined) r.fail(pixels->value_at, "native pixel data of a defined length");
    // YBR_FULL_422: two pixels in four bytes (Y, Y, Cb, Cr).
    const bool ybr_422 = out.photometric == "YBR_FULL_422" && out.samples == 3;
    if (ybr_422 && (out.bits_allocated != 8 || out.columns % 2 != 0)) {
      throw InputError(name + ": YBR_FULL_422 pixels of " + std::to_string(out.bits_allocated) + " bits in rows of " +
                       std::to_string(out.columns) + "; expected 8 bits and an even number of columns");
    }
    const std::uint64_t frame = std::uint64_t(out.rows) * std::uint64_t(out.columns) *
                                std::uint64_t(ybr_422 ? 2 : out.samples) * std::uint64_t(out.bits_allocated / 8);
    const std::uint64_t needed = frame * std::uint64_t(out.frames);
    if (pixels->length < needed) {
      throw InputError(fmt::format("{}: its pixel data holds {} bytes; {} frame(s) of {}x{}, {} sample(s) of {} bits "
                                   "need {} (a file cut short?)",
                                   name, pixels->length, out.frames, out.columns, out.rows, out.samples,
                                   out.bits_allocated, needed));
    }
    for (int k = 0; k < out.frames; ++k) out.frame_bytes.push_back({{pixels->value_at + frame * std::uint64_t(k), frame}});
    return out;
  }

  // Encapsulated: a basic offset table item, then the fragments, then the
  // sequence's end.
  if (pixels->length != kUndefined) r.fail(pixels->value_at, "encapsulated pixel data of undefined length");
  std::vector<std::uint32_t> offsets;
  std::vector<std::pair<std::uint64_t, std::uint64_t>> fragments;
  bool first = true;
  for (;;) {
    const Header h = r.header(false);
    if (h.tag == kSequenceEnd) break;
    if (h.tag != kItem || h.length == kUndefined) {
      r.fail(h.value_at - 8, "a fragment item (FFFE,E000) of defined length, or the pixel data's end (FFFE,E0DD)");
    }
    if (first) {
      for (std::uint32_t i = 0; i + 4 <= h.length; i += 4) offsets.push_back(r.u32());
      r.seek(h.value_at + h.length);
      first = false;
      continue;
    }
    if (fragments.size() >= 10'000'000) r.fail(h.value_at, "at most 10^7 fragments");
    fragments.emplace_back(h.value_at, h.length);
    r.seek(h.value_at + h.length);
  }
  if (fragments.empty()) throw InputError(name + ": its compressed pixel data holds no fragment; expected a frame");
  if (out.frames == 1) {
    out.frame_bytes.push_back(fragments);
  } else if (static_cast<int>(fragments.size()) == out.frames) {
    for (const auto& f : fragments) out.frame_bytes.push_back({f});
  } else if (static_cast<int>(offsets.size()) == out.frames) {
    // The offset table gives each frame's first fragment, counted from the
    // first fragment's item header (8 bytes before its value).
    const std::uint64_t base = fragments.front().first - 8;
    out.frame_bytes.assign(static_cast<std::size_t>(out.frames), {});
    std::size_t f = 0;
    for (int k = 0; k < out.frames; ++k) {
      const std::uint64_t end = k + 1 < out.frames ? base + offsets[static_cast<std::size_t>(k) + 1]
                                                   : std::numeric_limits<std::uint64_t>::max();
      if (k > 0 && offsets[static_cast<std::size_t>(k)] <= offsets[static_cast<std::size_t>(k) - 1]) {
        throw InputError(name + ": its basic offset table is not in increasing order; expected one offset per frame");
      }
      while (f < fragments.size() && fragments[f].first - 8 < end) out.frame_bytes[static_cast<std::size_t>(k)].push_back(fragments[f++]);
      if (out.frame_bytes[static_cast<std::size_t>(k)].empty()) {
        throw InputError(name + ": frame " + std::to_string(k) + " has no fragment in its basic offset table");
      }
    }
  } else {
    throw InputError(fmt::format("{}: {} frames in {} compressed fragments, and a basic offset table of {} entries; "
                                 "expected one fragment per frame or an offset per frame",
                                 name, out.frames, fragments.size(), offsets.size()));
  }
  return out;
}

}  // namespace gtrack::detail
