// estimates.csv / estimates.jsonl rows and summary.json.
#include "gtrack/results.hpp"

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <map>
#include <mutex>
#include <sstream>
#include <thread>

#include "gtrack/error.hpp"
#include "gtrack/log.hpp"
#include "gtrack/parameter_space.hpp"
#include "gtrack/sequence_io.hpp"
#include "gtrack/text_file.hpp"
#include "replace_file.hpp"

namespace gtrack {

namespace fs = std::filesystem;

namespace {

std::string num(double v, const char* fmt) {
  if (!std::isfinite(v)) return "null";
  char buf[64];
  std::snprintf(buf, sizeof buf, fmt, v);
  return buf;
}

// The shortest text that reads back as the same double (22.5 as "22.5",
// 1/30 with its 16 digits): a run's inputs, a frame's time and reading,
// which a resumed --two-pass run reads back and feeds to the tracker again
// exactly as the run had them.
std::string exact(double v) {
  if (!std::isfinite(v)) return "null";
  char buf[64];
  const auto [end, ec] = std::to_chars(buf, buf + sizeof buf, v);
  return ec == std::errc() ? std::string(buf, end) : num(v, "%.17g");
}

// The length of the well-formed UTF-8 sequence at text[i] (1 to 4), or 0.
size_t utf8_length(const std::string& text, size_t i) {
  const auto at = [&](size_t k) { return static_cast<unsigned char>(text[k]); };
  const unsigned char c = at(i);
  const size_t n = c < 0x80 ? 1 : (c >> 5) == 0x6 ? 2 : (c >> 4) == 0xE ? 3 : (c >> 3) == 0x1E ? 4 : 0;
  if (n == 0 || i + n > text.size()) return 0;
  for (size_t k = 1; k < n; ++k) {
    if ((at(i + k) & 0xC0) != 0x80) return 0;
  }
  // Overlong forms, surrogates and code points past U+10FFFF are not UTF-8.
  if ((n == 2 && c < 0xC2) || (n == 3 && c == 0xE0 && at(i + 1) < 0xA0) || (n == 3 && c == 0xED && at(i + 1) >= 0xA0) ||
      (n == 4 && c == 0xF0 && at(i + 1) < 0x90) || (n == 4 && (c > 0xF4 || (c == 0xF4 && at(i + 1) >= 0x90)))) {
    return 0;
  }
  return n;
}

std::ofstream open_for_writing(const fs::path& p, bool append) {
  errno = 0;
  std::ofstream out(p, append ? std::ios::app : std::ios::trunc);
  if (!out) throw InputError(p.string() + ": cannot open for writing (" + write_failure_reason() + ")");
  return out;
}

// The header of estimates.csv: a pose table with the tracker's columns.
std::string csv_header(int fingers) { return pose_table_header(fingers, {"cost", "status", "time_s", "ms"}); }

// Whole lines only: a last line without its newline was cut short.
std::vector<std::string> complete_lines(const fs::path& p) {
  // A day of frames at 30 frames/s is some 800 MB of estimates.jsonl.
  const std::string text = read_text_file(p, std::size_t(4) << 30, "a file of estimates");
  std::vector<std::string> lines;
  size_t start = 0;
  for (size_t nl; (nl = text.find('\n', start)) != std::string::npos; start = nl + 1) {
    lines.push_back(text.substr(start, nl - start));
  }
  return lines;
}

// The frame index a row starts with (csv: "N,", jsonl: {"frame":N,), or -1.
int row_frame(const std::string& line, const std::string& prefix) {
  if (line.compare(0, prefix.size(), prefix) != 0) return -1;
  size_t pos = prefix.size(), end = pos;
  while (end < line.size() && std::isdigit(static_cast<unsigned char>(line[end]))) ++end;
  if (end == pos || end - pos > 9 || end >= line.size() || line[end] != ',') return -1;
  return std::stoi(line.substr(pos, end - pos));
}

// Replaces a file by its lines.
void rewrite(const fs::path& p, const std::vector<std::string>& lines) {
  std::string text;
  for (const auto& l : lines) text += l + '\n';
  detail::replace_file(p, text);
}

}  // namespace

// A JSON string literal of free text (a decoder's message, a file name).
// JSON is UTF-8: a byte that is not (a file name in Latin-1) is written as
// the code point of the same number, \u00XX.
std::string json_string(const std::string& text) {
  std::string s = "\"";
  for (size_t i = 0; i < text.size();) {
    const char c = text[i];
    const size_t n = utf8_length(text, i);
    if (c == '"' || c == '\\') {
      s += '\\';
      s += c;
    } else if (n == 0 || static_cast<unsigned char>(c) < 0x20) {
      char buf[8];
      std::snprintf(buf, sizeof buf, "\\u%04x", static_cast<unsigned>(static_cast<unsigned char>(c)));
      s += buf;
    } else {
      s.append(text, i, n);
      i += n;
      continue;
    }
    ++i;
  }
  return s + "\"";
}

ResultWriter::ResultWriter(const fs::path& out_dir, int fingers, bool append) : dir_(out_dir) {
  std::error_code ec;
  fs::create_directories(out_dir, ec);
  if (ec || !fs::is_directory(out_dir)) {
    throw InputError(out_dir.string() + ": cannot create the output folder (" +
                     (ec ? ec.message() : std::string("not a folder")) + ")");
  }
  csv_ = open_for_writing(out_dir / "estimates.csv", append);
  jsonl_ = open_for_writing(out_dir / "estimates.jsonl", append);
  if (!append) csv_ << csv_header(fingers) << '\n';
  csv_.flush();
  if (!csv_) throw InputError((out_dir / "estimates.csv").string() + ": write failed (" + write_failure_reason() + ")");
}

std::string pose_text(const Eigen::VectorXd& h) {
  std::string text;
  for (Eigen::Index i = 0; i < h.size(); ++i) text += (i ? "," : "") + num(h[i], i < 3 ? "%.6f" : "%.4f");
  return text;
}

void ResultWriter::write(const Estimate& e) {
  std::string row = std::to_string(e.frame) + "," + pose_text(e.hypothesis);
  row += "," + num(e.terms.total, "%.6f") + "," + to_string(e.status) + "," + num(e.time_s, "%.6f") + "," +
         num(e.ms, "%.3f") + "\n";
  csv_ << row;
  csv_.flush();

  jsonl_ << estimate_json(e) << '\n';
  jsonl_.flush();
  if (!csv_ || !jsonl_) {
    throw InputError(dir_.string() + ": writing the estimates failed (" + write_failure_reason() + ")");
  }
}

void ResultWriter::sync() {
  detail::sync_to_disk(dir_ / "estimates.csv");
  detail::sync_to_disk(dir_ / "estimates.jsonl");
}

std::string estimate_json(const Estimate& e) {
  const Eigen::VectorXd& h = e.hypothesis;
  std::string j = "{\"frame\":" + std::to_string(e.frame) + ",\"time_s\":" + exact(e.time_s);
  for (Eigen::Index i = 0; i < h.size(); ++i) {
    j += ",\"" + parameter_name(static_cast<int>(i)) + "\":" + num(h[i], i < 3 ? "%.6f" : "%.4f");
  }
  j += ",\"cost\":" + num(e.terms.total, "%.6f") + ",\"status\":\"" + to_string(e.status) + "\",\"ms\":" +
       num(e.ms, "%.3f");
  j += ",\"D\":" + num(e.terms.dice, "%.6f") + ",\"K\":" + num(e.terms.kinematic, "%.6f") +
       ",\"S\":" + num(e.terms.stimulus, "%.6f") + ",\"T\":" + num(e.terms.temporal, "%.6f") +
       ",\"C\":" + num(e.terms.coherence, "%.6f") +
       ",\"outside_weight\":" + num(e.outside_weight, "%.4f") +
       ",\"outside_allowance\":" + num(e.outside_allowance, "%.1f") +
       ",\"rendered_pixels\":" + std::to_string(e.terms.rendered) +
       ",\"overlap_pixels\":" + std::to_string(e.terms.overlap) + ",\"rim_pixels\":" + std::to_string(e.terms.rim) +
       ",\"redetected\":" +
       (e.redetected ? "true" : "false") + ",\"mirrored\":" + (e.mirrored ? "true" : "false");
  if (e.tilt_margin) j += ",\"tilt_margin\":" + num(*e.tilt_margin, "%.4f");
  j += ",\"unseen_fingers\":[";
  for (std::size_t k = 0; k < e.unseen_fingers.size(); ++k) j += (k ? "," : "") + std::to_string(e.unseen_fingers[k]);
  j += "]";
  j += ",\"stimulus\":" + (e.stimulus ? exact(*e.stimulus) : std::string("null"));
  if (e.stimulus_age_s) j += ",\"stimulus_age_s\":" + num(*e.stimulus_age_s, "%.3f");
  j += ",\"observed_pixels\":" + std::to_string(e.observed_pixels) + ",\"evaluations\":" +
       std::to_string(e.evaluations);
  if (const auto& r = e.reference_terms) {
    j += ",\"reference\":{\"cost\":" + num(r->total, "%.6f") + ",\"D\":" + num(r->dice, "%.6f") +
         ",\"K\":" + num(r->kinematic, "%.6f") + ",\"S\":" + num(r->stimulus, "%.6f") +
         ",\"T\":" + num(r->temporal, "%.6f") + ",\"C\":" + num(r->coherence, "%.6f") +
         ",\"rendered_pixels\":" + std::to_string(r->rendered) +
         ",\"overlap_pixels\":" + std::to_string(r->overlap) + ",\"rim_pixels\":" + std::to_string(r->rim) + "}";
  }
  if (!e.two_pass_source.empty()) j += ",\"two_pass\":\"" + e.two_pass_source + "\"";
  if (!e.image.empty()) j += ",\"image\":" + json_string(e.image);
  if (e.written_unix_s > 0) j += ",\"written_unix_s\":" + num(e.written_unix_s, "%.6f");
  if (e.read_unix_s > 0) j += ",\"read_unix_s\":" + num(e.read_unix_s, "%.6f");
  if (e.unix_time_s > 0) j += ",\"unix_time_s\":" + num(e.unix_time_s, "%.6f");
  j += ",\"segment_ms\":" + num(e.times.segment_ms, "%.3f") + ",\"pso_ms\":" + num(e.times.pso_ms, "%.3f") +
       ",\"io_ms\":" + num(e.times.io_ms, "%.3f") + "}";
  return j;
}

std::optional<std::string_view> json_field(std::string_view text, std::string_view key) {
  const std::string quoted = "\"" + std::string(key) + "\":";
  const auto at = text.find(quoted);
  if (at == std::string_view::npos) return std::nullopt;
  const std::string_view value = text.substr(at + quoted.size());
  return value.substr(0, value.find_first_of(",}"));
}

std::vector<Estimate> read_estimates(const fs::path& out_dir, int fingers) {
  const fs::path file = out_dir / "estimates.jsonl";
  std::ifstream in(file);
  if (!in) throw InputError(file.string() + ": cannot open");
  std::vector<Estimate> out;
  std::string line;
  for (int n = 1; read_bounded_line(in, line, 1 << 20, file.string(), n, "estimates.jsonl's JSON lines"); ++n) {
    if (line.empty()) continue;
    const std::string where = file.string() + ":" + std::to_string(n) + ": ";
    // A key of the row's own (a --score-truth "reference" object comes after them).
    const std::string own = line.substr(0, line.find(",\"reference\":{"));
    const auto value_at = [&](const std::string& key) { return json_field(own, key); };
    const auto number = [&](const std::string& key, bool may_be_null) {
      const auto v = value_at(key);
      if (!v) throw InputError(where + "no '" + key + "'; expected a row of gtrack's estimates.jsonl");
      if (may_be_null && *v == "null") return std::numeric_limits<double>::quiet_NaN();
      const std::string text(*v);
      char* end = nullptr;
      const double x = std::strtod(text.c_str(), &end);
      if (text.empty() || end != text.c_str() + text.size() || !std::isfinite(x)) {
        throw InputError(where + "'" + key + "' is '" + shown(text, 40) + "'; expected a number");
      }
      return x;
    };
    Estimate e;
    const double frame = number("frame", false);
    if (frame < 0 || frame > std::numeric_limits<int>::max() || frame != std::floor(frame)) {
      throw InputError(where + "'frame' is not a frame index");
    }
    e.frame = static_cast<int>(frame);
    if (!out.empty() && e.frame <= out.back().frame) {
      throw InputError(where + "frame " + std::to_string(e.frame) + " after frame " + std::to_string(out.back().frame) +
                       "; expected the frames in increasing order");
    }
    e.time_s = number("time_s", false);
    e.hypothesis.resize(kPoseDims + fingers);
    for (int i = 0; i < kPoseDims + fingers; ++i) e.hypothesis[i] = number(parameter_name(i), true);
    if (value_at(parameter_name(kPoseDims + fingers))) {
      throw InputError(where + "has a joint '" + parameter_name(kPoseDims + fingers) + "'; expected a gripper of " +
                       std::to_string(fingers) + " fingers");
    }
    const auto status = value_at("status");
    const std::string text = status ? std::string(*status) : std::string();
    if (text == "\"ok\"") {
      e.status = TrackStatus::Tracked;
    } else if (text == "\"search\"") {
      e.status = TrackStatus::Search;
    } else if (text == "\"lost\"") {
      e.status = TrackStatus::Lost;
    } else {
      throw InputError(where + "'status' is '" + shown(text, 40) + "'; expected \"ok\", \"search\" or \"lost\"");
    }
    const double stimulus = number("stimulus", true);
    if (std::isfinite(stimulus)) e.stimulus = stimulus;
    out.push_back(std::move(e));
  }
  return out;
}

void ResultWriter::close() {
  csv_.close();
  jsonl_.close();
}

void write_summary(const fs::path& file, const TrackSummary& s) {
  std::ostringstream out;
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
      << "  \"overlay\": " << json_string(s.overlay_file.filename().string()) << ",\n"
      << "  \"resumed_after_frame\": " << (s.resumed_after >= 0 ? std::to_string(s.resumed_after) : "null") << ",\n"
      << "  \"frames_before_resume\": " << s.frames_before << ",\n"
      << "  \"cancelled\": " << (s.cancelled ? "true" : "false") << ",\n"
      << "  \"skipped_frames\": " << s.skipped_frames << ",\n"
      << "  \"skipped_stimulus_rows\": " << s.skipped_stimulus_rows << ",\n"
      << "  \"input_ended_early\": " << (s.input_ended_early.empty() ? "null" : json_string(s.input_ended_early))
      << ",\n"
      << "  \"stopped_by\": " << (s.stopped_by.empty() ? "null" : json_string(s.stopped_by)) << "\n"
      << "}\n";
  // Whole or not at all: a full disk is an error, and an earlier summary
  // stays until the new one is complete.
  detail::replace_file(file, out.str());
}

namespace {

void remove_all_of(const std::vector<fs::path>& files) {
  std::error_code ec;
  for (const auto& p : files) {
    fs::remove(p, ec);
    if (ec) throw InputError(p.string() + ": cannot remove the file of an earlier run (" + ec.message() + ")");
  }
}

}  // namespace

int remove_frame_images(const fs::path& dir) {
  std::error_code ec;
  std::vector<fs::path> found;
  if (!fs::is_directory(dir, ec)) return 0;
  for (const auto& entry : fs::directory_iterator(dir, ec)) {
    const std::string n = entry.path().filename().string();
    if (n.size() == 10 && entry.path().extension() == ".png" &&
        std::all_of(n.begin(), n.begin() + 6, [](char c) { return c >= '0' && c <= '9'; })) {
      found.push_back(entry.path());
    }
  }
  remove_all_of(found);
  return static_cast<int>(found.size());
}

int clear_previous_run(const fs::path& out_dir) {
  std::error_code ec;
  if (!fs::is_directory(out_dir, ec)) return 0;
  std::vector<fs::path> stale;
  for (const auto& entry : fs::directory_iterator(out_dir, ec)) {
    const fs::path& p = entry.path();
    const std::string n = p.filename().string();
    const bool overlay = (n.rfind("overlay.", 0) == 0 || n.rfind("overlay_from_", 0) == 0) &&
                         (p.extension() == ".mp4" || p.extension() == ".avi");
    if (overlay || n == "tracker_state.txt" || n == "summary.json") stale.push_back(p);
  }
  // An earlier --two-pass run's backward track and two-pass table.
  for (const char* sub : {"backward", "two_pass"}) {
    for (const char* file : {"estimates.csv", "estimates.jsonl"}) {
      if (fs::exists(out_dir / sub / file, ec)) stale.push_back(out_dir / sub / file);
    }
  }
  remove_all_of(stale);
  return static_cast<int>(stale.size()) + remove_frame_images(out_dir / "masks");
}

bool holds_estimates(const fs::path& out_dir) {
  std::ifstream in(out_dir / "estimates.csv");
  int lines = 0;
  for (std::string line; lines < 2 && std::getline(in, line);) lines += line.empty() ? 0 : 1;
  return lines > 1;
}

std::vector<int> resume_results(const fs::path& out_dir, int fingers, int last) {
  const fs::path csv = out_dir / "estimates.csv", jsonl = out_dir / "estimates.jsonl";
  if (!fs::exists(csv)) throw InputError(csv.string() + ": missing; there is nothing to resume");
  auto rows = complete_lines(csv);
  if (rows.empty() || rows[0] != csv_header(fingers)) {
    throw InputError(csv.string() + ":1: expected the header '" + csv_header(fingers) +
                     "' (a gripper with " + std::to_string(fingers) + " fingers); cannot resume");
  }
  // The rows up to the state's frame are kept; both files must hold the
  // same frames, or the two would no longer agree once the run goes on.
  const auto rows_until_state = [last](const fs::path& file, const std::vector<std::string>& lines, size_t first,
                                       const std::string& prefix, std::vector<int>& frames) {
    std::vector<std::string> kept(lines.begin(), lines.begin() + static_cast<std::ptrdiff_t>(first));
    for (size_t i = first; i < lines.size(); ++i) {
      const int f = row_frame(lines[i], prefix);
      if (f < 0) {
        const std::string expected = prefix.empty() ? "a frame index" : "'" + prefix + "' and a frame index";
        throw InputError(file.string() + ":" + std::to_string(i + 1) + ": expected a row that starts with " +
                         expected + ", got '" + shown(lines[i], 40) + "'; cannot resume");
      }
      if (f > last) break;
      kept.push_back(lines[i]);
      frames.push_back(f);
    }
    if (frames.empty() || frames.back() != last) {
      throw InputError(file.string() + ": its rows end at frame " +
                       (frames.empty() ? std::string("(none)") : std::to_string(frames.back())) +
                       ", the tracker state at frame " + std::to_string(last) + "; cannot resume");
    }
    return kept;
  };
  std::vector<int> frames, jframes;
  const auto kept = rows_until_state(csv, rows, 1, "", frames);
  if (!fs::exists(jsonl)) throw InputError(jsonl.string() + ": missing, while estimates.csv has rows; cannot resume");
  const auto jkept = rows_until_state(jsonl, complete_lines(jsonl), 0, "{\"frame\":", jframes);
  if (jframes != frames) {
    throw InputError(jsonl.string() + ": holds " + std::to_string(jframes.size()) + " rows up to frame " +
                     std::to_string(last) + ", estimates.csv " + std::to_string(frames.size()) + "; cannot resume");
  }
  rewrite(csv, kept);
  rewrite(jsonl, jkept);
  return frames;
}

namespace {

// The output folders this process holds locked: the lock file's descriptor
// and how many OutputLocks share it.
struct HeldLock {
  int fd = -1;
  int count = 0;
  std::thread::id owner;  // taken again by this thread only: another thread's run is refused
};
std::mutex g_held_mutex;
std::map<std::string, HeldLock> g_held;

}  // namespace

OutputLock::OutputLock(const fs::path& out_dir) {
  std::error_code ec;
  fs::create_directories(out_dir, ec);
  if (ec) throw InputError(out_dir.string() + ": cannot create the output folder (" + ec.message() + ")");
  const fs::path file = out_dir / ".gtrack_lock";
  // flock() conflicts between two descriptors of one process too, so a
  // folder this process holds is counted, not locked again.
  const fs::path canonical = fs::weakly_canonical(file, ec);
  key_ = ec ? fs::absolute(file).lexically_normal().string() : canonical.string();
  // `who`: " (pid N)", or "" when the lock file does not say.
  const auto busy = [&](const std::string& who) {
    return InputError(out_dir.string() + ": another gtrack track run is writing there" + who +
                      "; wait for it to end, or choose another --out");
  };
  const std::lock_guard<std::mutex> guard(g_held_mutex);
  if (HeldLock& held = g_held[key_]; held.count > 0) {
    if (held.owner != std::this_thread::get_id()) {
      throw busy(" (pid " + std::to_string(::getpid()) + ", this process, another thread)");
    }
    ++held.count;
    return;
  }
  const int fd = ::open(file.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
  if (fd < 0) {
    g_held.erase(key_);
    throw InputError(file.string() + ": cannot open (" + std::strerror(errno) + ")");
  }
  const int locked = ::flock(fd, LOCK_EX | LOCK_NB) == 0 ? 0 : errno;
  if (locked == EWOULDBLOCK) {
    char pid[32] = {};
    const ssize_t n = ::pread(fd, pid, sizeof pid - 1, 0);
    ::close(fd);
    g_held.erase(key_);
    throw busy(n > 0 ? " (pid " + std::string(pid, static_cast<size_t>(n)) + ")" : "");
  }
  if (locked != 0) {
    // A file system without locks (some network mounts): nothing to say
    // who else writes there, so the run goes on without one.
    logger().debug("{}: cannot be locked ({})", file.string(), std::strerror(locked));
  }
  const std::string me = std::to_string(::getpid());
  if (::ftruncate(fd, 0) == 0) (void)!::pwrite(fd, me.data(), me.size(), 0);
  g_held[key_] = HeldLock{fd, 1, std::this_thread::get_id()};
}

OutputLock::~OutputLock() {
  const std::lock_guard<std::mutex> guard(g_held_mutex);
  const auto held = g_held.find(key_);
  if (held == g_held.end() || --held->second.count > 0) return;
  ::close(held->second.fd);
  g_held.erase(held);
}

}  // namespace gtrack
