// Fuzz target: pose tables (ground_truth.csv, estimates.csv), read by
// `gtrack eval`, `gtrack track --restart-from` and the synthetic benchmark.
//
// A table that reads has joint columns, one parameter vector of the right
// size per row, and each frame once, as a whole number from 0. Only
// gtrack::Error (InputError) may come out of read_pose_table().
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <set>
#include <string>

#include "gtrack/error.hpp"
#include "gtrack/parameter_space.hpp"
#include "gtrack/sequence_io.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static const std::filesystem::path file =
      std::filesystem::temp_directory_path() / ("fuzz_pose_table_" + std::to_string(::getpid()) + ".csv");
  {
    std::ofstream out(file, std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
  }
  gtrack::PoseTable t;
  try {
    t = gtrack::read_pose_table(file);
  } catch (const gtrack::Error&) {
    return 0;
  }
  if (t.fingers < 1) __builtin_trap();
  std::set<int> frames;
  for (const auto& row : t.rows) {
    if (row.h.size() != gtrack::kPoseDims + t.fingers) __builtin_trap();
    if (row.frame < 0 || !frames.insert(row.frame).second) __builtin_trap();
    if (!row.status.empty() && row.status != "ok" && row.status != "search" && row.status != "lost") __builtin_trap();
  }
  return 0;
}
