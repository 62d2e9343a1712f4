// Frame sources: the order of an image folder, and its ranges; a recording
// read again in blocks, backward (RecordedFrames).
#include <gtest/gtest.h>
#include <gtrack/frame_source.hpp>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>
#include <string>
#include <vector>

#include <tiffio.h>

#include "gtrack/error.hpp"
#include "gtrack/log.hpp"
#include "support/logged.hpp"

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
// frame10, as a person reads them, not as the bytes sort. Hidden files (a
// copy's "._" metadata, an image being written) are not frames.
TEST(FrameSource, AFolderIsReadInTheOrderOfTheNumbersInItsNames) {
  const fs::path dir = folder_of("natural", {"frame10.png", "frame9.png", "frame1.png", "frame100.png", "frame09.png",
                                             "other.png", "frame2.png", "._frame3.png", ".frame4.png"});
  auto src = gtrack::open_frame_source(dir.string(), {4, 4}, {}, 30);
  EXPECT_EQ(names(*src), (std::vector<std::string>{"frame1.png@0", "frame2.png@1", "frame09.png@2", "frame9.png@3",
                                                   "frame10.png@4", "frame100.png@5", "other.png@6"}));
}

// A file that is not a video says so in one line: an empty one as empty,
// another with the decoder's words.
TEST(FrameSource, AFileThatIsNoVideoIsNamedWithWhatItIs) {
  const fs::path dir = folder_of("not_a_video", {});
  std::ofstream(dir / "empty.mp4").close();
  std::ofstream(dir / "text.mp4") << "not a video at all\n";
  const auto message = [](const fs::path& file) {
    try {
      gtrack::open_frame_source(file.string(), {4, 4}, {}, 30);
    } catch (const gtrack::InputError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_EQ(message(dir / "empty.mp4"),
            (dir / "empty.mp4").string() + ": an empty file (0 bytes); expected a video, a folder of images or a "
                                           "TIFF stack");
  EXPECT_EQ(message(dir / "text.mp4").rfind((dir / "text.mp4").string() + ": cannot open as a video (corrupt, "
                                            "unsupported, or holding no frame",
                                            0),
            0u)
      << message(dir / "text.mp4");
}

TEST(FrameSource, ARangeAndAStrideCountFromItsStart) {
  const fs::path dir = folder_of("range", {"000000.png", "000001.png", "000002.png", "000003.png", "000004.png"});
  gtrack::FrameRange r = gtrack::parse_frame_range("1:5");
  r.every = 2;
  auto src = gtrack::open_frame_source(dir.string(), {4, 4}, r, 30);
  EXPECT_EQ(names(*src), (std::vector<std::string>{"000001.png@1", "000003.png@3"}));
}

// A frame unlike its neighbours: noise drawn from its own seed, its number
// written on it.
cv::Mat numbered_frame(int i, int salt = 0) {
  cv::Mat img(96, 128, CV_8UC3);
  cv::RNG rng(static_cast<std::uint64_t>(1000 * salt + i + 1));
  rng.fill(img, cv::RNG::UNIFORM, 0, 255);
  cv::GaussianBlur(img, img, {7, 7}, 2);
  cv::putText(img, std::to_string(i), {10, 60}, cv::FONT_HERSHEY_SIMPLEX, 1.5, {255, 255, 255}, 3);
  return img;
}

// Writes `frames` frames; false when this OpenCV build has no such writer.
bool write_video(const fs::path& path, int fourcc, int frames, int salt = 0) {
  cv::VideoWriter w(path.string(), fourcc, 25, {128, 96});
  if (!w.isOpened()) return false;
  for (int i = 0; i < frames; ++i) w.write(numbered_frame(i, salt));
  return true;
}

std::vector<cv::Mat> decoded_in_order(const fs::path& video) {
  auto src = gtrack::open_frame_source(video.string(), {128, 96}, {}, 25);
  std::vector<cv::Mat> out;
  while (auto f = src->next()) {
    EXPECT_EQ(f->index, static_cast<int>(out.size()));
    out.push_back(f->image);
  }
  return out;
}

// The backward pass reads a recording a block at a time from its end: a
// video's blocks are read by seeking, and must be the very frames reading
// it in order gives, whatever the codec (intra-only MJPG; MPEG-4 with
// frames predicted from earlier ones).
TEST(RecordedFrames, AVideosBlocksReadFromItsEndAreTheFramesReadInOrder) {
  const fs::path dir = folder_of("recorded_video", {});
  struct Codec {
    std::string file;
    int fourcc;
  };
  int tried = 0;
  for (const Codec& c : {Codec{"clip.avi", cv::VideoWriter::fourcc('M', 'J', 'P', 'G')},
                         Codec{"clip.mp4", cv::VideoWriter::fourcc('m', 'p', '4', 'v')}}) {
    const fs::path video = dir / c.file;
    if (!write_video(video, c.fourcc, 90)) continue;
    ++tried;
    const std::vector<cv::Mat> reference = decoded_in_order(video);
    ASSERT_EQ(reference.size(), 90u) << c.file;
    // Frames 7, 10, ..., 88 (--frames 7:89 --every 3), blocks of 5 from the end.
    std::vector<int> frames;
    for (int i = 7; i < 89; i += 3) frames.push_back(i);
    gtrack::RecordedFrames recording(video.string(), {128, 96}, frames, 3, 25);
    for (std::size_t hi = frames.size(); hi > 0; hi -= std::min<std::size_t>(hi, 5)) {
      const std::size_t lo = hi - std::min<std::size_t>(hi, 5);
      const auto block = recording.read(lo, hi);
      ASSERT_EQ(block.size(), hi - lo) << c.file;
      for (std::size_t k = lo; k < hi; ++k) {
        const auto it = block.find(frames[k]);
        ASSERT_NE(it, block.end()) << c.file << " frame " << frames[k];
        EXPECT_EQ(cv::norm(it->second, reference[static_cast<std::size_t>(frames[k])], cv::NORM_INF), 0)
            << c.file << " frame " << frames[k];
      }
    }
    // The first block is read with the pass that fingerprints the video;
    // the five after it by seeking. Intra-only frames seek exactly.
    if (c.file == "clip.avi") EXPECT_TRUE(recording.seeks());
    if (recording.seeks()) EXPECT_EQ(recording.seeked_blocks(), 5) << c.file;
  }
  ASSERT_GT(tried, 0) << "no video writer in this OpenCV build";
}

// A video replaced between two reads: the frame that differs is named,
// rather than tracked as if it were the one this reader first decoded.
TEST(RecordedFrames, AVideoThatChangedIsAnErrorNamingTheFrame) {
  const fs::path dir = folder_of("recorded_changed", {});
  const fs::path video = dir / "clip.avi";
  ASSERT_TRUE(write_video(video, cv::VideoWriter::fourcc('M', 'J', 'P', 'G'), 40)) << "no MJPG writer";
  std::vector<int> frames(40);
  for (int i = 0; i < 40; ++i) frames[static_cast<std::size_t>(i)] = i;
  gtrack::RecordedFrames recording(video.string(), {128, 96}, frames, 1, 25);
  EXPECT_EQ(recording.read(30, 40).size(), 10u);
  ASSERT_TRUE(write_video(video, cv::VideoWriter::fourcc('M', 'J', 'P', 'G'), 40, 1));
  try {
    recording.read(20, 30);
    FAIL() << "a changed video was read as if it were the same";
  } catch (const gtrack::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("frame 20 is no longer what it was"), std::string::npos) << e.what();
  }
  EXPECT_EQ(recording.seeked_blocks(), 0);
}

// A folder's blocks are its images by their place in name order; a frame
// past the folder's end since is named.
TEST(RecordedFrames, AFoldersBlocksAreItsImagesAndAMissingOneIsNamed) {
  const fs::path dir = folder_of("recorded_folder", {});
  for (int i = 0; i < 12; ++i) cv::imwrite((dir / (std::to_string(i) + ".png")).string(), numbered_frame(i));
  gtrack::RecordedFrames recording(dir.string(), {128, 96}, {2, 4, 6, 8, 10}, 2, 25);
  const auto block = recording.read(3, 5);
  ASSERT_EQ(block.size(), 2u);
  EXPECT_EQ(cv::norm(block.at(10), numbered_frame(10), cv::NORM_INF), 0);
  EXPECT_FALSE(recording.seeks());
  fs::remove(dir / "11.png");
  fs::remove(dir / "10.png");
  try {
    recording.read(3, 5);
    FAIL() << "a removed image went unnoticed";
  } catch (const gtrack::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("frame 10 can no longer be read"), std::string::npos) << e.what();
  }
}

