// The stimulus CSV: both headers, interpolation, and errors with file:line.
#include <gtest/gtest.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "gtrack/error.hpp"
#include "gtrack/stimulus_log.hpp"
#include "support/logged.hpp"

namespace {

using gtrack::StimulusLog;

std::string error_of(const std::string& text) {
  try {
    StimulusLog::parse(text, "log.csv");
  } catch (const gtrack::InputError& e) {
    return e.what();
  }
  return "";
}

TEST(StimulusLog, FrameKeyedInterpolates) {
  const auto log = StimulusLog::parse("frame,value\n0,20\n10,30\n", "log.csv");
  EXPECT_EQ(log.key(), StimulusLog::Key::Frame);
  EXPECT_DOUBLE_EQ(*log.value_at(0, 99.0), 20.0);
  EXPECT_DOUBLE_EQ(*log.value_at(5, 99.0), 25.0);
  EXPECT_DOUBLE_EQ(*log.value_at(10, 0.0), 30.0);
  EXPECT_FALSE(log.value_at(11, 0.0));
  EXPECT_DOUBLE_EQ(log.nearest(11, 0.0), 30.0);
}

TEST(StimulusLog, TimeKeyedUsesFrameTime) {
  const auto log = StimulusLog::parse("time_s,value\r\n0.0,24.0\r\n2.0,28.0\r\n# comment\n\n", "log.csv");
  EXPECT_EQ(log.key(), StimulusLog::Key::Time);
  EXPECT_DOUBLE_EQ(*log.value_at(1000, 0.5), 25.0);
  EXPECT_FALSE(log.value_at(0, 2.5));
}

// A log on another clock (Unix time): its time at the first frame taken
// from every row, to the precision of its own times.
TEST(StimulusLog, ATimeShiftMovesEveryRow) {
  auto log = StimulusLog::parse("time_s,value\n1765011000.25,24.0\n1765011002.25,28.0\n", "log.csv");
  EXPECT_FALSE(log.value_at(0, 0.5));
  log.shift_time(1765011000.0);
  EXPECT_DOUBLE_EQ(log.time_shift(), 1765011000.0);
  EXPECT_DOUBLE_EQ(log.first_key(), 0.25);
  EXPECT_NEAR(*log.value_at(0, 1.25), 26.0, 1e-6);
  EXPECT_FALSE(log.value_at(0, 0.2));
  auto by_frame = StimulusLog::parse("frame,value\n0,20\n10,30\n", "log.csv");
  try {
    by_frame.shift_time(5);
    ADD_FAILURE() << "a frame-keyed log was shifted";
  } catch (const gtrack::InputError& e) {
    EXPECT_STREQ(e.what(), "log.csv: is keyed by frame; a time offset (--stimulus-offset) shifts a time_s log");
  }
  EXPECT_DOUBLE_EQ(*by_frame.value_at(5, 0), 25.0);
}

TEST(StimulusLog, ErrorsNameFileLineAndWhatWasExpected) {
  EXPECT_EQ(error_of("index,temp\n"), "log.csv:1: expected the header 'frame,value' or 'time_s,value' (or the key and "
                                       "named columns, 'time_s,B_mT,T_C'), got 'index,temp'");
  EXPECT_EQ(error_of("frame,\n"), "log.csv:1: expected the header 'frame,value' or 'time_s,value' (or the key and "
                                  "named columns, 'time_s,B_mT,T_C'), got 'frame,'");
  EXPECT_EQ(error_of("frame,value\n0,20\n1,abc\n"), "log.csv:3: expected a number in the value field, got 'abc'");
  EXPECT_EQ(error_of("frame,value\n0,20\n1.5,21\n"),
            "log.csv:3: expected a frame index (a whole number from 0 to 2147483647) in the first field, got '1.5'");
  EXPECT_EQ(error_of("frame,value\n0,20\n99999999999999999999999,21\n"),
            "log.csv:3: expected a frame index (a whole number from 0 to 2147483647) in the first field, got "
            "'99999999999999999999999'");
  // Long or binary fields are quoted short and printable.
  EXPECT_EQ(error_of("frame,value\n0," + std::string(100, 'A') + "\n"),
            "log.csv:2: expected a number in the value field, got '" + std::string(60, 'A') + "... (100 characters)'");
  EXPECT_EQ(error_of(std::string("frame,value\n0,\x01\xff\n")),
            "log.csv:2: expected a number in the value field, got '\\x01\\xFF'");
  EXPECT_EQ(error_of("frame,value\n3,20\n2,21\n"),
            "log.csv:3: expected a frame index greater than the previous row's, got '2'");
  EXPECT_EQ(error_of("time_s,value\n0.5\n"), "log.csv:2: expected two fields '<time_s>,<value>', got '0.5'");
  // The rows after a malformed one are read on: the error lists the others.
  EXPECT_EQ(error_of("frame,value\n0,20\n1,abc\n2,21\n3,\n4,22\n5;23\n"),
            "log.csv:3: expected a number in the value field, got 'abc'; 2 more rows are malformed too (lines 5, 7)");
  EXPECT_EQ(error_of("frame,value\n0,20\n1,abc\n2,21\n3,x\n"),
            "log.csv:3: expected a number in the value field, got 'abc'; 1 more row is malformed too (line 5)");
  EXPECT_EQ(error_of("frame,value\n"), "log.csv: the stimulus log has a header but no rows");
  EXPECT_EQ(error_of(""), "log.csv: empty stimulus log; expected the header 'frame,value' or 'time_s,value'");
}

// A check of each reading (the tracker's: an instance of the stimulus
// plugin) that throws is an error naming the file and the row's line.
TEST(StimulusLog, AReadingTheCheckRefusesNamesItsLine) {
  std::vector<double> seen, at;
  std::vector<StimulusLog::Key> keys;
  const auto check = [&](double v, StimulusLog::Key key, double k) {
    seen.push_back(v);
    keys.push_back(key);
    at.push_back(k);
    if (v > 150) throw std::invalid_argument("a reading of " + std::to_string(static_cast<int>(v)) + ", too hot");
  };
  EXPECT_NO_THROW(StimulusLog::parse("frame,value\n0,20\n# note\n3,21\n", "log.csv", check));
  EXPECT_EQ(seen, (std::vector<double>{20, 21}));
  EXPECT_EQ(at, (std::vector<double>{0, 3}));
  EXPECT_EQ(keys, (std::vector<StimulusLog::Key>{StimulusLog::Key::Frame, StimulusLog::Key::Frame}));
  try {
    StimulusLog::parse("time_s,value\n0,20\n\n0.5,295.15\n", "log.csv", check);
    ADD_FAILURE() << "a refused reading was taken";
  } catch (const gtrack::InputError& e) {
    EXPECT_STREQ(e.what(), "log.csv:4: a reading of 295, too hot");
  }
  EXPECT_EQ(at.back(), 0.5);
  EXPECT_EQ(keys.back(), StimulusLog::Key::Time);
  // After a malformed row, the rows the check refuses are listed too.
  try {
    StimulusLog::parse("frame,value\n0,22\n1,abc\n2,22\n3,400\n4,x\n", "log.csv", check);
    ADD_FAILURE() << "a malformed log was taken";
  } catch (const gtrack::InputError& e) {
    EXPECT_STREQ(e.what(), "log.csv:3: expected a number in the value field, got 'abc'; 1 more row is malformed too "
                           "(line 6); the stimulus plugin refuses the reading of line 5");
  }
}

// A logger's own header: the readings' column may have any name, and of
// several named columns the one asked for is read (a log had to be
// rewritten to 'frame,value' first).
TEST(StimulusLog, ALoggersNamedColumnsAreReadByName) {
  const auto one = StimulusLog::parse("time_s,B_mT\n0,2.5\n1,4.5\n", "log.csv");
  EXPECT_DOUBLE_EQ(*one.value_at(15, 0.5), 3.5);
  const std::string channels = "time_s,B_mT,T_C\n0,2.5,22\n1,4.5,24\n";
  EXPECT_DOUBLE_EQ(*StimulusLog::parse(channels, "log.csv", {}, "T_C").value_at(15, 0.5), 23.0);
  EXPECT_DOUBLE_EQ(*StimulusLog::parse(channels, "log.csv", {}, "B_mT").value_at(15, 0.5), 3.5);
  const auto error = [&](const std::string& text, const std::string& column) {
    try {
      StimulusLog::parse(text, "log.csv", {}, column);
    } catch (const gtrack::InputError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_EQ(error(channels, ""), "log.csv:1: the log has the columns 'B_mT', 'T_C'; say which holds the readings "
                                 "(--stimulus-column NAME)");
  EXPECT_EQ(error(channels, "T_F"), "log.csv:1: no column 'T_F'; the log has 'B_mT', 'T_C'");
  // Two probes logged under one name: which is the reading is not guessed.
  EXPECT_EQ(error("time_s,T_C,T_C\n0,22,23\n", "T_C"),
            "log.csv:1: the column 'T_C' appears twice ('T_C', 'T_C'); expected one column of that name, the "
            "readings'");
  EXPECT_EQ(error("time_s,B_mT,T_C\n0,2.5\n", "T_C"), "log.csv:2: expected 3 fields, as the header has, got '0,2.5'");
  EXPECT_EQ(error("time_s,B_mT,T_C\n0,2.5,hot\n", "T_C"), "log.csv:2: expected a number in the 'T_C' field, got 'hot'");
}

TEST(StimulusLog, MissingFileIsAnInputError) {
  EXPECT_THROW(StimulusLog::load("/nonexistent/stimulus.csv"), gtrack::InputError);
}

// A file that never ends a line is refused at a bounded length, not read
// into memory whole; a folder is said to be one.
TEST(StimulusLog, ALineWithoutEndAndAFolderAreRefused) {
  namespace fs = std::filesystem;
  const fs::path file = fs::temp_directory_path() / "gtrack_stimulus_long.csv";
  std::ofstream(file) << "frame,value\n0,1\n" << std::string(100000, 'x');
  try {
    StimulusLog::load(file);
    FAIL() << "a 100000-character line must throw";
  } catch (const gtrack::InputError& e) {
    EXPECT_EQ(std::string(e.what()), file.string() + ":3: a line of more than 4096 characters; expected 'frame,value' "
                                                      "or 'time_s,value' rows");
  }
  fs::remove(file);
  try {
    StimulusLog::load(fs::temp_directory_path());
    FAIL() << "a folder must throw";
  } catch (const gtrack::InputError& e) {
    EXPECT_NE(std::string(e.what()).find(": is a folder; expected a stimulus log"), std::string::npos) << e.what();
  }
}

}  // namespace

// A log still being written (--follow-stimulus): poll() takes whole lines
// as they are appended, checks them as parse() does, and latest() is the
// last row's reading.
TEST(StimulusLog, FollowTakesAppendedWholeLines) {
  namespace fs = std::filesystem;
  const fs::path file = fs::temp_directory_path() / "gtrack_stimulus_follow.csv";
  std::ofstream(file) << "";
  gtrack::StimulusLog log = gtrack::StimulusLog::follow(file);
  EXPECT_FALSE(log.latest());
  EXPECT_FALSE(log.value_at(0, 0.0));
  const auto append = [&](const std::string& text) { std::ofstream(file, std::ios::app) << text; };
  append("frame,value\n0,22.5\n1,2");  // the logger is half way through row 1
  EXPECT_TRUE(log.poll());
  ASSERT_TRUE(log.latest());
  EXPECT_DOUBLE_EQ(*log.latest(), 22.5);
  EXPECT_FALSE(log.poll());  // nothing whole since
  // The last row's age: from when it was read, until a new row comes; and
  // the time between the polls that took rows.
  std::this_thread::sleep_for(std::chrono::milliseconds(60));
  ASSERT_TRUE(log.latest_age_s());
  const double before = *log.latest_age_s();
  EXPECT_GE(before, 0.06);
  EXPECT_FALSE(log.typical_row_gap_s());
  append("3.0\n");
  EXPECT_TRUE(log.poll());
  EXPECT_DOUBLE_EQ(*log.latest(), 23.0);
  EXPECT_LT(*log.latest_age_s(), before);
  ASSERT_TRUE(log.typical_row_gap_s());
  EXPECT_GE(*log.typical_row_gap_s(), 0.06);
  EXPECT_FALSE(StimulusLog::parse("frame,value\n0,1\n").latest_age_s());  // a finished log has no age
  EXPECT_EQ(log.rows(), 2u);
  // A garbled row and one whose key steps back are said and left out: a
  // live run goes on, holding the last reading.
  append("2,abc\n1,30\n3,24.5\n");
  const std::string said = gtrack::testing::logged([&] { EXPECT_TRUE(log.poll()); });
  EXPECT_NE(said.find("gtrack_stimulus_follow.csv:4: expected a number in the value field, got 'abc'; the row is left "
                      "out, and the frames hold the last reading"),
            std::string::npos)
      << said;
  EXPECT_NE(said.find("gtrack_stimulus_follow.csv:5: expected a frame index greater than the previous row's"), std::string::npos)
      << said;
  EXPECT_EQ(log.skipped_rows(), 2);
  EXPECT_EQ(log.rows(), 3u);
  EXPECT_DOUBLE_EQ(*log.latest(), 24.5);
  // A reading the check refuses after it took one (a sensor's spike) is
  // left out as a glitch is; a refused first reading (a log in another
  // unit) stops the run.
  const fs::path checked = fs::temp_directory_path() / "gtrack_stimulus_follow_checked.csv";
  const auto too_hot = [](double v, gtrack::StimulusLog::Key, double) {
    if (v > 150) throw std::invalid_argument("too hot");
  };
  std::ofstream(checked) << "frame,value\n0,22\n";
  gtrack::StimulusLog spiked = gtrack::StimulusLog::follow(checked, too_hot);
  std::ofstream(checked, std::ios::app) << "1,295\n2,23\n";
  const std::string spike = gtrack::testing::logged([&] { EXPECT_TRUE(spiked.poll()); });
  EXPECT_NE(spike.find("gtrack_stimulus_follow_checked.csv:3: too hot; the row is left out"), std::string::npos)
      << spike;
  EXPECT_EQ(spiked.skipped_rows(), 1);
  EXPECT_DOUBLE_EQ(*spiked.latest(), 23.0);
  std::ofstream(checked) << "frame,value\n0,295\n";
  EXPECT_THROW(gtrack::StimulusLog::follow(checked, too_hot), gtrack::InputError);
  fs::remove(checked);
  std::ofstream(file) << "frame,value\n";
  EXPECT_THROW(log.poll(), gtrack::InputError);  // shrank: a new log, not this one
}

// A followed log that disappears is said once, and the readings so far are
// kept; when it is back, its rows are taken again.
TEST(StimulusLog, AFollowedLogThatIsGoneIsSaidOnce) {
  namespace fs = std::filesystem;
  const fs::path file = fs::temp_directory_path() / "gtrack_stimulus_gone.csv";
  std::ofstream(file) << "frame,value\n0,22.5\n";
  gtrack::StimulusLog log = gtrack::StimulusLog::follow(file);
  ASSERT_TRUE(log.latest());
  const std::string text = std::string("frame,value\n0,22.5\n");
  fs::remove(file);
  const std::string said = gtrack::testing::logged([&] {
    EXPECT_FALSE(log.poll());
    EXPECT_FALSE(log.poll());
  });
  EXPECT_NE(said.find("the followed stimulus log is gone"), std::string::npos) << said;
  EXPECT_EQ(said.find("is gone"), said.rfind("is gone")) << "said once: " << said;
  EXPECT_DOUBLE_EQ(*log.latest(), 22.5);
  std::ofstream(file) << text << "1,24.0\n";
  EXPECT_TRUE(log.poll());
  EXPECT_DOUBLE_EQ(*log.latest(), 24.0);
  // A copy renamed over it (a logger that replaces its file) holding the
  // rows read so far: its new rows are taken.
  const fs::path copy = file.string() + ".new";
  std::ofstream(copy) << text << "1,24.0\n2,25.5\n";
  fs::rename(copy, file);
  EXPECT_TRUE(log.poll());
  EXPECT_DOUBLE_EQ(*log.latest(), 25.5);
  // A new log, started afresh and as long by now: its rows are not the
  // ones read, and reading on from the same byte would take a row's end.
  fs::remove(file);
  std::ofstream(file) << "frame,value\n0,30.0\n1,30.1\n2,30.2\n3,30.3\n";
  try {
    log.poll();
    ADD_FAILURE() << "a new log in place of the followed one was read on from its old place";
  } catch (const gtrack::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("gtrack_stimulus_gone.csv: was replaced while followed"), std::string::npos)
        << e.what();
  }
  fs::remove(file);
}
