// Fuzz target: an image file's header, read by `gtrack track` for each
// image of a folder (and a TIFF stack's first page) to refuse an image of
// another size than the sensor's before it is decoded, and a TIFF stack
// among a folder's images before its first page alone is read.
//
// Nothing may come out of image_header_size(), tiff_has_pages_after_first()
// or is_tiff_content(): a header they cannot read is no size, no stack and
// the decoder has the last word. A size given is within 1..INT_MAX on both
// sides; a stack is a TIFF.
#include <climits>
#include <cstddef>
#include <cstdint>
#include <sstream>
#include <string>

#include "tracking/image_header.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  std::istringstream in(std::string(reinterpret_cast<const char*>(data), size));
  const auto header = gtrack::detail::image_header_size(in);
  if (header && (header->width < 1 || header->height < 1)) __builtin_trap();
  const bool stack = gtrack::detail::tiff_has_pages_after_first(in);
  if (stack && !gtrack::detail::is_tiff_content(in)) __builtin_trap();
  return 0;
}
