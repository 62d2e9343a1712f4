// Frame sources: the order of an image folder, and its ranges.
#include <gtest/gtest.h>
#include <gtrack/frame_source.hpp>

#include <filesystem>
#include <opencv2/imgcodecs.hpp>
#include <string>
#include <vector>

namespace fs = std::filesystem;

namespace {

fs::path folder_of(const std::string& name, const std::vector<std::string>& files) {
  const fs::path dir = fs::temp_directory_path() / "gtrack_frame_source_test" / name;
  fs::remove_all(dir);
  fs::create_directories(dir);
  const cv::Mat img(4, 4, CV_8UC3, cv::Scalar(10, 20, 30));
  for (const auto& f : files) cv::imwrite((dir / f).string(), img);
  return dir;
}

std::vector<std::string> names(gtrack::FrameSource& src) {
  std::vector<std::string> out;
  while (auto f = src.next()) out.push_back(fs::path(f->name).filename().string() + "@" + std::to_string(f->index));
  return out;
}

// Lab recordings number their frames without padding: frame9 comes before
// frame10, as a person reads them, not as the bytes sort.
TEST(FrameSource, AFolderIsReadInTheOrderOfTheNumbersInItsNames) {
  const fs::path dir = folder_of("natural", {"frame10.png", "frame9.png", "frame1.png", "frame100.png", "frame09.png",
                                             "other.png", "frame2.png"});
  auto src = gtrack::open_frame_source(dir.string(), {4, 4}, {}, 30);
  EXPECT_EQ(names(*src), (std::vector<std::string>{"frame1.png@0", "frame2.png@1", "frame09.png@2", "frame9.png@3",
                                                   "frame10.png@4", "frame100.png@5", "other.png@6"}));
}

TEST(FrameSource, ARangeAndAStrideCountFromItsStart) {
  const fs::path dir = folder_of("range", {"000000.png", "000001.png", "000002.png", "000003.png", "000004.png"});
  gtrack::FrameRange r = gtrack::parse_frame_range("1:5");
  r.every = 2;
  auto src = gtrack::open_frame_source(dir.string(), {4, 4}, r, 30);
  EXPECT_EQ(names(*src), (std::vector<std::string>{"000001.png@1", "000003.png@3"}));
}

}  // namespace
