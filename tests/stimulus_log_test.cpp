// The stimulus CSV: both headers, interpolation, and errors with file:line.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "gtrack/error.hpp"
#include "gtrack/stimulus_log.hpp"

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

TEST(StimulusLog, ErrorsNameFileLineAndWhatWasExpected) {
  EXPECT_EQ(error_of("frame,temp\n"), "log.csv:1: expected the header 'frame,value' or 'time_s,value', got 'frame,temp'");
  EXPECT_EQ(error_of("frame,value\n0,20\n1,abc\n"), "log.csv:3: expected a number in the value field, got 'abc'");
  EXPECT_EQ(error_of("frame,value\n0,20\n1.5,21\n"), "log.csv:3: expected a frame index in the first field, got '1.5'");
  EXPECT_EQ(error_of("frame,value\n3,20\n2,21\n"),
            "log.csv:3: expected a frame index greater than the previous row's, got '2'");
  EXPECT_EQ(error_of("time_s,value\n0.5\n"), "log.csv:2: expected two fields '<time_s>,<value>', got '0.5'");
  EXPECT_EQ(error_of("frame,value\n"), "log.csv: the stimulus log has a header but no rows");
  EXPECT_EQ(error_of(""), "log.csv: empty stimulus log; expected the header 'frame,value' or 'time_s,value'");
}

TEST(StimulusLog, MissingFileIsAnInputError) {
  EXPECT_THROW(StimulusLog::load("/nonexistent/stimulus.csv"), gtrack::InputError);
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
  append("3.0\n");
  EXPECT_TRUE(log.poll());
  EXPECT_DOUBLE_EQ(*log.latest(), 23.0);
  EXPECT_EQ(log.rows(), 2u);
  append("2,abc\n");
  try {
    log.poll();
    FAIL() << "a malformed appended row must be refused";
  } catch (const gtrack::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("gtrack_stimulus_follow.csv:4: expected a number in the value field, got 'abc'"),
              std::string::npos)
        << e.what();
  }
  std::ofstream(file) << "frame,value\n";
  EXPECT_THROW(log.poll(), gtrack::InputError);  // shrank: a new log, not this one
}