// A stack cut short (a copy that stopped, a disk that filled): its pages end
// where its directories do, and that is said, in the summary too, as for a
// video; libtiff's own count had stopped there without a word.
TEST(FrameSource, ATiffStackCutShortSaysWhereItsPagesEnd) {
  const fs::path dir = folder_of("tiff_cut", {});
  std::vector<cv::Mat> pages;
  for (int i = 0; i < 6; ++i) pages.push_back(numbered_frame(i));
  const fs::path whole = dir / "whole.tif", cut = dir / "cut.tif";
  ASSERT_TRUE(cv::imwritemulti(whole.string(), pages));
  {
    std::ifstream in(whole, std::ios::binary);
    const std::string bytes((std::istreambuf_iterator<char>(in)), {});
    std::ofstream(cut, std::ios::binary) << bytes.substr(0, bytes.size() * 6 / 10);
  }
  const auto warned = gtrack::testing::logged([&] {
    auto src = gtrack::open_frame_source(whole.string(), {128, 96}, {}, 25);
    EXPECT_EQ(src->ended_early(), "");
  });
  EXPECT_EQ(warned.find("its pages end"), std::string::npos) << warned;
  std::unique_ptr<gtrack::FrameSource> src;
  const auto said = gtrack::testing::logged([&] { src = gtrack::open_frame_source(cut.string(), {128, 96}, {}, 25); });
  ASSERT_GT(src->frame_count(), 0);
  ASSERT_LT(src->frame_count(), 6);
  EXPECT_NE(src->ended_early().find("its pages end after page " + std::to_string(src->frame_count() - 1) +
                                    " with an error"),
            std::string::npos)
      << src->ended_early();
  EXPECT_NE(said.find("cut.tif: its pages end after page"), std::string::npos) << said;
}

