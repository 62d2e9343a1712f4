#include "image_header.hpp"

#include <algorithm>
#include <array>
#include <cctype>
#include <climits>
#include <cstdint>
#include <istream>
#include <iterator>

namespace gtrack::detail {

namespace {

using Bytes = std::array<unsigned char, 32>;

std::uint32_t big_endian(const unsigned char* p, int n) {
  std::uint32_t v = 0;
  for (int i = 0; i < n; ++i) v = (v << 8) | p[i];
  return v;
}

std::uint32_t little_endian(const unsigned char* p, int n) {
  std::uint32_t v = 0;
  for (int i = n - 1; i >= 0; --i) v = (v << 8) | p[i];
  return v;
}

std::optional<ImageSize> sized(std::uint64_t width, std::uint64_t height) {
  if (width == 0 || height == 0 || width > INT_MAX || height > INT_MAX) return std::nullopt;
  return ImageSize{static_cast<int>(width), static_cast<int>(height)};
}

// The frame header's size: the segments before it are skipped by their
// lengths; a scan (SOS) or the end (EOI) before any frame header gives none.
std::optional<ImageSize> jpeg_size(std::istream& in) {
  in.seekg(2);
  for (int segments = 0; segments < 100000; ++segments) {
    int c = in.get();
    if (c != 0xFF) return std::nullopt;
    while (c == 0xFF) c = in.get();  // fill bytes
    if (c == EOF) return std::nullopt;
    const int marker = c;
    if (marker == 0x01 || (marker >= 0xD0 && marker <= 0xD7)) continue;  // no length
    if (marker == 0xD9 || marker == 0xDA) return std::nullopt;
    unsigned char length_bytes[2];
    if (!in.read(reinterpret_cast<char*>(length_bytes), 2)) return std::nullopt;
    const std::uint32_t length = big_endian(length_bytes, 2);
    if (length < 2) return std::nullopt;
    const bool frame_header = marker >= 0xC0 && marker <= 0xCF && marker != 0xC4 && marker != 0xC8 && marker != 0xCC;
    if (frame_header) {
      unsigned char f[5];  // precision, height, width
      if (length < 7 || !in.read(reinterpret_cast<char*>(f), 5)) return std::nullopt;
      return sized(big_endian(f + 3, 2), big_endian(f + 1, 2));
    }
    in.seekg(length - 2, std::ios::cur);
  }
  return std::nullopt;
}

// P1-P6: magic, then width and height as decimal text, with white space
// and # comments between.
std::optional<ImageSize> pnm_size(std::istream& in) {
  in.seekg(2);
  std::uint64_t values[2] = {0, 0};
  for (std::uint64_t& v : values) {
    int c = in.get();
    for (;;) {
      if (c == '#') {
        while (c != EOF && c != '\n' && c != '\r') c = in.get();
      } else if (c != EOF && std::isspace(c)) {
        c = in.get();
      } else {
        break;
      }
    }
    if (c == EOF || !std::isdigit(c)) return std::nullopt;
    for (; c != EOF && std::isdigit(c); c = in.get()) {
      v = v * 10 + static_cast<std::uint64_t>(c - '0');
      if (v > INT_MAX) return std::nullopt;
    }
    if (c == EOF) return std::nullopt;  // the number may go on in bytes not yet written
  }
  return sized(values[0], values[1]);
}

// n (2 or 4) bytes at `at`, in the file's byte order; none past its end.
std::optional<std::uint32_t> tiff_number(std::istream& in, bool little, std::uint64_t at, int n) {
  unsigned char v[4];
  in.clear();
  in.seekg(static_cast<std::streamoff>(at));
  if (!in.read(reinterpret_cast<char*>(v), n)) return std::nullopt;
  return little ? little_endian(v, n) : big_endian(v, n);
}

// The file's first four bytes (zeros when it is shorter).
std::array<unsigned char, 4> first_four_bytes(std::istream& in) {
  std::array<unsigned char, 4> b{};
  in.clear();
  in.seekg(0);
  in.read(reinterpret_cast<char*>(b.data()), 4);
  if (in.gcount() < 4) b = {};
  in.clear();
  return b;
}

// A classic TIFF's first page: ImageWidth (256) and ImageLength (257) in
// its first directory, SHORT or LONG, in the file's byte order (a SHORT
// value sits in the first two bytes of its entry's value field).
std::optional<ImageSize> tiff_size(std::istream& in, bool little) {
  const auto read = [&](std::uint64_t at, int n) { return tiff_number(in, little, at, n); };
  const auto directory = read(4, 4);
  const auto entries = directory ? read(*directory, 2) : std::nullopt;
  if (!entries) return std::nullopt;
  std::uint64_t width = 0, height = 0;
  for (std::uint32_t i = 0; i < *entries && !(width && height); ++i) {
    const std::uint64_t entry = std::uint64_t{*directory} + 2 + 12 * std::uint64_t{i};
    const auto tag = read(entry, 2), type = read(entry + 2, 2);
    if (!tag || !type) return std::nullopt;
    if ((*tag != 256 && *tag != 257) || (*type != 3 && *type != 4)) continue;
    const auto value = read(entry + 8, *type == 3 ? 2 : 4);
    if (!value) return std::nullopt;
    (*tag == 256 ? width : height) = *value;
  }
  return sized(width, height);
}

// A classic TIFF's directory after its first, unless it holds a reduced
// image (NewSubfileType 254 with bit 0 set: a thumbnail of the first).
bool tiff_second_page(std::istream& in, bool little) {
  const auto read = [&](std::uint64_t at, int n) { return tiff_number(in, little, at, n); };
  const auto first = read(4, 4);
  const auto entries = first ? read(*first, 2) : std::nullopt;
  const auto second = entries ? read(std::uint64_t{*first} + 2 + 12 * std::uint64_t{*entries}, 4) : std::nullopt;
  if (!second || *second == 0) return false;
  const auto count = read(*second, 2);
  if (!count) return false;
  for (std::uint32_t i = 0; i < *count; ++i) {
    const std::uint64_t entry = std::uint64_t{*second} + 2 + 12 * std::uint64_t{i};
    const auto tag = read(entry, 2), type = read(entry + 2, 2);
    if (!tag || !type) return false;
    if (*tag == 254 && (*type == 3 || *type == 4)) {
      const auto value = read(entry + 8, *type == 3 ? 2 : 4);
      return value && (*value & 1u) == 0;
    }
  }
  return true;
}

}  // namespace

bool tiff_has_pages_after_first(std::istream& in) {
  const auto b = first_four_bytes(in);
  if (b[0] == 'I' && b[1] == 'I' && b[2] == 42 && b[3] == 0) return tiff_second_page(in, true);
  if (b[0] == 'M' && b[1] == 'M' && b[2] == 0 && b[3] == 42) return tiff_second_page(in, false);
  return false;
}

bool is_tiff_content(std::istream& in) {
  const auto b = first_four_bytes(in);
  return (b[0] == 'I' && b[1] == 'I' && (b[2] == 42 || b[2] == 43) && b[3] == 0) ||
         (b[0] == 'M' && b[1] == 'M' && b[2] == 0 && (b[3] == 42 || b[3] == 43));
}

std::optional<ImageSize> image_header_size(std::istream& in) {
  in.seekg(0);
  Bytes b{};
  in.read(reinterpret_cast<char*>(b.data()), static_cast<std::streamsize>(b.size()));
  const std::streamsize got = in.gcount();
  in.clear();
  if (got < 2) return std::nullopt;
  static constexpr unsigned char kPng[] = {0x89, 'P', 'N', 'G', 0x0D, 0x0A, 0x1A, 0x0A};
  if (got >= 24 && std::equal(std::begin(kPng), std::end(kPng), b.begin()) &&
      big_endian(b.data() + 12, 4) == big_endian(reinterpret_cast<const unsigned char*>("IHDR"), 4)) {
    return sized(big_endian(b.data() + 16, 4), big_endian(b.data() + 20, 4));
  }
  if (b[0] == 0xFF && b[1] == 0xD8) return jpeg_size(in);
  if (b[0] == 'B' && b[1] == 'M' && got >= 26) {
    if (little_endian(b.data() + 14, 4) == 12) {  // BITMAPCOREHEADER: 16-bit sizes
      return sized(little_endian(b.data() + 18, 2), little_endian(b.data() + 20, 2));
    }
    const auto height = static_cast<std::int32_t>(little_endian(b.data() + 22, 4));  // < 0: top-down rows
    return sized(little_endian(b.data() + 18, 4), height < 0 ? -static_cast<std::int64_t>(height) : height);
  }
  if (b[0] == 'P' && b[1] >= '1' && b[1] <= '6') return pnm_size(in);
  if (got >= 8 && b[0] == 'I' && b[1] == 'I' && b[2] == 42 && b[3] == 0) return tiff_size(in, true);
  if (got >= 8 && b[0] == 'M' && b[1] == 'M' && b[2] == 0 && b[3] == 42) return tiff_size(in, false);
  return std::nullopt;
}

}  // namespace gtrack::detail
