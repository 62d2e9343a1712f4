// Per-frame results as files: estimates.csv, estimates.jsonl, summary.json.
//
// Rows are appended and flushed as soon as a frame is done, so a run that is
// interrupted keeps every finished frame in well-formed files.
// estimates.csv: frame,x_mm,y_mm,z_mm,rx_deg,ry_deg,rz_deg,q1_deg,...,qF_deg,cost,status,time_s,ms
// estimates.jsonl: one object per frame with the same fields plus the cost
// terms D, K, S, the stimulus value, |O| and per-stage times.
#pragma once

#include <filesystem>
#include <fstream>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "gtrack/export.hpp"
#include "gtrack/tracker.hpp"

namespace gtrack {

class GTRACK_API ResultWriter {
 public:
  // Creates the folder if needed; InputError if it cannot be written.
  // append: continue the files already there (after resume_results).
  ResultWriter(const std::filesystem::path& out_dir, int fingers, bool append = false);
  void write(const Estimate& estimate);
  // Puts the rows written so far on the disk (fsync), not only in the
  // system's cache: they then survive a power loss.
  void sync();
  void close();

 private:
  std::ofstream csv_, jsonl_;
  std::filesystem::path dir_;
};

// An exclusive lock on an output folder (flock on DIR/.gtrack_lock, which
// holds the owner's pid), held while a run writes there: a second process
// writing into the folder is refused with an InputError naming that pid.
// The thread that holds it takes it again freely (track_sequence() and
// two_pass() each take it; a caller that holds one across both keeps
// another run out between them); another thread is refused as another
// process is. It goes with the process, however it
// ends. A file system without locks (some network mounts) runs without one.
class GTRACK_API OutputLock {
 public:
  explicit OutputLock(const std::filesystem::path& out_dir);
  ~OutputLock();
  OutputLock(const OutputLock&) = delete;
  OutputLock& operator=(const OutputLock&) = delete;

 private:
  std::string key_;
};

// A JSON string literal of free text (a decoder's message, a file name):
// quotes and backslashes escaped, control bytes and bytes that are not
// UTF-8 (a Latin-1 file name) as \u00XX.
GTRACK_API std::string json_string(const std::string& text);

// One line of estimates.jsonl (without its newline).
GTRACK_API std::string estimate_json(const Estimate& estimate);

// A configuration as estimates.csv and estimates.jsonl write it: x, y, z
// to 1e-6 mm, angles to 1e-4 deg, comma-separated ("null" for a value
// that is not finite). Two estimates that give the same text are the same
// estimate in the files.
GTRACK_API std::string pose_text(const Eigen::VectorXd& h);

// The text of the value `key` has among a JSON line's fields (`"key":` up
// to the next ',' or '}'), as estimates.jsonl writes numbers, null, true,
// false and plain strings; nullopt when there is no such key.
GTRACK_API std::optional<std::string_view> json_field(std::string_view text, std::string_view key);

// The estimates of a run as its estimates.jsonl holds them: frame, time_s,
// configuration (NaN for null), status and stimulus reading, which is what
// two_pass() takes of a forward run (--two-pass --resume: the forward run
// done in parts). The other fields are left at their defaults. InputError
// "file:line: ..." for a line that is not one of gtrack's rows, or a
// configuration of another gripper.
GTRACK_API std::vector<Estimate> read_estimates(const std::filesystem::path& out_dir, int fingers);

GTRACK_API void write_summary(const std::filesystem::path& file, const TrackSummary& summary);

// Removes the frame images (NNNNNN.png) in dir, as gtrack writes them for
// sequences and masks; returns how many. Other files are left alone.
GTRACK_API int remove_frame_images(const std::filesystem::path& dir);

// A fresh run into a folder that holds an earlier one: removes the files of
// that run this one might not rewrite (overlay videos, masks, the tracker
// state, the summary, a --two-pass run's backward/ and two_pass/ tables), so
// nothing of the two is mixed. Returns how many were removed.
GTRACK_API int clear_previous_run(const std::filesystem::path& out_dir);

// Whether out_dir's estimates.csv holds a row after its header (a run that
// tracked at least one frame, its last row perhaps cut short).
GTRACK_API bool holds_estimates(const std::filesystem::path& out_dir);

// Prepares out_dir for a resumed run: keeps the rows of estimates.csv and
// estimates.jsonl up to frame `last` (a row cut short by an interruption, or
// written after the state was, is dropped) and returns the frame indices
// kept, in order. InputError when estimates.csv is missing or was written
// for another number of fingers.
GTRACK_API std::vector<int> resume_results(const std::filesystem::path& out_dir, int fingers, int last);

}  // namespace gtrack
