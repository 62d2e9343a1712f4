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
// (not a file's name): PNG, JPEG (its first frame header, SOF0-SOF15), BMP,
// PNM (P1-P6) and classic TIFF (its first page's directory). nullopt for
// any other kind (BigTIFF among them), a header cut short (a file still
// being written) or one that does not parse: the decoder then says what is
// wrong. Reads from the stream's start; never throws.
std::optional<ImageSize> image_header_size(std::istream& in);

// A classic TIFF (by its first bytes) with a page after its first that is
// not a thumbnail of it (NewSubfileType bit 0): a stack. false for any
// other file, a BigTIFF or a chain cut short. Never throws.
bool tiff_has_pages_after_first(std::istream& in);

// The first bytes of a TIFF or a BigTIFF, in either byte order.
bool is_tiff_content(std::istream& in);

}  // namespace gtrack::detail
