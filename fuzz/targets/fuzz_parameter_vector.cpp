// Fuzz target: the --params vector "x,y,z,rx,ry,rz,q1,...,qF".
//
// The first byte picks the expected dimension (6..69, as a gripper of 0..63
// fingers would), the rest is the text. A vector that parses has exactly that
// many finite values; anything else is an InputError.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "gtrack/error.hpp"
#include "gtrack/parameter_space.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 1) return 0;
  const int dims = gtrack::kPoseDims + data[0] % 64;
  const std::string_view text(reinterpret_cast<const char*>(data + 1), size - 1);
  try {
    const Eigen::VectorXd h = gtrack::parse_parameter_vector(text, dims);
    if (h.size() != dims || !h.allFinite()) __builtin_trap();
  } catch (const gtrack::Error&) {
  }
  return 0;
}
