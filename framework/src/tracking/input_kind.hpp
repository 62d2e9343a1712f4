// What kind of recording an --input names, as the frame sources tell them
// apart.
#pragma once

#include <string>

namespace gtrack::detail {

// A multi-page TIFF: a regular file named .tif or .tiff, in any case. Like
// a folder of images, it carries no frame rate of its own.
bool is_tiff_file(const std::string& spec);

}  // namespace gtrack::detail
