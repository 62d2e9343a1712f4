// Fuzz target: a DICOM file's layout, read by `gtrack track --input
// file.dcm` (and for each .dcm image of a folder).
//
// A layout that reads has an image size, 1 or 3 samples, at least one
// frame, and every frame's bytes inside the file; an RLE frame decodes to
// the frame's size. Only gtrack::Error (InputError) may come out of
// read_dicom_layout() and decode_rle_frame().
#include <cstddef>
#include <cstdint>
#include <sstream>
#include <string>
#include <vector>

#include "gtrack/error.hpp"
#include "tracking/dicom.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  std::istringstream in(std::string(reinterpret_cast<const char*>(data), size));
  gtrack::detail::DicomLayout layout;
  try {
    layout = gtrack::detail::read_dicom_layout(in, "fuzz.dcm");
  } catch (const gtrack::Error&) {
    return 0;
  }
  if (layout.rows <= 0 || layout.columns <= 0 || (layout.samples != 1 && layout.samples != 3)) __builtin_trap();
  if (layout.frames < 1) __builtin_trap();
  // A video's stream is frame 0's spans.
  for (int k = 0; k < (layout.video ? 1 : layout.frames); ++k) {
    const auto spans = layout.frame_spans(k);
    if (spans.empty()) __builtin_trap();
    for (const auto& [offset, length] : spans) {
      if (offset > size || length > size - offset) __builtin_trap();
    }
  }
  // RLE frames are decoded here, not by OpenCV: to the layout's frame size,
  // or refused with an InputError.
  if (layout.rle) {
    for (int k = 0; k < layout.frames && k < 4; ++k) {
      std::vector<unsigned char> bytes;
      for (const auto& [offset, length] : layout.frame_spans(k)) {
        bytes.insert(bytes.end(), data + offset, data + offset + length);
      }
      try {
        const auto decoded = gtrack::detail::decode_rle_frame(bytes, layout, "fuzz.dcm frame");
        if (decoded.size() != layout.frame_size) __builtin_trap();
      } catch (const gtrack::Error&) {
      }
    }
  }
  return 0;
}