// A little-endian grey TIFF: a 128x96 page, then a 4x3 page whose
// NewSubfileType is `second_type` (1: a reduced image, a thumbnail).
std::string two_page_tiff(std::uint32_t second_type) {
  std::string b;
  const auto u16 = [&](std::uint32_t v) {
    b.push_back(static_cast<char>(v & 255));
    b.push_back(static_cast<char>((v >> 8) & 255));
  };
  const auto u32 = [&](std::uint32_t v) {
    for (int i = 0; i < 4; ++i) b.push_back(static_cast<char>((v >> (8 * i)) & 255));
  };
  const std::uint32_t p1 = 8, p2 = p1 + 128 * 96, ifd1 = p2 + 12, ifd2 = ifd1 + 2 + 10 * 12 + 4;
  b += "II";
  u16(42);
  u32(ifd1);
  b.append(128 * 96, static_cast<char>(200));
  b.append(12, static_cast<char>(50));
  const auto ifd = [&](std::uint32_t type, std::uint32_t w, std::uint32_t h, std::uint32_t pixels, std::uint32_t next) {
    u16(10);
    const auto entry = [&](std::uint32_t tag, bool is_long, std::uint32_t v) {
      u16(tag);
      u16(is_long ? 4 : 3);
      u32(1);
      if (is_long) {
        u32(v);
      } else {
        u16(v);
        u16(0);
      }
    };
    entry(254, true, type);        // NewSubfileType
    entry(256, false, w);          // ImageWidth
    entry(257, false, h);          // ImageLength
    entry(258, false, 8);          // BitsPerSample
    entry(259, false, 1);          // Compression: none
    entry(262, false, 1);          // Photometric: black is zero
    entry(273, true, pixels);      // StripOffsets
    entry(277, false, 1);          // SamplesPerPixel
    entry(278, false, h);          // RowsPerStrip
    entry(279, true, w * h);       // StripByteCounts
    u32(next);
  };
  ifd(0, 128, 96, p1, ifd2);
  ifd(second_type, 4, 3, p2, 0);
  return b;
}

// A folder's images are one frame each: a TIFF stack among them, of which
// only the first page would be read, is refused, naming it; a second page
// that is the first's thumbnail does not make a stack. A file named .tif
// that is another kind of image, given as the input, is one page, and
// nothing is said of its pages ending early.
TEST(FrameSource, ATiffStackInAFolderOfImagesIsRefused) {
  const fs::path dir = folder_of("tiff_in_folder", {});
  ASSERT_TRUE(cv::imwrite((dir / "a0.png").string(), numbered_frame(0)));
  std::vector<cv::Mat> pages;
  for (int i = 1; i < 4; ++i) pages.push_back(numbered_frame(i));
  ASSERT_TRUE(cv::imwritemulti((dir / "a1.tif").string(), pages));
  const auto frames_before_refusal = [](const fs::path& folder, std::string& refusal) {
    int frames = 0;
    try {
      auto src = gtrack::open_frame_source(folder.string(), {128, 96}, {}, 25);
      while (src->next()) ++frames;
    } catch (const gtrack::InputError& e) {
      refusal = e.what();
    }
    return frames;
  };
  std::string refusal;
  EXPECT_LE(frames_before_refusal(dir, refusal), 1);
  EXPECT_EQ(refusal, (dir / "a1.tif").string() + ": a TIFF stack of several pages in a folder of images, each of "
                                                 "which is one frame; give the stack to --input by itself");
  const fs::path thumbnail = folder_of("tiff_thumbnail", {});
  std::ofstream(thumbnail / "b.tif", std::ios::binary) << two_page_tiff(1);
  refusal.clear();
  EXPECT_EQ(frames_before_refusal(thumbnail, refusal), 1);
  EXPECT_EQ(refusal, "");
  std::ofstream(thumbnail / "b.tif", std::ios::binary) << two_page_tiff(0);
  EXPECT_EQ(frames_before_refusal(thumbnail, refusal), 0);
  EXPECT_EQ(refusal.rfind((thumbnail / "b.tif").string() + ": a TIFF stack of several pages", 0), 0u) << refusal;

  fs::copy_file(dir / "a0.png", thumbnail / "png.tif");
  std::unique_ptr<gtrack::FrameSource> src;
  const auto said =
      gtrack::testing::logged([&] { src = gtrack::open_frame_source((thumbnail / "png.tif").string(), {128, 96}, {}, 25); });
  EXPECT_EQ(src->frame_count(), 1);
  EXPECT_EQ(src->ended_early(), "");
  EXPECT_EQ(said.find("its pages end"), std::string::npos) << said;
  EXPECT_TRUE(src->next());
}

