// The stimulus CSV: both headers, interpolation, and errors with file:line.
#include <gtest/gtest.h>

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
