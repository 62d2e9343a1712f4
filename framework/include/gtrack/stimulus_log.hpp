// The stimulus reading of every frame, from a CSV log.
//
// Two forms, chosen by the header: `frame,value` (one row per frame index;
// frames between rows take the linearly interpolated value) or
// `time_s,value` (interpolated at the frame's time, index / fps). The
// readings' column may have another name (`time_s,B_mT`), and a log of
// several named columns (a logger's channels, `time_s,B_mT,T_C`) is read
// from the one `column` names (required then; an error lists them). Rows must
// be increasing in the key column. A malformed row is an InputError
// "file:line: expected <what>, got '<text>'", which lists the lines of the
// other malformed rows after it (parse() and load()). A frame before the first or
// after the last row is outside the log: value_at() returns nullopt and the
// tracker warns once and holds the nearest reading.
//
// A ReadingCheck sees each row's reading as it is read, with the row's key
// (its frame index or time_s, as the header says), and throws for one it
// refuses (a stimulus plugin's update() given a temperature in kelvin, or
// a change too fast for its rate limit); the error is then
// "file:line: <its message>". A HeaderCheck sees the log once its header
// is read, before any row (value_name() is known then), and throws for a
// log it refuses as a whole (a readings' column in another unit).
#pragma once

#include <chrono>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <ios>
#include <optional>
#include <string>
#include <vector>

#include "gtrack/export.hpp"

namespace gtrack {

class GTRACK_API StimulusLog {
 public:
  enum class Key { Frame, Time };

  using ReadingCheck = std::function<void(double value, Key key, double at)>;
  using HeaderCheck = std::function<void(const StimulusLog& log)>;

  // `first_bytes`: only that many bytes of the file are read (a log that
  // has grown since a run being resumed read it, as that run read it).
  static StimulusLog load(const std::filesystem::path& file, ReadingCheck check = {},
                          const std::string& column = "", HeaderCheck header_check = {},
                          std::optional<std::uintmax_t> first_bytes = std::nullopt);
  static StimulusLog parse(const std::string& text, const std::string& source = "<string>",
                           ReadingCheck check = {}, const std::string& column = "", HeaderCheck header_check = {});
  // A log still being written (a live run): poll() takes the rows appended
  // since the last call, whole lines only, with the same checks as parse()
  // (errors name the file and line); true when rows were added. The file may
  // be empty, or hold only its header, at first. A malformed row, one whose
  // key does not increase, or a reading the check refuses once it has taken
  // one, is warned about and left out (counted by skipped_rows()); a bad
  // header, a first reading the check refuses, a file that shrinks or is
  // replaced by one without the rows read so far throw.
  static StimulusLog follow(const std::filesystem::path& file, ReadingCheck check = {},
                            const std::string& column = "", HeaderCheck header_check = {});
  bool poll();
  // The last row's reading; nullopt while there is none.
  std::optional<double> latest() const;
  // follow(): seconds since the last row was read (poll() that took it),
  // on this machine's steady clock; nullopt while there is none.
  std::optional<double> latest_age_s() const;
  // follow(): the median time between the polls that took new rows (of the
  // last 15): how often the logger writes; nullopt before two have.
  std::optional<double> typical_row_gap_s() const;
  // follow(): the rows left out, malformed or refused.
  int skipped_rows() const { return skipped_rows_; }

  Key key() const { return key_; }
  // A time_s log on another clock: `seconds` (its time at the recording's
  // first frame) subtracted from every row's key. Throws InputError for a
  // log keyed by frame, or one still followed.
  void shift_time(double seconds);
  double time_shift() const { return shift_s_; }
  // How a message shows the keys once shift_time() moved them: " (its
  // time_s less --stimulus-offset S)", else "".
  std::string shift_note() const;
  // The reading for a frame (index and time); nullopt outside the log.
  std::optional<double> value_at(int frame, double time_s) const;
  // The reading of the nearest row (for frames outside the log); the log
  // must have a row.
  double nearest(int frame, double time_s) const;
  size_t rows() const { return keys_.size(); }
  // The first and last rows' keys (frame index or time_s); rows() > 0.
  double first_key() const { return keys_.front(); }
  double last_key() const { return keys_.back(); }
  const std::string& source() const { return source_; }
  // The readings' column as the header names it ("value", "B_mT"); empty
  // before a followed log's header is read.
  const std::string& value_name() const { return value_name_; }

 private:
  void take_line(std::string line);

  Key key_ = Key::Frame;
  std::string column_;       // the readings' column asked for ("": the only one)
  std::string value_name_;   // the readings' column, as the header names it
  size_t value_field_ = 1;   // its place in a row
  size_t field_count_ = 2;   // the fields of a row
  std::vector<double> keys_, values_;
  double shift_s_ = 0;                   // shift_time(): seconds taken from the keys
  std::string source_;
  ReadingCheck check_;
  HeaderCheck header_check_;
  bool header_ = false;
  int lines_ = 0;                        // lines read so far (for error messages)
  std::filesystem::path followed_;       // follow(): the file
  std::streamoff read_to_ = 0;           // follow(): bytes taken (whole lines)
  bool gone_ = false;                    // follow(): the file is missing, and that was said
  bool refused_ = false;                 // the last row was refused by the check (not malformed)
  int skipped_rows_ = 0;                 // follow(): rows left out, malformed or refused
  std::chrono::steady_clock::time_point latest_at_;  // follow(): when the last row was read
  std::vector<double> row_gaps_s_;                   // follow(): the last times between rows read
  // follow(): the bytes just before read_to_, which the file (or one put in
  // its place) must still hold.
  std::string tail_;
};

}  // namespace gtrack
