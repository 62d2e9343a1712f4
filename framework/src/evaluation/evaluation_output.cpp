// The evaluation as JSON and the per-frame errors as CSV.
#include <cmath>
#include <cstdio>
#include <sstream>

#include "gtrack/error.hpp"
#include "gtrack/evaluation.hpp"
#include "gtrack/text_file.hpp"

namespace gtrack {

namespace {

std::string num(double v) {
  if (!std::isfinite(v)) return "null";
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.4g", v);
  return buf;
}

std::string stats_json(const ErrorStats& s) {
  // No frame, no figure: null, never a perfect 0.
  if (s.count == 0) return "{\"mean\": null, \"std\": null, \"median\": null, \"max\": null, \"count\": 0}";
  return "{\"mean\": " + num(s.mean) + ", \"std\": " + num(s.std) + ", \"median\": " + num(s.median) +
         ", \"max\": " + num(s.max) +
         ", \"count\": " + std::to_string(s.count) + "}";
}

void error_set_json(std::ostringstream& o, const ErrorSet& e, const std::string& indent) {
  o << indent << "\"position_um\": " << stats_json(e.position_um) << ",\n"
    << indent << "\"position_inplane_um\": " << stats_json(e.position_inplane_um) << ",\n"
    << indent << "\"depth_um\": " << stats_json(e.depth_um) << ",\n"
    << indent << "\"orientation_deg\": " << stats_json(e.orientation_deg) << ",\n"
    << indent << "\"orientation_axes_deg\": {\"x\": " << stats_json(e.axis_deg[0])
    << ", \"y\": " << stats_json(e.axis_deg[1]) << ", \"z\": " << stats_json(e.axis_deg[2]) << "},\n"
    << indent << "\"joint_deg\": " << stats_json(e.joint_deg) << ",\n"
    << indent << "\"endpoint_um\": " << stats_json(e.endpoint_um);
}

}  // namespace

std::string evaluation_json(const Evaluation& ev) {
  std::ostringstream o;
  o << "{\n";
  error_set_json(o, ev.in_view, "  ");
  o << ",\n"
    << "  \"frames\": " << ev.frames << ",\n"
    << "  \"in_view_frames\": " << ev.in_view_frames << ",\n"
    << "  \"evaluated_frames\": " << ev.evaluated_frames << ",\n"
    << "  \"lost_frames\": " << ev.lost_frames << ",\n"
    << "  \"lost_in_view_frames\": " << ev.lost_in_view_frames << ",\n"
    << "  \"missing_frames\": " << ev.missing_frames << ",\n"
    << "  \"search_frames\": " << ev.search_frames << ",\n"
    << "  \"off_track_frames\": " << ev.off_track_frames << ",\n"
    << "  \"tilt_mirror\": {\"frames\": " << ev.tilt_mirror_frames
    << ", \"orientation_share\": " << num(ev.tilt_mirror_orientation_share)
    << ", \"orientation_other_frames_deg\": " << stats_json(ev.orientation_without_tilt_mirror_deg) << "},\n"
    << "  \"tilt_branch\": {\"frames\": " << ev.tilt_branch_frames
    << ", \"orientation_share\": " << num(ev.tilt_branch_orientation_share) << "},\n"
    << "  \"out_of_view\": {\n    \"frames\": " << ev.out_of_view_frames << ",\n";
  error_set_json(o, ev.out_of_view, "    ");
  int worst = 0, unrecovered = 0;
  for (const auto& r : ev.recovery) {
    worst = std::max(worst, r.frames_to_recover);
    unrecovered += r.recovered ? 0 : 1;
  }
  o << "\n  },\n  \"recovery\": {\"returns\": " << ev.recovery.size()
    << ", \"frames_lost_after_return\": " << ev.frames_lost_after_return << ", \"max_frames_to_recover\": " << worst
    << ", \"unrecovered\": " << unrecovered << ", \"episodes\": [";
  for (size_t i = 0; i < ev.recovery.size(); ++i) {
    const auto& r = ev.recovery[i];
    o << (i ? ", " : "") << "{\"returned_at\": " << r.returned_at << ", \"frames_to_recover\": " << r.frames_to_recover
      << ", \"recovered\": " << (r.recovered ? "true" : "false") << "}";
  }
  o << "]},\n  \"thresholds\": {\"out_of_view_below\": " << num(ev.options.out_of_view_below)
    << ", \"off_track_endpoint_um\": " << num(ev.options.off_track_endpoint_um)
    << ", \"off_track_in_plane\": " << (ev.options.off_track_in_plane ? "true" : "false") << "}\n}\n";
  return o.str();
}

void write_frame_errors(const std::filesystem::path& file, const Evaluation& ev) {
  std::ostringstream out;
  out << "frame,in_view,out_of_view,status,lost,position_um,inplane_um,depth_um,orientation_deg,rx_err_deg,"
         "ry_err_deg,rz_err_deg,joint_deg,endpoint_um,symmetry_k,tilt_mirror,tilt_branch,endpoint_inplane_um\n";
  for (const auto& f : ev.per_frame) {
    out << f.frame << "," << num(f.in_view) << "," << (f.out_of_view ? 1 : 0) << "," << f.status << ","
        << (f.lost ? 1 : 0);
    if (f.lost) {
      out << ",,,,,,,,,,,,,\n";
      continue;
    }
    const auto& e = f.errors;
    out << "," << num(e.position_um) << "," << num(e.inplane_um) << "," << num(e.depth_um) << ","
        << num(e.orientation_deg) << "," << num(e.axis_deg[0]) << "," << num(e.axis_deg[1]) << ","
        << num(e.axis_deg[2]) << "," << num(e.joint_deg) << "," << num(e.endpoint_um) << "," << e.symmetry_k << ","
        << (e.tilt_mirror ? 1 : 0) << "," << (e.tilt_branch ? 1 : 0) << "," << num(e.endpoint_inplane_um) << "\n";
  }
  write_text_file(file, out.str());
}

}  // namespace gtrack