// A TIFF stack (ImageJ/Fiji, Micro-Manager): each page is a frame, 16-bit
// and grey pages included; a range skips the pages before it, and the
// backward pass reads its blocks by page.
TEST(FrameSource, EachPageOfATiffStackIsAFrame) {
  const fs::path dir = folder_of("tiff_stack", {});
  std::vector<cv::Mat> pages;
  for (int i = 0; i < 9; ++i) pages.push_back(numbered_frame(i));
  const fs::path stack = dir / "stack.TIF";
  ASSERT_TRUE(cv::imwritemulti(stack.string(), pages));
  gtrack::FrameRange r = gtrack::parse_frame_range("2:9");
  r.every = 3;
  auto src = gtrack::open_frame_source(stack.string(), {128, 96}, r, 25);
  EXPECT_EQ(src->frame_count(), 9);
  std::vector<int> seen;
  while (auto f = src->next()) {
    seen.push_back(f->index);
    EXPECT_EQ(cv::norm(f->image, pages[static_cast<std::size_t>(f->index)], cv::NORM_INF), 0) << f->index;
    EXPECT_DOUBLE_EQ(f->time_s, f->index / 25.0);
  }
  EXPECT_EQ(seen, (std::vector<int>{2, 5, 8}));
  gtrack::RecordedFrames recording(stack.string(), {128, 96}, {0, 1, 2, 3, 4, 5, 6, 7, 8}, 1, 25);
  const auto block = recording.read(6, 9);
  ASSERT_EQ(block.size(), 3u);
  EXPECT_EQ(cv::norm(block.at(7), pages[7], cv::NORM_INF), 0);
  EXPECT_FALSE(recording.seeks());
  // The next block reads the stack with the page count the first one found.
  const auto earlier = recording.read(2, 6);
  ASSERT_EQ(earlier.size(), 4u);
  EXPECT_EQ(cv::norm(earlier.at(2), pages[2], cv::NORM_INF), 0);
  EXPECT_EQ(cv::norm(earlier.at(5), pages[5], cv::NORM_INF), 0);

  // 16-bit grey pages, as cameras write them: grey BGR at a 257th.
  std::vector<cv::Mat> deep;
  for (int i = 0; i < 3; ++i) deep.push_back(cv::Mat(96, 128, CV_16UC1, cv::Scalar(257 * (40 + 10 * i))));
  const fs::path deep_stack = dir / "deep.tiff";
  ASSERT_TRUE(cv::imwritemulti(deep_stack.string(), deep));
  auto deep_src = gtrack::open_frame_source(deep_stack.string(), {128, 96}, {}, 25);
  int n = 0;
  while (auto f = deep_src->next()) {
    ASSERT_EQ(f->image.type(), CV_8UC3);
    EXPECT_EQ(f->image.at<cv::Vec3b>(5, 5), cv::Vec3b::all(static_cast<uchar>(40 + 10 * n)));
    ++n;
  }
  EXPECT_EQ(n, 3);

  // Pages of another size than the sensor's: the first page's header says
  // so, before a block of pages is decoded.
  try {
    gtrack::open_frame_source(stack.string(), {64, 48}, {}, 25);
    FAIL() << "a stack of another size was opened";
  } catch (const gtrack::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("stack.TIF: image is 128x96 but the sensor expects 64x48"),
              std::string::npos)
        << e.what();
  }

  // A page of another size is named; a file that is no TIFF is one line.
  pages[4] = cv::Mat(48, 64, CV_8UC3, cv::Scalar::all(9));
  ASSERT_TRUE(cv::imwritemulti(stack.string(), pages));
  auto mixed = gtrack::open_frame_source(stack.string(), {128, 96}, {}, 25);
  try {
    while (mixed->next()) {
    }
    FAIL() << "a page of another size was taken";
  } catch (const gtrack::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("stack.TIF page 4: image is 64x48 but the sensor expects 128x96"),
              std::string::npos)
        << e.what();
  }
  const fs::path fake = dir / "notes.tif";
  std::ofstream(fake) << "not an image\n";
  try {
    gtrack::open_frame_source(fake.string(), {128, 96}, {}, 25);
    FAIL() << "a text file was read as a stack";
  } catch (const gtrack::InputError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("notes.tif: cannot read as a TIFF stack"), std::string::npos) << what;
    EXPECT_EQ(what.find('\n'), std::string::npos) << what;
  }
}

}  // namespace

namespace {

using gtrack::testing::logged;

}  // namespace

// Frames are numbered by their order in a folder: a number missing from
// the names (a dropped frame) is warned about, once, with the first gap;
// names that carry time stamps, which never count up by one, are not. The
// number that counts is the one that changes between names.
TEST(FrameSource, AGapInAFoldersNumberingIsWarnedAbout) {
  const fs::path gap = folder_of("gap", {"img_0001.png", "img_0002.png", "img_0003.png", "img_0005.png",
                                         "img_0006.png", "img_0009.png"});
  std::vector<std::string> got;
  std::string warned = logged([&] {
    auto src = gtrack::open_frame_source(gap.string(), {4, 4}, {}, 30);
    got = names(*src);
  });
  EXPECT_EQ(got[3], "img_0005.png@3");
  EXPECT_NE(warned.find("the images' numbers skip from img_0003.png to img_0005.png and at 1 more place;"),
            std::string::npos)
      << warned;
  const fs::path stamped = folder_of("stamped", {"cam_1701234567123.png", "cam_1701234567156.png",
                                                 "cam_1701234567190.png"});
  warned = logged([&] { gtrack::open_frame_source(stamped.string(), {4, 4}, {}, 30); });
  EXPECT_EQ(warned, "");
  // Micro-Manager's names count in their first number, not their last.
  const fs::path mm = folder_of("micromanager", {"img_000000010_Default_000.png", "img_000000011_Default_000.png",
                                                 "img_000000013_Default_000.png", "img_000000014_Default_000.png"});
  warned = logged([&] { gtrack::open_frame_source(mm.string(), {4, 4}, {}, 30); });
  EXPECT_NE(warned.find("skip from img_000000011_Default_000.png to img_000000013_Default_000.png;"),
            std::string::npos)
      << warned;
  // A clock in the name changes in more than one number across a minute.
  const fs::path clock = folder_of("clock", {"t10-58.png", "t10-59.png", "t11-00.png", "t11-01.png"});
  warned = logged([&] { gtrack::open_frame_source(clock.string(), {4, 4}, {}, 30); });
  EXPECT_EQ(warned, "");
  const fs::path whole = folder_of("whole", {"f0.png", "f1.png", "f2.png"});
  warned = logged([&] { gtrack::open_frame_source(whole.string(), {4, 4}, {}, 30); });
  EXPECT_EQ(warned, "");
}

