// An image file's width and height from its header, without decoding it,
// so that an image of the wrong size (a folder of a 30000x30000 scan, a
// camera set to another resolution) is refused before its pixels are
// allocated.
#pragma once

#include <istream>
#include <optional>

#include "gtrack/sensor.hpp"

namespace gtrack::detail {

// The size the header read from `in` gives, recognised by its first bytes
// (not a file's name): PNG, JPEG (its first frame header, SOF0-SOF15), BMP
// and PNM (P1-P6). nullopt for any other kind, a header cut short (a file
// still being written) or one that does not parse: the decoder then says
// what is wrong. Reads from the stream's start; never throws.
std::optional<ImageSize> image_header_size(std::istream& in);

// Whether `in` starts as a TIFF file (classic or BigTIFF), whose first
// page's size libtiff reads; the stream is put back at its start.
bool is_tiff(std::istream& in);

}  // namespace gtrack::detail
