// Per-frame results as files: estimates.csv, estimates.jsonl, summary.json.
//
// Rows are appended and flushed as soon as a frame is done, so a run that is
// interrupted keeps every finished frame in well-formed files.
// estimates.csv: frame,x_mm,y_mm,z_mm,rx_deg,ry_deg,rz_deg,q1_deg,...,qF_deg,cost,status,ms
// estimates.jsonl: one object per frame with the same fields plus time_s,
// the cost terms D, K, S, the stimulus value, |O| and per-stage times.
#pragma once

#include <filesystem>
#include <fstream>
#include <string>

#include "gtrack/export.hpp"
#include "gtrack/tracker.hpp"

namespace gtrack {

class GTRACK_API ResultWriter {
 public:
  // Creates the folder if needed; InputError if it cannot be written.
  ResultWriter(const std::filesystem::path& out_dir, int fingers);
  void write(const Estimate& estimate);
  void close();

 private:
  std::ofstream csv_, jsonl_;
  std::filesystem::path dir_;
};

GTRACK_API void write_summary(const std::filesystem::path& file, const TrackSummary& summary);

}  // namespace gtrack
