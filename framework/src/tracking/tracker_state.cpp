// tracker_state.txt: writing it after every frame, reading it to resume.
#include "gtrack/tracker_state.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <set>
#include <sstream>
#include <vector>

#include "gtrack/error.hpp"
#include "gtrack/text_file.hpp"
#include "replace_file.hpp"

namespace gtrack {

namespace fs = std::filesystem;

namespace {

void write_vector(std::ostream& out, const char* name, const std::optional<Eigen::VectorXd>& v) {
  out << name;
  if (!v) {
    out << " -\n";
    return;
  }
  char buf[32];
  for (Eigen::Index i = 0; i < v->size(); ++i) {
    std::snprintf(buf, sizeof buf, " %.17g", (*v)[i]);
    out << buf;
  }
  out << '\n';
}

}  // namespace

void write_tracker_state(const fs::path& file, const TrackerState& s, bool durable) {
  std::ostringstream out;
  out << "gtrack-tracker-state 1\n"
      << "frame " << s.frame << "\n"
      << "lost " << s.lost << "\n"
      << "started " << (s.started ? 1 : 0) << "\n"
      << "reference_area " << s.reference_area << "\n";
  write_vector(out, "last", s.last);
  write_vector(out, "before_last", s.before_last);
  write_vector(out, "reported", s.reported);
  out << "last_found " << (s.last_found ? 1 : 0) << "\n";
  write_vector(out, "found_step", s.found_step);
  if (!s.run.empty()) {
    if (s.run.find('\n') != std::string::npos) throw InputError("a tracker state's run line cannot hold a line break");
    out << "run " << s.run << "\n";
  }
  detail::replace_file(file, out.str(), durable);
}

TrackerState parse_tracker_state(std::string_view text, const std::string& name) {
  std::istringstream in{std::string(text)};
  TrackerState s;
  std::string line;
  int n = 0;
  const auto fail = [&](const std::string& what) {
    throw InputError(name + ":" + std::to_string(n) + ": " + what);
  };
  bool header = false, have_frame = false;
  std::set<std::string> seen;
  while (std::getline(in, line)) {
    ++n;
    std::istringstream ls(line);
    std::string key;
    ls >> key;
    if (n > 1 && !seen.insert(key).second) fail("'" + key + "' again");
    if (n == 1) {
      int version = 0;
      if (key != "gtrack-tracker-state" || !(ls >> version) || version != 1) {
        fail("expected 'gtrack-tracker-state 1', the header of a tracker state");
      }
      header = true;
      continue;
    }
    if (key == "run") {
      if (line.rfind("run ", 0) != 0 || line.size() == 4) fail("expected the run's input after 'run '");
      s.run = line.substr(4);
      continue;
    }
    if (key == "last" || key == "before_last" || key == "reported" || key == "found_step") {
      std::vector<double> v;
      std::string tok;
      bool none = false;
      while (ls >> tok) {
        if (tok == "-") {
          none = true;
          continue;
        }
        char* end = nullptr;
        const double x = std::strtod(tok.c_str(), &end);
        if (end == tok.c_str() || *end != '\0' || !std::isfinite(x)) fail("'" + tok + "' is not a finite number");
        v.push_back(x);
      }
      if (none != v.empty()) fail("expected '-' or the values of a configuration after '" + key + "'");
      if (!none) {
        if (key == "found_step" && v.size() != 2) fail("expected '-' or two values (x, y) after 'found_step'");
        (key == "last" ? s.last : key == "before_last" ? s.before_last : key == "reported" ? s.reported : s.found_step) =
            Eigen::Map<Eigen::VectorXd>(v.data(), static_cast<Eigen::Index>(v.size()));
      }
      continue;
    }
    long long value = 0;
    std::string rest;
    if (!(ls >> value) || (ls >> rest)) fail("expected one integer after '" + key + "'");
    const auto within = [&](long long lo, long long hi) {
      if (value < lo || value > hi) {
        fail("'" + key + "' must be in [" + std::to_string(lo) + ", " + std::to_string(hi) + "], got " +
             std::to_string(value));
      }
    };
    constexpr long long kMaxInt = std::numeric_limits<int>::max();
    if (key == "frame") {
      within(-1, kMaxInt);
      s.frame = static_cast<int>(value);
      have_frame = true;
    } else if (key == "lost") {
      within(0, kMaxInt);
      s.lost = static_cast<int>(value);
    } else if (key == "started") {
      within(0, 1);
      s.started = value != 0;
    } else if (key == "last_found") {
      within(0, 1);
      s.last_found = value != 0;
    } else if (key == "reference_area") {
      within(0, std::numeric_limits<long long>::max());
      s.reference_area = static_cast<std::uint64_t>(value);
    } else {
      fail("unknown key '" + key + "'");
    }
  }
  if (!header || !have_frame) {
    n = std::max(n, 1);
    fail("incomplete tracker state (no header or no frame line)");
  }
  // Every line is written every time: one that is missing means the file
  // was damaged, and a default in its place would resume a different track
  // (but `reported`, which states of earlier releases lack).
  for (const char* key :
       {"lost", "started", "reference_area", "last", "before_last", "last_found", "found_step"}) {
    if (!seen.count(key)) fail(std::string("missing the '") + key + "' line of a tracker state");
  }
  return s;
}

TrackerState read_tracker_state(const fs::path& file) {
  // A state is a few hundred bytes.
  return parse_tracker_state(read_text_file(file, 1 << 20, "a tracker state file"), file.string());
}

}  // namespace gtrack
