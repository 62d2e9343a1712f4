// estimates.csv / estimates.jsonl rows and summary.json.
#include "gtrack/results.hpp"

#include <cmath>
#include <cstdio>

#include "gtrack/error.hpp"

namespace gtrack {

namespace fs = std::filesystem;

namespace {

std::string num(double v, const char* fmt) {
  if (!std::isfinite(v)) return "null";
  char buf[64];
  std::snprintf(buf, sizeof buf, fmt, v);
  return buf;
}

std::ofstream open_truncated(const fs::path& p) {
  std::ofstream out(p, std::ios::trunc);
  if (!out) throw InputError(p.string() + ": cannot open for writing");
  return out;
}

}  // namespace

ResultWriter::ResultWriter(const fs::path& out_dir, int fingers) : dir_(out_dir) {
  std::error_code ec;
  fs::create_directories(out_dir, ec);
  if (ec || !fs::is_directory(out_dir)) {
    throw InputError(out_dir.string() + ": cannot create the output folder (" +
                     (ec ? ec.message() : std::string("not a folder")) + ")");
  }
  csv_ = open_truncated(out_dir / "estimates.csv");
  jsonl_ = open_truncated(out_dir / "estimates.jsonl");
  csv_ << "frame,x_mm,y_mm,z_mm,rx_deg,ry_deg,rz_deg";
  for (int f = 1; f <= fingers; ++f) csv_ << ",q" << f << "_deg";
  csv_ << ",cost,status,ms\n";
  csv_.flush();
  if (!csv_) throw InputError((out_dir / "estimates.csv").string() + ": write failed");
}

void ResultWriter::write(const Estimate& e) {
  const Eigen::VectorXd& h = e.hypothesis;
  std::string row = std::to_string(e.frame);
  for (Eigen::Index i = 0; i < h.size(); ++i) row += "," + num(h[i], i < 3 ? "%.6f" : "%.4f");
  row += "," + num(e.terms.total, "%.6f") + "," + to_string(e.status) + "," + num(e.ms, "%.3f") + "\n";
  csv_ << row;
  csv_.flush();

  static const char* pose[] = {"x_mm", "y_mm", "z_mm", "rx_deg", "ry_deg", "rz_deg"};
  std::string j = "{\"frame\":" + std::to_string(e.frame) + ",\"time_s\":" + num(e.time_s, "%.6f");
  for (Eigen::Index i = 0; i < h.size(); ++i) {
    const std::string name = i < kPoseDims ? pose[i] : "q" + std::to_string(i - kPoseDims + 1) + "_deg";
    j += ",\"" + name + "\":" + num(h[i], i < 3 ? "%.6f" : "%.4f");
  }
  j += ",\"cost\":" + num(e.terms.total, "%.6f") + ",\"status\":\"" + to_string(e.status) + "\",\"ms\":" +
       num(e.ms, "%.3f");
  j += ",\"D\":" + num(e.terms.dice, "%.6f") + ",\"K\":" + num(e.terms.kinematic, "%.6f") +
       ",\"S\":" + num(e.terms.stimulus, "%.6f") + ",\"T\":" + num(e.terms.temporal, "%.6f") +
       ",\"outside_weight\":" + num(e.outside_weight, "%.4f") +
       ",\"outside_allowance\":" + num(e.outside_allowance, "%.1f") + ",\"redetected\":" +
       (e.redetected ? "true" : "false") + ",\"mirrored\":" + (e.mirrored ? "true" : "false");
  j += ",\"stimulus\":" + (e.stimulus ? num(*e.stimulus, "%.4f") : std::string("null"));
  j += ",\"observed_pixels\":" + std::to_string(e.observed_pixels) + ",\"evaluations\":" +
       std::to_string(e.evaluations);
  j += ",\"segment_ms\":" + num(e.times.segment_ms, "%.3f") + ",\"pso_ms\":" + num(e.times.pso_ms, "%.3f") + "}\n";
  jsonl_ << j;
  jsonl_.flush();
  if (!csv_ || !jsonl_) throw InputError(dir_.string() + ": writing the estimates failed (disk full?)");
}

void ResultWriter::close() {
  csv_.close();
  jsonl_.close();
}

void write_summary(const fs::path& file, const TrackSummary& s) {
  std::ofstream out(file, std::ios::trunc);
  if (!out) throw InputError(file.string() + ": cannot open for writing");
  const double fps = s.wall_s > 0 ? s.frames / s.wall_s : 0.0;
  out << "{\n"
      << "  \"frames\": " << s.frames << ",\n"
      << "  \"lost_frames\": " << s.lost_frames << ",\n"
      << "  \"mean_cost\": " << num(s.mean_cost, "%.6f") << ",\n"
      << "  \"mean_ms\": " << num(s.mean_ms, "%.3f") << ",\n"
      << "  \"stages_ms\": {\"segment\": " << num(s.mean_times.segment_ms, "%.3f")
      << ", \"pso\": " << num(s.mean_times.pso_ms, "%.3f") << ", \"io\": " << num(s.mean_times.io_ms, "%.3f")
      << "},\n"
      << "  \"wall_s\": " << num(s.wall_s, "%.3f") << ",\n"
      << "  \"frames_per_s\": " << num(fps, "%.3f") << ",\n"
      << "  \"renderer\": \"" << s.renderer << "\",\n"
      << "  \"overlay\": \"" << s.overlay_file.filename().string() << "\",\n"
      << "  \"cancelled\": " << (s.cancelled ? "true" : "false") << "\n"
      << "}\n";
  if (!out) throw InputError(file.string() + ": write failed");
}

}  // namespace gtrack