// `in`, an AVI of OpenCV's MJPG writer, with frame `drop`'s chunk emptied
// and the index rebuilt: a frame dropped as capture software records one.
void drop_avi_frame(const fs::path& in, const fs::path& out, int drop) {
  std::ifstream is(in, std::ios::binary);
  const std::string d((std::istreambuf_iterator<char>(is)), std::istreambuf_iterator<char>());
  const auto u32 = [&](std::size_t at) {
    std::uint32_t v = 0;
    std::memcpy(&v, d.data() + at, 4);
    return v;
  };
  const auto put = [](std::string& s, std::uint32_t v) { s.append(reinterpret_cast<const char*>(&v), 4); };
  const std::size_t movi = d.find("movi");
  ASSERT_NE(movi, std::string::npos);
  std::string body, index;
  std::size_t i = movi + 4;
  for (int k = 0; i + 8 <= d.size() && d.compare(i + 2, 2, "dc") == 0; ++k) {
    const std::uint32_t n = u32(i + 4), kept = k == drop ? 0 : n;
    index.append(d, i, 4);
    put(index, 0x10);
    put(index, static_cast<std::uint32_t>(4 + body.size()));
    put(index, kept);
    body.append(d, i, 4);
    put(body, kept);
    body.append(d, i + 8, kept + (kept & 1));
    i += 8 + n + (n & 1);
  }
  std::string avi = d.substr(0, movi + 4) + body;
  const auto list = static_cast<std::uint32_t>(4 + body.size());
  std::memcpy(&avi[movi - 4], &list, 4);
  avi += "idx1";
  put(avi, static_cast<std::uint32_t>(index.size()));
  avi += index;
  const auto riff = static_cast<std::uint32_t>(avi.size() - 8);
  std::memcpy(&avi[4], &riff, 4);
  std::ofstream(out, std::ios::binary) << avi;
}

// A frame dropped from a recording is decoded as no frame at all: the
// frames after it keep the source's numbers (and times), taken from their
// time stamps, and the gap is warned about once.
TEST(FrameSource, AFrameDroppedFromAVideoKeepsTheNumbersAfterIt) {
  const fs::path dir = folder_of("dropped_video", {});
  const fs::path whole = dir / "whole.avi", dropped = dir / "dropped.avi";
  ASSERT_TRUE(write_video(whole, cv::VideoWriter::fourcc('M', 'J', 'P', 'G'), 12)) << "no MJPG writer";
  drop_avi_frame(whole, dropped, 5);
  const std::vector<cv::Mat> reference = decoded_in_order(whole);
  ASSERT_EQ(reference.size(), 12u);
  for (const gtrack::FrameRange range : {gtrack::FrameRange{}, gtrack::FrameRange{2, -1, 2}}) {
    std::vector<int> got;
    const std::string warned = logged([&] {
      auto src = gtrack::open_frame_source(dropped.string(), {128, 96}, range, 25);
      while (auto f = src->next()) {
        got.push_back(f->index);
        EXPECT_DOUBLE_EQ(f->time_s, f->index / 25.0);
        EXPECT_EQ(cv::norm(f->image, reference[static_cast<std::size_t>(f->index)], cv::NORM_INF), 0)
            << "frame " << f->index;
      }
    });
    EXPECT_EQ(got, range.every == 1 ? std::vector<int>({0, 1, 2, 3, 4, 6, 7, 8, 9, 10, 11})
                                   : std::vector<int>({2, 4, 6, 8, 10}));
    EXPECT_NE(warned.find("dropped.avi: frame 5 is missing (the time stamps go on at frame 6"), std::string::npos)
        << warned;
    EXPECT_EQ(warned.find("reported damage"), std::string::npos) << warned;
  }
  // Read again in blocks from its end (the backward pass), with the
  // dropped frame's number skipped.
  const std::vector<int> frames = {0, 1, 2, 3, 4, 6, 7, 8, 9, 10, 11};
  gtrack::RecordedFrames recording(dropped.string(), {128, 96}, frames, 1, 25);
  for (std::size_t hi = frames.size(); hi > 0; hi -= std::min<std::size_t>(hi, 4)) {
    const std::size_t lo = hi - std::min<std::size_t>(hi, 4);
    const auto block = recording.read(lo, hi);
    ASSERT_EQ(block.size(), hi - lo);
    for (std::size_t k = lo; k < hi; ++k) {
      const auto it = block.find(frames[k]);
      ASSERT_NE(it, block.end()) << "frame " << frames[k];
      EXPECT_EQ(cv::norm(it->second, reference[static_cast<std::size_t>(frames[k])], cv::NORM_INF), 0)
          << "frame " << frames[k];
    }
  }
}

