// Fuzz target: the stimulus CSV (frame,value or time_s,value).
//
// A log that parses must answer every query: value_at() inside the log gives
// a finite value (it interpolates between finite rows), nearest() always
// does. Only gtrack::Error (InputError) may come out of parse().
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <string>

#include "gtrack/error.hpp"
#include "gtrack/stimulus_log.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  gtrack::StimulusLog log;
  try {
    log = gtrack::StimulusLog::parse(text, "fuzz.csv");
  } catch (const gtrack::Error&) {
    return 0;
  }
  if (log.rows() == 0) __builtin_trap();
  for (int frame : {-1, 0, 1, 2, 7, 100, 1000000}) {
    const double t = frame / 30.0;
    if (const auto v = log.value_at(frame, t); v && !std::isfinite(*v)) __builtin_trap();
    if (!std::isfinite(log.nearest(frame, t))) __builtin_trap();
  }
  return 0;
}
