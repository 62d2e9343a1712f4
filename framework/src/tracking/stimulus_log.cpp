// Parsing and interpolating the stimulus CSV (frame,value or time_s,value).
#include "gtrack/stimulus_log.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <vector>

#include <fmt/format.h>

#include "gtrack/error.hpp"
#include "gtrack/log.hpp"
#include "gtrack/text_file.hpp"

namespace gtrack {

namespace {

std::string trim(std::string s) {
  const auto not_space = [](unsigned char c) { return !std::isspace(c); };
  s.erase(s.begin(), std::find_if(s.begin(), s.end(), not_space));
  s.erase(std::find_if(s.rbegin(), s.rend(), not_space).base(), s.end());
  return s;
}

bool parse_number(const std::string& text, double& out) {
  const std::string t = trim(text);
  if (t.empty()) return false;
  auto [end, ec] = std::from_chars(t.data(), t.data() + t.size(), out);
  return ec == std::errc() && end == t.data() + t.size() && std::isfinite(out);
}

// The fields of a line, trimmed.
std::vector<std::string> fields_of(const std::string& line) {
  std::vector<std::string> out;
  size_t start = 0;
  for (size_t comma; (comma = line.find(',', start)) != std::string::npos; start = comma + 1) {
    out.push_back(trim(line.substr(start, comma - start)));
  }
  out.push_back(trim(line.substr(start)));
  return out;
}

// A field as it is quoted in a message: short, printable ASCII.
std::string field_text(const std::string& text) { return "'" + shown(text, 60, true) + "'"; }

// A row of a stimulus log is a few dozen characters.
constexpr size_t kMaxLine = 4096;

}  // namespace

StimulusLog StimulusLog::load(const std::filesystem::path& file, ReadingCheck check, const std::string& column,
                              HeaderCheck header_check, std::optional<std::uintmax_t> first_bytes) {
  std::error_code ec;
  if (std::filesystem::is_directory(file, ec)) {
    throw InputError(file.string() + ": is a folder; expected a stimulus log (a CSV file)");
  }
  std::ifstream whole(file, std::ios::binary);
  if (!whole) throw InputError(file.string() + ": cannot open the stimulus log");
  std::istringstream first;
  if (first_bytes) {
    const auto size = std::filesystem::file_size(file, ec);
    if (ec || size < *first_bytes) {
      throw InputError(fmt::format("{}: holds fewer than the {} bytes to be read", file.string(), *first_bytes));
    }
    std::string bytes(static_cast<size_t>(*first_bytes), '\0');
    whole.read(bytes.data(), static_cast<std::streamsize>(bytes.size()));
    if (static_cast<std::uintmax_t>(whole.gcount()) != *first_bytes) {
      throw InputError(fmt::format("{}: holds fewer than the {} bytes to be read", file.string(), *first_bytes));
    }
    first.str(std::move(bytes));
  }
  std::istream& in = first_bytes ? static_cast<std::istream&>(first) : whole;
  std::string text, line;
  for (int n = 1; read_bounded_line(in, line, kMaxLine, file.string(), n, "'frame,value' or 'time_s,value' rows"); ++n) {
    text += line;
    text += '\n';
  }
  return parse(text, file.string(), std::move(check), column, std::move(header_check));
}

StimulusLog StimulusLog::parse(const std::string& text, const std::string& source, ReadingCheck check,
                               const std::string& column, HeaderCheck header_check) {
  StimulusLog log;
  log.source_ = source;
  log.check_ = std::move(check);
  log.header_check_ = std::move(header_check);
  log.column_ = column;
  std::istringstream in(text);
  std::string line;
  // A malformed row stops the run, but the rows after it are read on, so
  // that the error lists every malformed one (a glitchy hour-long log is
  // mended in one go, not one row a run).
  std::string first_error;
  std::vector<int> more, refused;
  while (std::getline(in, line)) {
    const bool had_header = log.header_;
    try {
      log.take_line(std::move(line));
    } catch (const InputError& e) {
      if (!had_header || (log.refused_ && first_error.empty())) throw;
      if (first_error.empty()) {
        first_error = e.what();
      } else {
        (log.refused_ ? refused : more).push_back(log.lines_);
      }
      log.refused_ = false;
    }
  }
  if (!first_error.empty()) {
    const auto listed = [](const std::vector<int>& rows) {
      std::string lines = rows.size() == 1 ? "line " : "lines ";
      for (size_t i = 0; i < std::min<size_t>(rows.size(), 10); ++i) lines += (i ? ", " : "") + std::to_string(rows[i]);
      return lines + (rows.size() > 10 ? ", ..." : "");
    };
    std::string also;
    if (!more.empty()) {
      also += "; " + std::to_string(more.size()) + " more row" + (more.size() == 1 ? " is" : "s are") +
              " malformed too (" + listed(more) + ")";
    }
    if (!refused.empty()) also += "; the stimulus plugin refuses the reading of " + listed(refused);
    throw InputError(first_error + also);
  }
  if (!log.header_) {
    throw InputError(source + ": empty stimulus log; expected the header 'frame,value' or 'time_s,value'");
  }
  if (log.keys_.empty()) throw InputError(source + ": the stimulus log has a header but no rows");
  return log;
}

void StimulusLog::take_line(std::string line) {
  const int lineno = ++lines_;
  if (!line.empty() && line.back() == '\r') line.pop_back();
  if (lineno == 1 && line.size() >= 3 && line.compare(0, 3, "\xEF\xBB\xBF") == 0) line.erase(0, 3);
  const std::string t = trim(line);
  if (t.empty() || t[0] == '#') return;
  const std::vector<std::string> fields = fields_of(t);
  const std::string where = source_ + ":" + std::to_string(lineno) + ": ";
  if (!header_) {
    // The key, then one column of readings or several named ones (a
    // logger's channels), of which `column_` is taken.
    const bool keyed = fields.size() >= 2 && (fields[0] == "frame" || fields[0] == "time_s");
    const bool named = std::all_of(fields.begin() + std::min<size_t>(1, fields.size()), fields.end(),
                                   [](const std::string& f) { return !f.empty(); });
    if (!keyed || !named) {
      throw InputError(where + "expected the header 'frame,value' or 'time_s,value' (or the key and named columns, " +
                       "'time_s,B_mT,T_C'), got " + field_text(t));
    }
    std::string names;
    for (size_t i = 1; i < fields.size(); ++i) names += (i > 1 ? ", " : "") + field_text(fields[i]);
    if (column_.empty() && fields.size() > 2) {
      throw InputError(where + "the log has the columns " + names +
                       "; say which holds the readings (--stimulus-column NAME)");
    }
    const auto at = column_.empty() ? fields.begin() + 1 : std::find(fields.begin() + 1, fields.end(), column_);
    if (at == fields.end()) throw InputError(where + "no column " + field_text(column_) + "; the log has " + names);
    if (!column_.empty() && std::find(at + 1, fields.end(), column_) != fields.end()) {
      throw InputError(where + "the column " + field_text(column_) + " appears twice (" + names +
                       "); expected one column of that name, the readings'");
    }
    key_ = fields[0] == "frame" ? Key::Frame : Key::Time;
    value_field_ = static_cast<size_t>(at - fields.begin());
    field_count_ = fields.size();
    value_name_ = *at;
    if (header_check_) header_check_(*this);  // refused as a whole: as a bad header
    header_ = true;
    return;
  }
  const char* key_name = key_ == Key::Frame ? "a frame index" : "a time in seconds";
  double k = 0, v = 0;
  if (fields.size() != field_count_) {
    const std::string key_field = key_ == Key::Frame ? "frame" : "time_s";
    throw InputError(where + "expected " +
                     (field_count_ == 2 ? "two fields '<" + key_field + ">,<value>'"
                                        : std::to_string(field_count_) + " fields, as the header has") +
                     ", got " + field_text(t));
  }
  const std::string& a = fields[0];
  const std::string& b = fields[value_field_];
  if (!parse_number(a, k) || (key_ == Key::Frame && (k < 0 || k != std::floor(k) || k > 2147483647.0))) {
    throw InputError(where + "expected " +
                     (key_ == Key::Frame ? std::string("a frame index (a whole number from 0 to 2147483647)")
                                         : std::string(key_name)) +
                     " in the first field, got " + field_text(a));
  }
  if (!parse_number(b, v)) {
    throw InputError(where + "expected a number in the " + (value_name_ == "value" ? "value" : field_text(value_name_)) +
                     " field, got " + field_text(b));
  }
  // No sensor of a lab reads past this in any unit; larger values are a
  // unit or logging mistake, and overflow the interpolation.
  if (std::abs(v) > 1e9) throw InputError(where + "expected a reading of magnitude up to 1e9, got " + field_text(b));
  if (!keys_.empty() && !(k > keys_.back())) {
    throw InputError(where + "expected " + key_name + " greater than the previous row's, got " + field_text(a));
  }
  if (check_) {
    try {
      check_(v, key_, k);
    } catch (const std::exception& e) {
      refused_ = true;
      throw InputError(where + e.what());
    }
  }
  keys_.push_back(k);
  values_.push_back(v);
}

StimulusLog StimulusLog::follow(const std::filesystem::path& file, ReadingCheck check, const std::string& column,
                                HeaderCheck header_check) {
  StimulusLog log;
  log.source_ = file.string();
  log.check_ = std::move(check);
  log.header_check_ = std::move(header_check);
  log.column_ = column;
  log.followed_ = file;
  std::ifstream probe(file, std::ios::binary);
  if (!probe) throw InputError(file.string() + ": cannot open the stimulus log");
  log.poll();
  return log;
}

bool StimulusLog::poll() {
  if (followed_.empty()) return false;
  std::ifstream in(followed_, std::ios::binary);
  if (!in) {
    // Moved away for a moment (a logger that replaces its file), or gone:
    // the readings so far are kept, and the frames hold the last one.
    if (!gone_) {
      logger().warn("{}: the followed stimulus log is gone; frames hold its last reading until it is back", source_);
      gone_ = true;
    }
    return false;
  }
  if (gone_) {
    logger().info("{}: the followed stimulus log is back", source_);
    gone_ = false;
  }
  in.seekg(0, std::ios::end);
  const std::streamoff size = in.tellg();
  if (size < read_to_) {
    throw InputError(source_ + ": the stimulus log shrank while it was followed (from " + std::to_string(read_to_) +
                     " to " + std::to_string(size) + " bytes)");
  }
  // Another file in its place (a logger that writes a copy and renames it
  // over the log) goes on from the same byte only if it still holds the rows
  // read so far: a new log, started afresh, is refused as a shrunk one is.
  if (!tail_.empty()) {
    std::string held(tail_.size(), '\0');
    in.seekg(read_to_ - static_cast<std::streamoff>(tail_.size()));
    in.read(held.data(), static_cast<std::streamsize>(held.size()));
    if (in.gcount() != static_cast<std::streamsize>(held.size()) || held != tail_) {
      throw InputError(source_ + ": was replaced while followed by a file that does not hold the rows read so far "
                       "(a new log in place of the old one); a followed log may only grow");
    }
    in.clear();
  }
  if (size == read_to_) return false;
  in.seekg(read_to_);
  std::string fresh(static_cast<size_t>(size - read_to_), '\0');
  in.read(fresh.data(), static_cast<std::streamsize>(fresh.size()));
  fresh.resize(static_cast<size_t>(in.gcount()));
  // Whole lines only: the logger may be half way through the last one.
  const size_t end = fresh.rfind('\n');
  if (end == std::string::npos) return false;
  const size_t rows_before = keys_.size();
  size_t start = 0;
  while (start <= end) {
    const size_t nl = fresh.find('\n', start);
    try {
      refused_ = false;
      take_line(fresh.substr(start, nl - start));
    } catch (const InputError& e) {
      // A live run goes on past a row the logger garbled (a glitch, a
      // clock that stepped back), or a reading the plugin refuses after it
      // took others (a sensor's spike): said, left out, the frames holding
      // the last reading. A header that is not one, or a refused first
      // reading (a log in another unit), still stops it.
      if (!header_ || (refused_ && keys_.empty())) throw;
      logger().warn("{}; the row is left out, and the frames hold the last reading", e.what());
      ++skipped_rows_;
    }
    start = nl + 1;
  }
  read_to_ += static_cast<std::streamoff>(end + 1);
  tail_ = (tail_ + fresh.substr(0, end + 1));
  if (tail_.size() > 256) tail_.erase(0, tail_.size() - 256);
  if (keys_.size() > rows_before) {
    const auto now = std::chrono::steady_clock::now();
    if (rows_before > 0) {
      row_gaps_s_.push_back(std::chrono::duration<double>(now - latest_at_).count());
      if (row_gaps_s_.size() > 15) row_gaps_s_.erase(row_gaps_s_.begin());
    }
    latest_at_ = now;
  }
  return keys_.size() > rows_before;
}

std::string StimulusLog::shift_note() const {
  return shift_s_ != 0 ? fmt::format(" (its time_s less --stimulus-offset {})", shift_s_) : "";
}

void StimulusLog::shift_time(double seconds) {
  if (!std::isfinite(seconds)) throw InputError(source_ + ": a time offset must be a finite number of seconds");
  if (key_ != Key::Time) {
    throw InputError(source_ + ": is keyed by frame; a time offset (--stimulus-offset) shifts a time_s log");
  }
  if (!followed_.empty()) {
    throw InputError(source_ + ": is followed, each frame taking its last row; a time offset has nothing to shift");
  }
  for (double& k : keys_) k -= seconds;
  shift_s_ += seconds;
}

std::optional<double> StimulusLog::latest() const {
  if (values_.empty()) return std::nullopt;
  return values_.back();
}

std::optional<double> StimulusLog::typical_row_gap_s() const {
  if (row_gaps_s_.empty()) return std::nullopt;
  std::vector<double> gaps = row_gaps_s_;
  std::nth_element(gaps.begin(), gaps.begin() + static_cast<std::ptrdiff_t>(gaps.size() / 2), gaps.end());
  return gaps[gaps.size() / 2];
}

std::optional<double> StimulusLog::latest_age_s() const {
  if (values_.empty() || followed_.empty()) return std::nullopt;
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - latest_at_).count();
}

std::optional<double> StimulusLog::value_at(int frame, double time_s) const {
  if (keys_.empty()) return std::nullopt;
  const double k = key_ == Key::Frame ? static_cast<double>(frame) : time_s;
  // A small tolerance keeps time keys written with rounding inside the log.
  const double eps = key_ == Key::Frame ? 0.0 : 1e-9;
  if (k < keys_.front() - eps || k > keys_.back() + eps) return std::nullopt;
  const auto it = std::lower_bound(keys_.begin(), keys_.end(), k);
  if (it == keys_.end()) return values_.back();
  const size_t i = static_cast<size_t>(it - keys_.begin());
  if (*it == k || i == 0) return values_[i];
  const double a = (k - keys_[i - 1]) / (keys_[i] - keys_[i - 1]);
  // Written as a blend, not a difference, so that huge readings cannot overflow.
  return (1 - a) * values_[i - 1] + a * values_[i];
}

double StimulusLog::nearest(int frame, double time_s) const {
  const double k = key_ == Key::Frame ? static_cast<double>(frame) : time_s;
  if (k <= keys_.front()) return values_.front();
  if (k >= keys_.back()) return values_.back();
  return *value_at(frame, time_s);
}

}  // namespace gtrack