// A 12-bit camera stores its values in the low bits of 16-bit files: at
// the default 16 bits they come out dark, which is warned about once; with
// image_bits = 12 they fill the 8 bits, in the first pass and when read again.
// Values above what image_bits says (the high bits) are warned about.
TEST(FrameSource, SixteenBitImagesAreScaledByTheirSignificantBits) {
  const fs::path dir = folder_of("twelve_bits", {});
  const std::vector<int> values = {4095, 2048, 600};
  for (std::size_t i = 0; i < values.size(); ++i) {
    cv::Mat img(8, 8, CV_16UC1, cv::Scalar(values[i]));
    ASSERT_TRUE(cv::imwrite((dir / ("f" + std::to_string(i) + ".png")).string(), img));
  }
  std::vector<cv::Vec3b> seen;
  const std::string warned = logged([&] {
    auto src = gtrack::open_frame_source(dir.string(), {8, 8}, {}, 25);
    while (auto f = src->next()) seen.push_back(f->image.at<cv::Vec3b>(3, 3));
  });
  ASSERT_EQ(seen.size(), 3u);
  EXPECT_EQ(seen[0], cv::Vec3b::all(16));  // 4095 / 257
  EXPECT_NE(warned.find("f0.png: a 16-bit image whose values reach only 4095 of 65535"), std::string::npos) << warned;
  EXPECT_NE(warned.find("[tracker] image_bits"), std::string::npos) << warned;
  EXPECT_EQ(warned.find("f1.png"), std::string::npos) << "warned once: " << warned;

  seen.clear();
  const std::string quiet = logged([&] {
    auto src = gtrack::open_frame_source(dir.string(), {8, 8}, {}, 25);
    src->set_image_bits(12);
    while (auto f = src->next()) seen.push_back(f->image.at<cv::Vec3b>(3, 3));
  });
  EXPECT_EQ(quiet.find("16-bit"), std::string::npos) << quiet;
  EXPECT_EQ(seen, (std::vector<cv::Vec3b>{cv::Vec3b::all(255), cv::Vec3b::all(128), cv::Vec3b::all(37)}));
  gtrack::RecordedFrames recording(dir.string(), {8, 8}, {0, 1, 2}, 1, 25);
  recording.set_image_bits(12);
  EXPECT_EQ(recording.read(1, 2).at(1).at<cv::Vec3b>(3, 3), cv::Vec3b::all(128));
  auto src = gtrack::open_frame_source(dir.string(), {8, 8}, {}, 25);
  EXPECT_THROW(src->set_image_bits(17), std::invalid_argument);
  // 12 bits in the high bits of each sample, said to be 12: they saturate.
  const fs::path high = folder_of("twelve_high_bits", {});
  ASSERT_TRUE(cv::imwrite((high / "f0.png").string(), cv::Mat(8, 8, CV_16UC1, cv::Scalar(4095 << 4))));
  const std::string saturated = logged([&] {
    auto s = gtrack::open_frame_source(high.string(), {8, 8}, {}, 25);
    s->set_image_bits(12);
    s->next();
  });
  EXPECT_NE(saturated.find("f0.png: a 16-bit image with values up to 65520, above the 4095 of [tracker] image_bits = "
                           "12, which saturate"),
            std::string::npos)
      << saturated;
}

namespace {

// A stack of `pages` grey 16x16 pages, the first described by `description`
// (as ImageJ and OME-TIFF writers describe theirs).
void write_described_stack(const fs::path& file, int pages, const std::string& description, int samples = 1) {
  TIFF* tif = TIFFOpen(file.c_str(), "w");
  ASSERT_NE(tif, nullptr);
  std::vector<unsigned char> row(16 * static_cast<size_t>(samples));
  for (int p = 0; p < pages; ++p) {
    TIFFSetField(tif, TIFFTAG_IMAGEWIDTH, 16);
    TIFFSetField(tif, TIFFTAG_IMAGELENGTH, 16);
    TIFFSetField(tif, TIFFTAG_BITSPERSAMPLE, 8);
    TIFFSetField(tif, TIFFTAG_SAMPLESPERPIXEL, samples);
    TIFFSetField(tif, TIFFTAG_PHOTOMETRIC, samples == 3 ? PHOTOMETRIC_RGB : PHOTOMETRIC_MINISBLACK);
    TIFFSetField(tif, TIFFTAG_PLANARCONFIG, PLANARCONFIG_CONTIG);
    TIFFSetField(tif, TIFFTAG_ROWSPERSTRIP, 16);
    if (p == 0 && !description.empty()) TIFFSetField(tif, TIFFTAG_IMAGEDESCRIPTION, description.c_str());
    std::fill(row.begin(), row.end(), static_cast<unsigned char>(10 * p));
    for (int y = 0; y < 16; ++y) ASSERT_EQ(TIFFWriteScanline(tif, row.data(), static_cast<uint32_t>(y), 0), 1);
    ASSERT_EQ(TIFFWriteDirectory(tif), 1);
  }
  TIFFClose(tif);
}

std::string read_all_logged(const fs::path& file, int every) {
  gtrack::FrameRange r;
  r.every = every;
  return logged([&] {
    auto src = gtrack::open_frame_source(file.string(), {16, 16}, r, 25);
    while (src->next()) {
    }
  });
}

}  // namespace

