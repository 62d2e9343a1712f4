// Pose tables on disk: ground_truth.csv and estimates.csv.
//
// Both files start with frame,x_mm,y_mm,z_mm,rx_deg,ry_deg,rz_deg and one
// q<f>_deg column per finger; columns are found by their header names, so a
// file may carry more (estimates: cost, status, ms; ground truth: visible,
// in_view, occluded). Numeric extra columns are kept by name, `status` as
// text. A malformed file is an InputError "file:line: what was expected".
#pragma once

#include <Eigen/Core>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include "gtrack/export.hpp"

namespace gtrack {

struct PoseRow {
  int frame = 0;
  Eigen::VectorXd h;   // x,y,z (mm), rx,ry,rz (deg), q1..qF (deg)
  std::string status;  // "" when the file has no status column
  std::map<std::string, double> extra;
};

struct PoseTable {
  int fingers = 0;
  std::vector<std::string> extra_columns;
  std::vector<PoseRow> rows;  // in file order
};

GTRACK_API PoseTable read_pose_table(const std::filesystem::path& file);
// A ground truth: a pose table whose every pose and joint is a finite number
// (an estimate's lost frame may be null; a truth's may not). InputError
// "file:line: ..." naming the first column that is not.
GTRACK_API PoseTable read_truth_table(const std::filesystem::path& file);

// Header of a pose table for `fingers` joints followed by `extra` columns.
GTRACK_API std::string pose_table_header(int fingers, const std::vector<std::string>& extra);
// One row: frame, h with enough digits for sub-micrometre positions, extras.
GTRACK_API std::string pose_table_row(int frame, const Eigen::VectorXd& h, const std::vector<double>& extra);

}  // namespace gtrack
