// Where gtrack's own messages go: the process's stderr as it was when the
// first message was written, through a descriptor of its own. A library's
// output taken aside from fd 2 (detail::CapturedStderr, around a decoder)
// never holds them, whichever thread takes it aside: frames are read on a
// thread of their own while the tracker logs and shows its progress.
#pragma once

#include <cstdio>

namespace gtrack::detail {

std::FILE* console();

}  // namespace gtrack::detail