// Every page of a stack is taken as the next frame: a stack whose writer
// says it holds several channels or z-slices per time point is warned
// about unless --every steps over them, and so is one that holds fewer
// pages than its writer says (a copy cut short).
TEST(FrameSource, AStacksLayoutFromImageJOrOmeIsChecked) {
  const fs::path dir = folder_of("stack_layout", {});
  const fs::path two_channels = dir / "two_channels.tif";
  write_described_stack(two_channels, 6,
                        "ImageJ=1.54f\nimages=6\nchannels=2\nframes=3\nhyperstack=true\nmode=composite\n");
  const std::string mixed = read_all_logged(two_channels, 1);
  EXPECT_NE(mixed.find("two_channels.tif: ImageJ says it holds 2 channel(s) and 1 z-slice(s) per time point"),
            std::string::npos)
      << mixed;
  EXPECT_NE(mixed.find("--every 2"), std::string::npos) << mixed;
  EXPECT_EQ(read_all_logged(two_channels, 2), "");
  // Read again in blocks (the backward pass), it is not warned about again.
  const std::string again = logged([&] {
    gtrack::RecordedFrames recording(two_channels.string(), {16, 16}, {0, 1, 2, 3, 4, 5}, 1, 25);
    EXPECT_EQ(recording.read(0, 6).size(), 6u);
  });
  EXPECT_EQ(again, "");

  const fs::path cut = dir / "cut.tif";
  write_described_stack(cut, 4, "ImageJ=1.54f\nimages=300\nframes=300\nfinterval=0.1\n");
  const std::string short_copy = read_all_logged(cut, 1);
  EXPECT_NE(short_copy.find("cut.tif: ImageJ says it holds 300 pages, the file has 4"), std::string::npos)
      << short_copy;

  const fs::path ome = dir / "ome.tif";
  write_described_stack(ome, 8,
                        "<?xml version=\"1.0\"?><OME xmlns=\"http://www.openmicroscopy.org/Schemas/OME/2016-06\">"
                        "<Image ID=\"Image:0\"><Pixels ID=\"Pixels:0\" DimensionOrder=\"XYCZT\" SizeC=\"1\" "
                        "SizeT=\"4\" SizeX=\"16\" SizeY=\"16\" SizeZ=\"2\" Type=\"uint8\"></Pixels></Image></OME>");
  const std::string slices = read_all_logged(ome, 1);
  EXPECT_NE(slices.find("ome.tif: OME-TIFF says it holds 1 channel(s) and 2 z-slice(s) per time point"),
            std::string::npos)
      << slices;
  EXPECT_EQ(slices.find("pages, the file has"), std::string::npos) << slices;

  const fs::path time_first = dir / "time_first.tif";
  write_described_stack(time_first, 8,
                        "<OME><Image><Pixels DimensionOrder=\"XYTCZ\"\nSizeC=\"2\"\tSizeT=\"4\" SizeZ=\"1\">"
                        "</Pixels></Image></OME>");
  const std::string order = read_all_logged(time_first, 2);
  EXPECT_NE(order.find("time_first.tif: OME-TIFF says its pages do not run through time last (2 channel(s)"), std::string::npos)
      << order;

  // Time runs last when what follows it has one element (Z here).
  const fs::path ctz = dir / "ctz.tif";
  write_described_stack(ctz, 8,
                        "<OME><Image><Pixels DimensionOrder=\"XYCTZ\" SizeC=\"2\" SizeT=\"4\" SizeZ=\"1\">"
                        "</Pixels></Image></OME>");
  const std::string ctz_said = read_all_logged(ctz, 1);
  EXPECT_NE(ctz_said.find("ctz.tif: OME-TIFF says it holds 2 channel(s)"), std::string::npos) << ctz_said;
  EXPECT_EQ(read_all_logged(ctz, 2), "");
  // RGB pages: SizeC counts their samples, and each page is one frame.
  const fs::path rgb = dir / "rgb.tif";
  write_described_stack(rgb, 4,
                        "<OME><Image><Pixels DimensionOrder=\"XYCZT\" SizeC=\"3\" SizeT=\"4\" SizeZ=\"1\">"
                        "</Pixels></Image></OME>",
                        3);
  EXPECT_EQ(read_all_logged(rgb, 1), "");
  // Two channels without time points: the slices are the time points.
  const fs::path two_no_frames = dir / "two_no_frames.tif";
  write_described_stack(two_no_frames, 6, "ImageJ=1.54f\nimages=6\nchannels=2\nslices=3\nhyperstack=true\n");
  const std::string no_frames = read_all_logged(two_no_frames, 1);
  EXPECT_NE(no_frames.find("ImageJ says it holds 2 channel(s) and 1 z-slice(s) per time point"), std::string::npos)
      << no_frames;

  // A plain ImageJ stack (ImageJ calls its unlabelled pages slices) is a
  // recording: not warned about.
  const fs::path plain_imagej = dir / "plain_imagej.tif";
  write_described_stack(plain_imagej, 6, "ImageJ=1.54f\nimages=6\nslices=6\nloop=false\n");
  EXPECT_EQ(read_all_logged(plain_imagej, 1), "");

  // A stack that says nothing of its layout, or says it holds what it
  // holds, is read without a word.
  const fs::path plain = dir / "plain.tif";
  write_described_stack(plain, 3, "");
  EXPECT_EQ(read_all_logged(plain, 1), "");
  write_described_stack(plain, 3, "ImageJ=1.54f\nimages=3\nframes=3\n");
  EXPECT_EQ(read_all_logged(plain, 1), "");
}

