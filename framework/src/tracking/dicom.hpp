// A DICOM file's image layout: what its frames are and where their bytes
// lie, read without decoding them (and without a DICOM library: OpenCV's
// reads single frames only). A B-mode cine loop exported by a scanner is
// one multi-frame file: native pixels (8 or 16 bits, grey or colour), or
// each frame compressed as JPEG or JPEG 2000 (decoded by OpenCV) or RLE
// lossless (decoded here), or the whole loop as one MPEG-2, H.264 or HEVC
// video stream (decoded by OpenCV's video reader).
#pragma once

#include <cstdint>
#include <istream>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "gtrack/error.hpp"

namespace gtrack::detail {

// A file refused for what its header says (an encoding, a kind of pixel
// not taken): final, however long a followed folder's writer is waited on.
struct DicomRefusal : InputError {
  using InputError::InputError;
};

struct DicomLayout {
  int rows = 0, columns = 0;
  int samples = 1;         // per pixel: 1 (grey) or 3 (colour)
  int bits_allocated = 8;  // 8 or 16
  int bits_stored = 0;     // 0: as allocated
  int high_bit = -1;       // the stored bits' highest; -1: bits_stored - 1
  int planar = 0;          // 3 samples: 0 = interleaved, 1 = one plane after the other
  int frames = 1;
  std::string photometric;      // MONOCHROME2, RGB, YBR_FULL_422, ...
  std::string transfer_syntax;  // its UID
  bool encapsulated = false;    // compressed: each frame's fragments are a JPEG, JPEG 2000 or RLE stream
  bool rle = false;             // RLE lossless: decoded by decode_rle_frame()
  bool video = false;           // MPEG-2, H.264 or HEVC: the fragments hold one video stream, not a frame each
  double fps = 0;               // from the frame time (vector) or the cine rate; 0 when the file gives none
  // The pixel size the file gives, in mm (width, height): the first 2D
  // ultrasound region's (0018,6011: PhysicalDeltaX and Y in cm), else Pixel
  // Spacing (0028,0030), else Imager Pixel Spacing (0018,1164); none when
  // the file gives none.
  std::optional<std::pair<double, double>> pixel_mm;
  // Why the file holds fewer whole frames than it says (cut short), or "".
  std::string cut_short;

  // Native pixels: where the first frame starts and each frame's size (for
  // RLE too: the size of a decoded frame).
  std::uint64_t pixels_at = 0, frame_size = 0;
  // Encapsulated: the fragments (offset in the file, length), and each
  // frame's first fragment (frame k has fragments [first[k], first[k+1])).
  std::vector<std::pair<std::uint64_t, std::uint64_t>> fragments;
  std::vector<std::size_t> first_fragment;

  // Frame k's bytes as (offset, length) spans (a video: the stream's, as frame 0's).
  std::vector<std::pair<std::uint64_t, std::uint64_t>> frame_spans(int k) const;
};

// Reads the layout from the file's start (with its 128-byte preamble and
// "DICM", or a bare dataset). InputError naming `name` and what was
// expected, for anything it cannot take.
DicomLayout read_dicom_layout(std::istream& in, const std::string& name);

// Named .dcm or .dicom, in any case.
bool has_dicom_extension(const std::string& path);

// A regular file named .dcm or .dicom (any case), or with "DICM" at byte
// 128, as scanners export without an extension (not DICOMDIR, an index).
bool is_dicom_file(const std::string& spec);

// The transfer syntax by name, for messages ("JPEG baseline (1.2.840...)").
std::string transfer_syntax_name(const std::string& uid);

// An RLE lossless frame (its fragments' bytes, in order) decoded to native
// pixel bytes: 16-bit samples little endian, and 3 samples one plane after
// the other (as PlanarConfiguration 1 lays them out). InputError naming
// `what` when the frame does not hold the layout's pixels.
std::vector<unsigned char> decode_rle_frame(const std::vector<unsigned char>& data, const DicomLayout& layout,
                                            const std::string& what);

// A JPEG stream of RGB samples (no JFIF or Adobe marker, component ids not
// 'R', 'G', 'B') that a decoder would take as YCbCr: given an Adobe marker
// that says RGB. Other streams are returned unchanged.
std::vector<unsigned char> jpeg_marked_rgb(std::vector<unsigned char> stream);

}  // namespace gtrack::detail
