// Fuzz target: tracker_state.txt, read by `gtrack track --resume`.
//
// A state that parses has a frame, finite configurations, and writes back to
// a text that parses to the same state. Only gtrack::Error (InputError) may
// come out of parse_tracker_state().
#include <unistd.h>

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "gtrack/error.hpp"
#include "gtrack/tracker_state.hpp"

namespace {

bool same(const std::optional<Eigen::VectorXd>& a, const std::optional<Eigen::VectorXd>& b) {
  if (a.has_value() != b.has_value()) return false;
  return !a || (a->size() == b->size() && *a == *b);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  gtrack::TrackerState s;
  try {
    s = gtrack::parse_tracker_state(text, "fuzz.txt");
  } catch (const gtrack::Error&) {
    return 0;
  }
  for (const auto* v : {&s.last, &s.before_last}) {
    if (*v && !(*v)->allFinite()) __builtin_trap();
  }
  // Round trip through the writer.
  static const std::filesystem::path file =
      std::filesystem::temp_directory_path() / ("fuzz_tracker_state_" + std::to_string(::getpid()) + ".txt");
  gtrack::write_tracker_state(file, s);
  std::ifstream in(file);
  std::stringstream back;
  back << in.rdbuf();
  const gtrack::TrackerState t = gtrack::parse_tracker_state(back.str(), file.string());
  if (t.frame != s.frame || t.lost != s.lost || t.started != s.started || t.reference_area != s.reference_area ||
      !same(t.last, s.last) || !same(t.before_last, s.before_last) || t.run != s.run) {
    __builtin_trap();
  }
  return 0;
}
