// Reading and writing pose tables (ground truth and estimates).
#include "gtrack/sequence_io.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>

#include "gtrack/error.hpp"
#include "gtrack/parameter_space.hpp"
#include "gtrack/text_file.hpp"

namespace gtrack {

namespace {

std::vector<std::string> split_csv(const std::string& line) {
  std::vector<std::string> out;
  std::string cell;
  std::istringstream in(line);
  while (std::getline(in, cell, ',')) {
    while (!cell.empty() && (cell.back() == '\r' || cell.back() == ' ')) cell.pop_back();
    while (!cell.empty() && cell.front() == ' ') cell.erase(cell.begin());
    out.push_back(cell);
  }
  if (!line.empty() && line.back() == ',') out.emplace_back();
  return out;
}

bool parse_number(const std::string& s, double& v) {
  // gtrack's own tables write a value that is no number as "null" (as its
  // JSON lines do); other tools write "nan".
  if (s == "nan" || s == "NaN" || s == "null") {
    v = std::nan("");
    return true;
  }
  auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
  return !s.empty() && ec == std::errc() && end == s.data() + s.size();
}

// A table's line: a device or a file that is no table (/dev/zero, a video
// given by mistake) is one line of error.
bool table_line(std::istream& in, std::string& line, const std::filesystem::path& file, int line_no) {
  return read_bounded_line(in, line, 1 << 16, file.string(), line_no, "a CSV pose table");
}

}  // namespace

constexpr double kMaxPoseCell = 1e6;

// A truth must be finite in every pose and joint cell; an estimate's lost
// frame may be null.
static PoseTable read_table(const std::filesystem::path& file, bool finite) {
  std::error_code ec;
  if (std::filesystem::is_directory(file, ec)) throw InputError(file.string() + ": is a folder; expected a pose table");
  std::ifstream in(file);
  if (!in) throw InputError(file.string() + ": cannot open");
  std::string line;
  if (!table_line(in, line, file, 1)) throw InputError(file.string() + ":1: empty file, expected a header line");
  if (line.compare(0, 3, "\xEF\xBB\xBF") == 0) line.erase(0, 3);  // a UTF-8 byte-order mark
  const auto header = split_csv(line);
  std::map<std::string, int> col;
  for (int i = 0; i < static_cast<int>(header.size()); ++i) {
    if (!col.emplace(header[i], i).second) {
      throw InputError(file.string() + ":1: column '" + shown(header[i], 60) + "' appears twice (columns " +
                       std::to_string(col[header[i]] + 1) + " and " + std::to_string(i + 1) + ")");
    }
  }
  // A tracker's output read as the truth (the two files given the other way round).
  if (finite && col.count("status")) {
    throw InputError(file.string() +
                     ":1: has the tracker's 'status' column; expected a ground truth (are the truth and the "
                     "estimates given the other way round?)");
  }

  PoseTable table;
  std::vector<std::string> names = {"frame"};
  for (int d = 0; d < kPoseDims; ++d) names.push_back(parameter_name(d));
  for (const auto& n : names) {
    if (!col.count(n)) throw InputError(file.string() + ":1: missing column '" + n + "'");
  }
  while (col.count(joint_name(table.fingers + 1))) ++table.fingers;
  if (table.fingers == 0) throw InputError(file.string() + ":1: no joint columns (q1_deg, q2_deg, ...)");
  for (int f = 0; f < table.fingers; ++f) names.push_back(joint_name(f + 1));
  std::vector<int> idx;
  for (const auto& n : names) idx.push_back(col[n]);
  const int status_col = col.count("status") ? col["status"] : -1;
  std::vector<int> extra_idx;
  for (int i = 0; i < static_cast<int>(header.size()); ++i) {
    if (std::find(idx.begin(), idx.end(), i) != idx.end() || i == status_col) continue;
    table.extra_columns.push_back(header[i]);
    extra_idx.push_back(i);
  }

  int line_no = 1;
  std::map<int, int> first_line;  // frame -> the line it is on
  while (table_line(in, line, file, line_no + 1)) {
    ++line_no;
    if (line.empty() || line == "\r") continue;
    const auto cells = split_csv(line);
    const auto where = file.string() + ":" + std::to_string(line_no) + ": ";
    if (cells.size() != header.size()) {
      throw InputError(where + "expected " + std::to_string(header.size()) + " columns, got " +
                       std::to_string(cells.size()));
    }
    PoseRow row;
    double v = 0;
    if (!parse_number(cells[idx[0]], v) || v != std::floor(v) || v < 0 || v > 2147483647.0) {
      throw InputError(where + "expected a frame index (a whole number from 0), got '" + shown(cells[idx[0]], 60) +
                       "'");
    }
    row.frame = static_cast<int>(v);
    row.h.resize(kPoseDims + table.fingers);
    for (int d = 0; d < row.h.size(); ++d) {
      if (!parse_number(cells[idx[d + 1]], row.h[d])) {
        throw InputError(where + "expected a number for '" + names[d + 1] + "', got " +
                         (cells[idx[d + 1]].empty() ? std::string("an empty cell (a lost frame's cells hold nan)")
                                                    : "'" + shown(cells[idx[d + 1]], 60) + "'"));
      }
      if (finite && !std::isfinite(row.h[d])) {
        throw InputError(where + "expected a finite number for '" + names[d + 1] + "' in a ground truth (frame " +
                         std::to_string(row.frame) + ")");
      }
      // A kilometre or a thousand turns is no pose of a micro-gripper, and
      // larger values overflow the error figures.
      if (std::abs(row.h[d]) > kMaxPoseCell) {
        throw InputError(where + "'" + names[d + 1] + "' = " + shown(cells[idx[d + 1]], 32) +
                         " is not a plausible pose value (expected a magnitude up to 1e6 " +
                         (d < 3 ? "mm" : "deg") + ")");
      }
    }
    if (status_col >= 0) {
      row.status = cells[status_col];
      if (row.status != "ok" && row.status != "search" && row.status != "lost") {
        throw InputError(where + "expected a status of ok, search or lost, got '" + shown(row.status, 60) + "'");
      }
      // Only a lost frame has no configuration.
      if (row.status != "lost" && !row.h.allFinite()) {
        int d = 0;
        while (std::isfinite(row.h[d])) ++d;
        throw InputError(where + "expected a finite number for '" + names[d + 1] + "' in a row whose status is " +
                         row.status + " (only a lost frame may hold nan)");
      }
    }
    for (size_t e = 0; e < extra_idx.size(); ++e) {
      const std::string& cell = cells[extra_idx[e]];
      if (cell.empty()) continue;
      if (!parse_number(cell, v)) {
        throw InputError(where + "expected a number for '" + table.extra_columns[e] + "', got '" + shown(cell, 60) +
                         "'");
      }
      // The shares of the gripper a ground truth says are seen, in view and hidden.
      const std::string& name = table.extra_columns[e];
      if (finite && (name == "visible" || name == "in_view" || name == "occluded") && !(v >= 0 && v <= 1)) {
        throw InputError(where + "expected a share from 0 to 1 for '" + name + "', got '" + shown(cell, 60) + "'");
      }
      row.extra[name] = v;
    }
    const auto [first, fresh] = first_line.emplace(row.frame, line_no);
    if (!fresh) {
      throw InputError(where + "frame " + std::to_string(row.frame) + " again (first at line " +
                       std::to_string(first->second) + ")");
    }
    table.rows.push_back(std::move(row));
  }
  return table;
}

PoseTable read_pose_table(const std::filesystem::path& file) { return read_table(file, false); }

PoseTable read_truth_table(const std::filesystem::path& file) { return read_table(file, true); }

std::string pose_table_header(int fingers, const std::vector<std::string>& extra) {
  std::string s = "frame";
  for (int d = 0; d < kPoseDims + fingers; ++d) s += "," + parameter_name(d);
  for (const auto& e : extra) s += "," + e;
  return s;
}

std::string pose_table_row(int frame, const Eigen::VectorXd& h, const std::vector<double>& extra) {
  std::string s = std::to_string(frame);
  char buf[64];
  for (int d = 0; d < h.size(); ++d) {
    // Positions in mm need 6 decimals for sub-micrometre truth; angles 5.
    std::snprintf(buf, sizeof buf, d < 3 ? ",%.6f" : ",%.5f", h[d]);
    s += buf;
  }
  for (double e : extra) {
    std::snprintf(buf, sizeof buf, ",%.4f", e);
    s += buf;
  }
  return s;
}

}  // namespace gtrack
