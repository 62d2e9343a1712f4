// Fuzz target: an image file's header, read by `gtrack track` for each
// image of a folder (and a TIFF stack's first page) to refuse an image of
// another size than the sensor's before it is decoded.
//
// Nothing may come out of image_header_size(): a header it cannot read is
// no size, and the decoder has the last word. A size it gives is within
// 1..INT_MAX on both sides.
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
  return 0;
}