// Images of other depths than 8 and 16 bits (float, signed) are refused in
// one line naming the image, not tracked as black.
TEST(FrameSource, AFloatImageIsRefusedNamingIt) {
  const fs::path dir = folder_of("float_images", {});
  ASSERT_TRUE(cv::imwrite((dir / "f0.tif").string(), cv::Mat(8, 8, CV_32FC1, cv::Scalar(0.7))));
  auto src = gtrack::open_frame_source(dir.string(), {8, 8}, {}, 25);
  try {
    src->next();
    FAIL() << "a float image was read";
  } catch (const gtrack::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("f0.tif: a 32-bit float image; expected 8 or 16 bits"), std::string::npos)
        << e.what();
  }
}

// A PNG whose header claims 60000 x 60000 pixels (68 bytes in all): its
// size is refused from its header, before it is decoded; for a sensor of
// that size, OpenCV refuses it with an assertion. Either error is one line
// naming the file.
TEST(FrameSource, AnImageWhoseHeaderIsTooLargeIsRefusedNamingIt) {
  const fs::path dir = folder_of("header_too_large", {});
  const unsigned char png[] = {
      0x89, 0x50, 0x4e, 0x47, 0x0d, 0x0a, 0x1a, 0x0a, 0x00, 0x00, 0x00, 0x0d, 0x49, 0x48, 0x44, 0x52, 0x00,
      0x00, 0xea, 0x60, 0x00, 0x00, 0xea, 0x60, 0x08, 0x02, 0x00, 0x00, 0x00, 0x0f, 0xb0, 0xe2, 0x15, 0x00,
      0x00, 0x00, 0x0b, 0x49, 0x44, 0x41, 0x54, 0x78, 0xda, 0x63, 0x60, 0x40, 0x06, 0x00, 0x00, 0x0e, 0x00,
      0x01, 0x3a, 0x35, 0x04, 0x56, 0x00, 0x00, 0x00, 0x00, 0x49, 0x45, 0x4e, 0x44, 0xae, 0x42, 0x60, 0x82};
  std::ofstream(dir / "000000.png", std::ios::binary).write(reinterpret_cast<const char*>(png), sizeof png);
  try {
    gtrack::open_frame_source(dir.string(), {8, 8}, {}, 25)->next();
    FAIL() << "an image of 60000 x 60000 pixels was read";
  } catch (const gtrack::InputError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("000000.png: image is 60000x60000 but the sensor expects 8x8"), std::string::npos) << what;
    EXPECT_EQ(what.find('\n'), std::string::npos) << what;
  }
  try {
    gtrack::open_frame_source(dir.string(), {60000, 60000}, {}, 25)->next();
    FAIL() << "an image of 60000 x 60000 pixels was read";
  } catch (const gtrack::InputError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("000000.png: cannot read the image"), std::string::npos) << what;
    EXPECT_NE(what.find("its header gives a size above the 2^30 pixels OpenCV decodes"), std::string::npos) << what;
    EXPECT_EQ(what.find('\n'), std::string::npos) << what;
  }
}

// An image of another size than the sensor's is refused from its header,
// before its pixels are decoded: each kind cut right after its header
// (which no decoder reads) gives the size it says. The same cut at the
// sensor's size is left to the decoder, which cannot read it.
TEST(FrameSource, AnImageOfAnotherSizeIsRefusedFromItsHeader) {
  const fs::path dir = folder_of("header_size", {});
  cv::Mat img(30, 40, CV_8UC3);
  cv::randu(img, 0, 255);
  const auto bytes_of = [&](const std::string& ext) {
    std::vector<uchar> buf;
    EXPECT_TRUE(cv::imencode(ext, ext == ".pgm" ? cv::Mat(30, 40, CV_8UC1, cv::Scalar(7)) : img, buf));
    return std::string(buf.begin(), buf.end());
  };
  // Where each header ends: PNG's IHDR chunk; JPEG's frame header (SOF0);
  // BMP's file and info headers; PGM's text header.
  const std::string jpeg = bytes_of(".jpg");
  const size_t sof = jpeg.find("\xFF\xC0");
  ASSERT_NE(sof, std::string::npos);
  const std::vector<std::pair<std::string, std::string>> cut = {
      {"a.png", bytes_of(".png").substr(0, 33)},
      {"a.jpg", jpeg.substr(0, sof + 9)},
      {"a.bmp", bytes_of(".bmp").substr(0, 54)},
      {"a.pgm", bytes_of(".pgm").substr(0, 13)},
  };
  for (const auto& [name, bytes] : cut) {
    const fs::path one = dir / name.substr(2);
    fs::create_directories(one);
    std::ofstream(one / name, std::ios::binary) << bytes;
    try {
      gtrack::open_frame_source(one.string(), {64, 48}, {}, 25)->next();
      FAIL() << name << ": read";
    } catch (const gtrack::InputError& e) {
      const std::string what = e.what();
      EXPECT_NE(what.find(name + ": image is 40x30 but the sensor expects 64x48"), std::string::npos) << what;
    }
    // The sensor's size, or the same turned (an orientation tag may turn
    // a decoded image): the decoder has the last word.
    for (const gtrack::ImageSize sensor : {gtrack::ImageSize{40, 30}, gtrack::ImageSize{30, 40}}) {
      try {
        if (auto f = gtrack::open_frame_source(one.string(), sensor, {}, 25)->next()) {
          EXPECT_EQ(f->image.cols, sensor.width) << name;  // a decoder that takes what it has
        }
      } catch (const gtrack::InputError& e) {
        EXPECT_EQ(std::string(e.what()).find("image is 40x30"), std::string::npos) << e.what();
      }
    }
  }
}
