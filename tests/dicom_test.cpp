// DICOM input: a scanner's multi-frame file (native, JPEG, JPEG 2000 or
// RLE frames) read frame by frame, its frame rate taken, and what it cannot
// take refused in a line; a B-mode cine loop tracked as its frames are.
#include <gtest/gtest.h>
#include <gtrack/frame_source.hpp>

#include <array>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>
#include <string>
#include <thread>
#include <vector>

#include "gtrack/error.hpp"
#include "support/dicom_writer.hpp"
#include "support/scoped_env.hpp"

namespace fs = std::filesystem;
using gtrack::testing::DicomWriteOptions;
using gtrack::testing::write_dicom;

namespace {

fs::path dir_for(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() / "gtrack_dicom_test" / name;
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

// Frames unlike each other and unlike their mirror: a gradient, a
// square that moves, noise.
std::vector<cv::Mat> frames(int n, int type = CV_8UC1, int w = 40, int h = 30) {
  std::vector<cv::Mat> out;
  cv::RNG rng(7);
  for (int i = 0; i < n; ++i) {
    cv::Mat m(h, w, type);
    rng.fill(m, cv::RNG::UNIFORM, 0, type == CV_16UC1 ? 4096 : 256);
    cv::rectangle(m, cv::Rect(2 + 5 * i, 3, 8, 6), cv::Scalar::all(type == CV_16UC1 ? 4095 : 255), cv::FILLED);
    out.push_back(m);
  }
  return out;
}

std::vector<cv::Mat> read_all(const fs::path& file, cv::Size size, double* fps = nullptr, std::string* what = nullptr) {
  auto src = gtrack::open_frame_source(file.string(), {size.width, size.height}, {}, 30);
  if (fps) *fps = src->fps();
  if (what) *what = src->description();
  std::vector<cv::Mat> out;
  while (auto f = src->next()) out.push_back(f->image);
  return out;
}

cv::Mat bgr(const cv::Mat& m) {
  cv::Mat out;
  if (m.channels() == 1) {
    cv::cvtColor(m, out, cv::COLOR_GRAY2BGR);
  } else {
    out = m;
  }
  return out;
}

// A whole file, byte for byte.
std::string file_bytes(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

bool same(const cv::Mat& a, const cv::Mat& b) {
  return a.size() == b.size() && a.type() == b.type() && cv::norm(a, b, cv::NORM_INF) == 0;
}

std::string input_error(const fs::path& file, cv::Size size = {40, 30}) {
  try {
    read_all(file, size);
  } catch (const gtrack::InputError& e) {
    return e.what();
  }
  return "";
}

}  // namespace

// Native grey frames, in explicit VR with the file meta group and in a
// bare implicit-VR dataset (with a sequence of undefined length before the
// image): the frames written, at the rate of the file's frame time.
TEST(Dicom, NativeFramesAreTheImagesWrittenAtTheFilesRate) {
  const fs::path dir = dir_for("native");
  const auto written = frames(3);
  DicomWriteOptions o;
  o.frame_time_ms = 40;
  write_dicom(dir / "cine.dcm", written, o);
  double fps = 0;
  std::string what;
  auto got = read_all(dir / "cine.dcm", {40, 30}, &fps, &what);
  ASSERT_EQ(got.size(), 3u);
  for (int i = 0; i < 3; ++i) EXPECT_TRUE(same(got[i], bgr(written[i]))) << "frame " << i;
  EXPECT_DOUBLE_EQ(fps, 25);
  EXPECT_NE(what.find("a DICOM file of 3 frames, explicit VR little endian"), std::string::npos) << what;

  DicomWriteOptions bare;
  bare.transfer_syntax = "1.2.840.10008.1.2";
  bare.preamble = false;
  bare.sequence_before = true;
  write_dicom(dir / "bare.dcm", written, bare);
  got = read_all(dir / "bare.dcm", {40, 30}, &fps);
  ASSERT_EQ(got.size(), 3u);
  for (int i = 0; i < 3; ++i) EXPECT_TRUE(same(got[i], bgr(written[i]))) << "frame " << i;
  EXPECT_DOUBLE_EQ(fps, 0) << "no frame time: no rate of its own, as a folder";
  {
    auto src = gtrack::open_frame_source((dir / "bare.dcm").string(), {40, 30}, {}, 20);
    src->next();
    EXPECT_DOUBLE_EQ(src->next()->time_s, 1.0 / 20) << "its frames' times at the rate taken";
  }
  DicomWriteOptions vector;
  vector.frame_time_vector = "0\\40\\40";
  write_dicom(dir / "vector.dcm", written, vector);
  read_all(dir / "vector.dcm", {40, 30}, &fps);
  EXPECT_DOUBLE_EQ(fps, 25) << "the frame time vector's mean after its first entry";
  EXPECT_FALSE(gtrack::open_frame_source((dir / "bare.dcm").string(), {40, 30}, {}, 30)->pixel_size_mm())
      << "a region with no pixel size gives none";
  DicomWriteOptions region;
  region.region_cm_x = 0.009;
  region.region_cm_y = 0.0095;
  for (const char* syntax : {"1.2.840.10008.1.2.1", "1.2.840.10008.1.2"}) {
    region.transfer_syntax = syntax;
    write_dicom(dir / "region.dcm", written, region);
    const auto pixel = gtrack::open_frame_source((dir / "region.dcm").string(), {40, 30}, {}, 30)->pixel_size_mm();
    ASSERT_TRUE(pixel) << syntax;
    EXPECT_NEAR(pixel->first, 0.09, 1e-12) << syntax;
    EXPECT_NEAR(pixel->second, 0.095, 1e-12) << syntax;
  }

  // Without a region, Pixel Spacing (row spacing, then column spacing, mm);
  // a region, when there is one, is what an ultrasound image is measured by.
  DicomWriteOptions spacing;
  spacing.pixel_spacing = "0.12\\0.1";
  write_dicom(dir / "spacing.dcm", written, spacing);
  const auto spaced = gtrack::open_frame_source((dir / "spacing.dcm").string(), {40, 30}, {}, 30)->pixel_size_mm();
  ASSERT_TRUE(spaced);
  EXPECT_DOUBLE_EQ(spaced->first, 0.1);
  EXPECT_DOUBLE_EQ(spaced->second, 0.12);
  spacing.region_cm_x = spacing.region_cm_y = 0.009;
  write_dicom(dir / "spacing.dcm", written, spacing);
  EXPECT_DOUBLE_EQ(gtrack::open_frame_source((dir / "spacing.dcm").string(), {40, 30}, {}, 30)->pixel_size_mm()->first,
                   0.09);

  // Scanners export without an extension: "DICM" at byte 128 says what it is.
  fs::copy_file(dir / "cine.dcm", dir / "IM_0001");
  EXPECT_EQ(read_all(dir / "IM_0001", {40, 30}).size(), 3u);
  // A range and a stride count from the file's first frame.
  auto src = gtrack::open_frame_source((dir / "cine.dcm").string(), {40, 30}, {1, -1, 1}, 30);
  std::vector<int> indices;
  while (auto f = src->next()) indices.push_back(f->index);
  EXPECT_EQ(indices, (std::vector<int>{1, 2}));
  // Read again in blocks, as --two-pass does.
  gtrack::RecordedFrames recording((dir / "cine.dcm").string(), {40, 30}, {0, 1, 2}, 1, 30);
  EXPECT_TRUE(same(recording.read(2, 3).at(2), bgr(written[2])));
}

// A folder of single-frame DICOM files (one file per frame) is read as a
// folder of images; a multi-frame file in it is refused, pointing to it.
TEST(Dicom, AFolderOfSingleFrameFilesIsAFolderOfImages) {
  const fs::path dir = dir_for("folder");
  const auto written = frames(3);
  for (int i = 0; i < 3; ++i) write_dicom(dir / ("IM" + std::to_string(i) + ".dcm"), {written[static_cast<std::size_t>(i)]});
  const auto got = read_all(dir, {40, 30});
  ASSERT_EQ(got.size(), 3u);
  for (int i = 0; i < 3; ++i) EXPECT_TRUE(same(got[i], bgr(written[i]))) << "frame " << i;
  // A scanner's export: IM_0001, ... with no extension, beside its index.
  const fs::path exported = dir_for("exported");
  for (int i = 0; i < 3; ++i) {
    write_dicom(exported / ("IM_000" + std::to_string(i + 1)), {written[static_cast<std::size_t>(i)]});
  }
  std::ofstream(exported / "DICOMDIR") << std::string(128, '\0') << "DICM";
  std::ofstream(exported / "README") << "not an image";
  const auto from_export = read_all(exported, {40, 30});
  ASSERT_EQ(from_export.size(), 3u);
  EXPECT_TRUE(same(from_export[2], bgr(written[2])));
  EXPECT_FALSE(gtrack::open_frame_source(exported.string(), {40, 30}, {}, 30)->pixel_size_mm());
  // An export that names its files by their UIDs: the last part of the
  // name reads as an extension of digits. Each is looked at, in the order
  // of its numbers; a text file so named is not an image.
  const fs::path by_uid = dir_for("by_uid");
  for (int i = 0; i < 3; ++i) {
    write_dicom(by_uid / ("1.2.840.113619.2.55." + std::to_string(9 - 4 * i)), {written[static_cast<std::size_t>(2 - i)]});
  }
  std::ofstream(by_uid / "notes.2024") << "not an image";
  const auto from_uids = read_all(by_uid, {40, 30});
  ASSERT_EQ(from_uids.size(), 3u);
  for (int i = 0; i < 3; ++i) EXPECT_TRUE(same(from_uids[i], bgr(written[i]))) << "frame " << i;
  // Its pixel size is its first file's, as a multi-frame file's is (a
  // folder's had gone unchecked against the sensor's).
  DicomWriteOptions region;
  region.region_cm_x = region.region_cm_y = 0.012;
  write_dicom(exported / "IM_0001", {written[0]}, region);
  const auto pixel = gtrack::open_frame_source(exported.string(), {40, 30}, {}, 30)->pixel_size_mm();
  ASSERT_TRUE(pixel);
  EXPECT_DOUBLE_EQ(pixel->first, 0.12);
  // The index itself as --input: said to be one, not tried as a video.
  EXPECT_NE(input_error(exported / "DICOMDIR").find("DICOMDIR: a DICOMDIR, the index of a scanner's export, holds no "
                                                     "frames; give the folder of the images it lists"),
            std::string::npos)
      << input_error(exported / "DICOMDIR");
  write_dicom(dir / "IM3.dcm", written);
  const std::string e = input_error(dir);
  EXPECT_NE(e.find("IM3.dcm: a DICOM file of 3 frames in a folder of images; give the file itself as --input"),
            std::string::npos)
      << e;
  // Followed, it is refused at once: no writer will change what it is.
  const fs::path followed = dir_for("folder_followed");
  write_dicom(followed / "IM3.dcm", written);
  gtrack::FollowOptions follow;
  follow.idle_s = 20;
  const auto start = std::chrono::steady_clock::now();
  try {
    gtrack::open_frame_source(followed.string(), {40, 30}, {}, 30, follow)->next();
    ADD_FAILURE() << "a multi-frame file in a followed folder was taken";
  } catch (const gtrack::InputError& refused) {
    EXPECT_EQ(std::string(refused.what()).find("unchanged for"), std::string::npos) << refused.what();
  }
  EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(), 10.0);
}

// A followed folder: a scanner's IM_0001 whose size was set before its
// bytes were written is taken once "DICM" is there, not passed over.
TEST(Dicom, AFollowedFoldersFileWithoutAnExtensionIsTakenOnceItSaysDicom) {
  const fs::path dir = dir_for("followed");
  const fs::path staged = dir_for("followed_staged") / "IM_0001";
  const auto written = frames(1);
  write_dicom(staged, written);
  const auto size = fs::file_size(staged);
  std::ofstream(dir / "IM_0001", std::ios::binary) << std::string(size, '\0');  // the size first
  std::thread writer([&] {
    std::this_thread::sleep_for(std::chrono::milliseconds(300));
    std::ifstream in(staged, std::ios::binary);
    std::ofstream out(dir / "IM_0001", std::ios::binary | std::ios::in | std::ios::out);
    out << in.rdbuf();
  });
  gtrack::FollowOptions follow;
  follow.idle_s = 3;
  auto src = gtrack::open_frame_source(dir.string(), {40, 30}, {}, 30, follow);
  const auto f = src->next();
  writer.join();
  ASSERT_TRUE(f);
  EXPECT_TRUE(same(f->image, bgr(written[0])));
}

// Colour (RGB interleaved and planar, YBR_FULL_422), 16-bit samples of 12
// stored bits, and MONOCHROME1's inverted grey.
TEST(Dicom, ColourSixteenBitAndInvertedGreyFramesAreTakenAsTheFileSays) {
  const fs::path dir = dir_for("kinds");
  const auto colour = frames(2, CV_8UC3);
  for (int planar : {0, 1}) {
    DicomWriteOptions o;
    o.planar = planar;
    write_dicom(dir / "colour.dcm", colour, o);
    const auto got = read_all(dir / "colour.dcm", {40, 30});
    ASSERT_EQ(got.size(), 2u);
    EXPECT_TRUE(same(got[1], colour[1])) << "planar " << planar;
  }
  // YBR_FULL_422: each two pixels share their colour (blocks of even width here).
  cv::Mat blocks(30, 40, CV_8UC3);
  for (int x = 0; x < 40; x += 2) {
    blocks.colRange(x, x + 2).setTo(cv::Scalar(6 * x, 255 - 6 * x, 3 * x + 40));
  }
  DicomWriteOptions ybr;
  ybr.photometric = "YBR_FULL_422";
  write_dicom(dir / "ybr422.dcm", {blocks}, ybr);
  const auto got422 = read_all(dir / "ybr422.dcm", {40, 30});
  ASSERT_EQ(got422.size(), 1u);
  EXPECT_LE(cv::norm(got422[0], blocks, cv::NORM_INF), 3) << "within the colour conversion's rounding";
  // 12 bits stored in the high bits (high bit 15), and 12 bits with a bit
  // above them set (an overlay bit): the stored bits only.
  DicomWriteOptions high;
  high.bits_stored = 12;
  high.high_bit = 15;
  write_dicom(dir / "high.dcm", {cv::Mat(30, 40, CV_16UC1, cv::Scalar(2048 << 4))}, high);
  auto high_got = read_all(dir / "high.dcm", {40, 30});
  ASSERT_EQ(high_got.size(), 1u);
  EXPECT_EQ(high_got[0].at<cv::Vec3b>(5, 5), cv::Vec3b::all(128));
  DicomWriteOptions overlay;
  overlay.bits_stored = 12;
  write_dicom(dir / "overlay.dcm", {cv::Mat(30, 40, CV_16UC1, cv::Scalar(0x8000 | 2048))}, overlay);
  high_got = read_all(dir / "overlay.dcm", {40, 30});
  ASSERT_EQ(high_got.size(), 1u);
  EXPECT_EQ(high_got[0].at<cv::Vec3b>(5, 5), cv::Vec3b::all(128));
  std::vector<cv::Mat> twelve = {cv::Mat(30, 40, CV_16UC1, cv::Scalar(4095)), cv::Mat(30, 40, CV_16UC1, cv::Scalar(2048))};
  DicomWriteOptions o12;
  o12.bits_stored = 12;
  write_dicom(dir / "twelve.dcm", twelve, o12);
  auto got = read_all(dir / "twelve.dcm", {40, 30});
  ASSERT_EQ(got.size(), 2u);
  EXPECT_EQ(got[0].at<cv::Vec3b>(5, 5), cv::Vec3b::all(255));
  EXPECT_EQ(got[1].at<cv::Vec3b>(5, 5), cv::Vec3b::all(128));
  DicomWriteOptions inverted;
  inverted.photometric = "MONOCHROME1";
  write_dicom(dir / "inverted.dcm", {cv::Mat(30, 40, CV_8UC1, cv::Scalar(10))}, inverted);
  got = read_all(dir / "inverted.dcm", {40, 30});
  ASSERT_EQ(got.size(), 1u);
  EXPECT_EQ(got[0].at<cv::Vec3b>(5, 5), cv::Vec3b::all(245));
}

// Compressed frames: JPEG with a fragment per frame, JPEG split in
// fragments found by the offset table, and JPEG 2000.
TEST(Dicom, CompressedFramesAreDecodedFrameByFrame) {
  const fs::path dir = dir_for("compressed");
  const auto written = frames(3, CV_8UC3, 64, 48);
  std::vector<cv::Mat> jpeg;
  for (const cv::Mat& f : written) {
    std::vector<unsigned char> bytes;
    cv::imencode(".jpg", f, bytes);
    jpeg.push_back(cv::imdecode(bytes, cv::IMREAD_COLOR));
  }
  DicomWriteOptions o;
  o.transfer_syntax = "1.2.840.10008.1.2.4.50";
  o.compress_as = ".jpg";
  o.photometric = "YBR_FULL_422";
  write_dicom(dir / "jpeg.dcm", written, o);
  auto got = read_all(dir / "jpeg.dcm", {64, 48});
  ASSERT_EQ(got.size(), 3u);
  for (int i = 0; i < 3; ++i) EXPECT_TRUE(same(got[i], jpeg[i])) << "frame " << i;
  o.fragments_per_frame = 2;
  o.offset_table = true;
  write_dicom(dir / "fragments.dcm", written, o);
  got = read_all(dir / "fragments.dcm", {64, 48});
  ASSERT_EQ(got.size(), 3u);
  for (int i = 0; i < 3; ++i) EXPECT_TRUE(same(got[i], jpeg[i])) << "frame " << i;
  // No offset table: each frame starts at a fragment that starts a JPEG.
  o.offset_table = false;
  write_dicom(dir / "untabled.dcm", written, o);
  got = read_all(dir / "untabled.dcm", {64, 48});
  ASSERT_EQ(got.size(), 3u);
  for (int i = 0; i < 3; ++i) EXPECT_TRUE(same(got[i], jpeg[i])) << "frame " << i;
  // A JPEG of RGB samples with no marker saying so (the DICOM header says
  // RGB) is decoded without a colour transform: here the encoder's YCbCr
  // samples, shown as R, G and B.
  DicomWriteOptions rgb = o;
  rgb.photometric = "RGB";
  rgb.strip_jfif = true;
  write_dicom(dir / "rgb_jpeg.dcm", written, rgb);
  got = read_all(dir / "rgb_jpeg.dcm", {64, 48});
  ASSERT_EQ(got.size(), 3u);
  cv::Mat ycc;
  cv::cvtColor(jpeg[0], ycc, cv::COLOR_BGR2YCrCb);  // Y, Cr, Cb
  std::vector<cv::Mat> c;
  cv::split(ycc, c);
  cv::Mat expected;
  cv::merge(std::vector<cv::Mat>{c[1], c[2], c[0]}, expected);  // B = Cr, G = Cb, R = Y
  // (Within the rounding and clipping of the noise's saturated colours.)
  EXPECT_LE(cv::norm(got[0], expected, cv::NORM_L1) / static_cast<double>(got[0].total() * 3), 2.0);
  EXPECT_GE(cv::norm(jpeg[0], expected, cv::NORM_L1) / static_cast<double>(got[0].total() * 3), 20.0)
      << "the test tells the two decodings apart";
  // The same stream with its JFIF marker is YCbCr, whatever the header says.
  rgb.strip_jfif = false;
  write_dicom(dir / "rgb_jfif.dcm", written, rgb);
  got = read_all(dir / "rgb_jfif.dcm", {64, 48});
  ASSERT_EQ(got.size(), 3u);
  EXPECT_TRUE(same(got[0], jpeg[0]));
  // Only the end mark missing: every frame is whole, and none is dropped.
  std::string bytes = file_bytes(dir / "jpeg.dcm");
  std::ofstream(dir / "no_end.dcm", std::ios::binary) << bytes.substr(0, bytes.size() - 8);
  auto no_end = gtrack::open_frame_source((dir / "no_end.dcm").string(), {64, 48}, {}, 30);
  EXPECT_EQ(no_end->frame_count(), 3);
  EXPECT_EQ(no_end->ended_early(), "");

  std::vector<unsigned char> probe;
  bool j2k = false;
  try {
    j2k = cv::imencode(".jp2", written[0], probe);
  } catch (const cv::Exception&) {
    j2k = false;
  }
  if (j2k) {
    DicomWriteOptions o2;
    o2.transfer_syntax = "1.2.840.10008.1.2.4.90";
    o2.compress_as = ".jp2";
    write_dicom(dir / "j2k.dcm", written, o2);
    got = read_all(dir / "j2k.dcm", {64, 48});
    ASSERT_EQ(got.size(), 3u);
    for (int i = 0; i < 3; ++i) {
      std::vector<unsigned char> bytes;
      cv::imencode(".jp2", written[static_cast<std::size_t>(i)], bytes);
      EXPECT_TRUE(same(got[i], cv::imdecode(bytes, cv::IMREAD_COLOR))) << "frame " << i;
    }
  }
}

// RLE lossless frames (PS3.5 annex G), grey, 16-bit and colour: the
// frames written, as their native file gives them.
TEST(Dicom, RleFramesAreTheImagesWritten) {
  const fs::path dir = dir_for("rle");
  DicomWriteOptions o;
  o.transfer_syntax = "1.2.840.10008.1.2.5";
  o.compress_as = ".rle";
  // Grey, with runs (the square, a flat band) and noise.
  auto grey = frames(3, CV_8UC1, 300, 30);
  for (cv::Mat& f : grey) f.colRange(100, 290).setTo(77);
  write_dicom(dir / "grey.dcm", grey, o);
  auto got = read_all(dir / "grey.dcm", {300, 30});
  ASSERT_EQ(got.size(), 3u);
  for (int i = 0; i < 3; ++i) EXPECT_TRUE(same(got[i], bgr(grey[i]))) << "frame " << i;
  // 12 bits stored in 16, and colour (planar or not in the header: RLE's
  // segments are planes either way), each against its native file.
  DicomWriteOptions twelve = o;
  twelve.bits_stored = 12;
  DicomWriteOptions colour = o;
  colour.planar = 1;
  for (const auto& [written, opt] : {std::pair{frames(2, CV_16UC1), twelve}, std::pair{frames(2, CV_8UC3), colour},
                                     std::pair{frames(2, CV_8UC3), o}}) {
    write_dicom(dir / "rle.dcm", written, opt);
    DicomWriteOptions native = opt;
    native.transfer_syntax = "1.2.840.10008.1.2.1";
    native.compress_as.clear();
    write_dicom(dir / "native.dcm", written, native);
    got = read_all(dir / "rle.dcm", {40, 30});
    const auto expected = read_all(dir / "native.dcm", {40, 30});
    ASSERT_EQ(got.size(), 2u);
    for (int i = 0; i < 2; ++i) EXPECT_TRUE(same(got[i], expected[i])) << "frame " << i;
  }
  EXPECT_GT(cv::norm(got[0], got[1], cv::NORM_INF), 0) << "frames unlike each other";
  // The most significant bytes' segment first: 0xFF00 and 0x00FF, a
  // frame made by hand (literal runs, padded with the no-op 0x80).
  const std::string header = std::string("\x02\0\0\0\x40\0\0\0\x46\0\0\0", 12) + std::string(52, '\0');
  DicomWriteOptions hand = o;
  hand.encoded = {header + std::string("\x03\xFF\x00\xFF\x00\x80", 6) + std::string("\x03\x00\xFF\x00\xFF\x80", 6)};
  write_dicom(dir / "hand.dcm", {cv::Mat(2, 2, CV_16UC1)}, hand);
  got = read_all(dir / "hand.dcm", {2, 2});
  ASSERT_EQ(got.size(), 1u);
  EXPECT_EQ(got[0].at<cv::Vec3b>(0, 0), cv::Vec3b::all(254));
  EXPECT_EQ(got[0].at<cv::Vec3b>(0, 1), cv::Vec3b::all(1));
  // A replicate run (-3: the byte 4 times) fills a grey 2x2 frame.
  hand.encoded = {std::string("\x01\0\0\0\x40\0\0\0", 8) + std::string(56, '\0') + std::string("\xFD\x2A", 2)};
  write_dicom(dir / "run.dcm", {cv::Mat(2, 2, CV_8UC1)}, hand);
  got = read_all(dir / "run.dcm", {2, 2});
  ASSERT_EQ(got.size(), 1u);
  EXPECT_EQ(cv::countNonZero(got[0].reshape(1) == 42), 12);
  // A segment that ends short, and a header with the wrong segment count:
  // one line naming the frame.
  hand.encoded = {std::string("\x01\0\0\0\x40\0\0\0", 8) + std::string(56, '\0') + std::string("\xFE\x2A", 2)};
  write_dicom(dir / "short.dcm", {cv::Mat(2, 2, CV_8UC1)}, hand);
  std::string e = input_error(dir / "short.dcm", {2, 2});
  EXPECT_NE(e.find("short.dcm frame 0: its RLE segment 1 decodes to 3 bytes; expected 4 (2x2 pixels)"),
            std::string::npos)
      << e;
  write_dicom(dir / "count.dcm", {cv::Mat(30, 40, CV_8UC3, cv::Scalar::all(9))}, o);
  std::string bytes = file_bytes(dir / "count.dcm");
  const std::size_t at = bytes.find(std::string("\x03\0\0\0\x40\0\0\0", 8));
  ASSERT_NE(at, std::string::npos);
  bytes[at] = 1;
  std::ofstream(dir / "count.dcm", std::ios::binary) << bytes;
  e = input_error(dir / "count.dcm");
  EXPECT_NE(e.find("count.dcm frame 0: its RLE header gives 1 segments; expected 3 (3 sample(s) of 8 bits)"),
            std::string::npos)
      << e;
  EXPECT_EQ(e.find('\n'), std::string::npos) << e;
  // RLE keeps every sample: YBR_FULL_422 is no RLE frame.
  DicomWriteOptions ybr = o;
  ybr.photometric = "YBR_FULL_422";
  write_dicom(dir / "ybr.dcm", frames(1, CV_8UC3), ybr);
  e = input_error(dir / "ybr.dcm");
  EXPECT_NE(e.find("ybr.dcm: RLE lossless frames in photometric interpretation YBR_FULL_422"), std::string::npos)
      << e;
}

// A cine loop stored as a video stream (MPEG-2, H.264, and H.264's
// fragmentable form): its frames, in order and at the file's rate, decoded
// by the video reader from a copy of the stream that is gone as soon as the
// reader has it; a stream cut short gives its frames up to the cut, a stream
// short of the file's count says so; a folder of images refuses it, and a
// stream that does not decode is one line.
TEST(Dicom, AVideoStreamIsReadAsItsFrames) {
  const fs::path dir = dir_for("video");
  const fs::path tmp = dir / "tmp";
  fs::create_directories(tmp);
  const gtrack::testing::ScopedEnv tmpdir("TMPDIR", tmp.string());
  // A smooth picture with a square that moves: frames a lossy codec keeps
  // apart.
  std::vector<cv::Mat> written;
  for (int i = 0; i < 12; ++i) {
    cv::Mat m(96, 128, CV_8UC3);
    for (int y = 0; y < m.rows; ++y) m.row(y).setTo(cv::Scalar(40 + y, 60, 200 - y));
    cv::rectangle(m, cv::Rect(8 + 8 * i, 30, 24, 24), cv::Scalar::all(240), cv::FILLED);
    written.push_back(m);
  }
  const auto stream_of = [&](const char* file, int fourcc) {
    {
      cv::VideoWriter w((dir / file).string(), cv::CAP_FFMPEG, fourcc, 25, {128, 96});
      if (!w.isOpened()) return std::string();
      for (const cv::Mat& m : written) w << m;
    }
    return file_bytes(dir / file);
  };
  const std::string mpeg2 = stream_of("stream.mpg", cv::VideoWriter::fourcc('M', 'P', 'G', '2'));
  const std::string h264 = stream_of("stream.ts", cv::VideoWriter::fourcc('H', '2', '6', '4'));
  if (mpeg2.empty() || h264.empty()) GTEST_SKIP() << "this machine's OpenCV writes no MPEG-2 or no H.264 video";
  // HEVC where the machine's encoder has it (Debian's does, through x265).
  const std::string hevc = stream_of("stream_hevc.ts", cv::VideoWriter::fourcc('H', 'E', 'V', 'C'));
  DicomWriteOptions o;
  o.fragments_per_frame = 3;
  o.frame_time_ms = 50;
  o.photometric = "YBR_PARTIAL_420";
  for (const auto& [syntax, stream] : {std::pair<std::string, std::string>{"1.2.840.10008.1.2.4.100", mpeg2},
                                       {"1.2.840.10008.1.2.4.107", hevc},
                                       {"1.2.840.10008.1.2.4.102", h264},
                                       {"1.2.840.10008.1.2.4.102.1", h264}}) {
    SCOPED_TRACE(syntax);
    if (stream.empty()) continue;
    o.transfer_syntax = syntax;
    o.video = stream;
    write_dicom(dir / "video.dcm", written, o);
    auto src = gtrack::open_frame_source((dir / "video.dcm").string(), {128, 96}, {}, 30);
    EXPECT_TRUE(fs::is_empty(tmp)) << "the stream's copy is gone once the decoder has it";
    EXPECT_DOUBLE_EQ(src->fps(), 20) << "the file's frame time, not the stream's rate";
    std::vector<cv::Mat> got;
    while (auto f = src->next()) {
      EXPECT_EQ(f->name, (dir / "video.dcm").string() + " frame " + std::to_string(f->index));
      EXPECT_DOUBLE_EQ(f->time_s, f->index / 20.0);
      got.push_back(f->image);
    }
    ASSERT_EQ(got.size(), written.size());
    for (std::size_t i = 0; i < got.size(); ++i) {
      const double here = cv::norm(got[i], written[i], cv::NORM_L1) / static_cast<double>(got[i].total() * 3);
      EXPECT_LE(here, 6.0) << "frame " << i;
      const std::size_t other = i + 1 < got.size() ? i + 1 : i - 1;
      EXPECT_LT(here, cv::norm(got[i], written[other], cv::NORM_L1) / static_cast<double>(got[i].total() * 3))
          << "frame " << i << " is the frame written there, not its neighbour";
    }
    EXPECT_EQ(src->ended_early(), "");
  }
  EXPECT_NE(gtrack::open_frame_source((dir / "video.dcm").string(), {128, 96}, {}, 30)->description().find(
                "fragmentable MPEG-4 AVC/H.264 video (1.2.840.10008.1.2.4.102.1)"),
            std::string::npos);
  std::string bytes = file_bytes(dir / "video.dcm");
  // Only the end mark missing: every frame, and nothing said.
  std::ofstream(dir / "no_end.dcm", std::ios::binary) << bytes.substr(0, bytes.size() - 8);
  EXPECT_EQ(read_all(dir / "no_end.dcm", {128, 96}).size(), 12u);
  auto no_end = gtrack::open_frame_source((dir / "no_end.dcm").string(), {128, 96}, {}, 30);
  while (no_end->next()) {
  }
  EXPECT_EQ(no_end->ended_early(), "");
  // Cut within its last fragment: the frames before the cut, and why.
  std::ofstream(dir / "cut.dcm", std::ios::binary) << bytes.substr(0, bytes.size() - 8 - 300);
  auto cut = gtrack::open_frame_source((dir / "cut.dcm").string(), {128, 96}, {}, 30);
  int n = 0;
  while (cut->next()) ++n;
  EXPECT_GT(n, 0);
  EXPECT_LT(n, 12);
  EXPECT_NE(cut->ended_early().find("its compressed pixel data ends within a fragment"), std::string::npos)
      << cut->ended_early();
  // A file that says 20 frames over a stream of 12; a stream with no rate
  // in the file takes the stream's.
  std::vector<cv::Mat> twenty = written;
  twenty.resize(20, written.back());
  DicomWriteOptions no_rate = o;
  no_rate.frame_time_ms = 0;
  write_dicom(dir / "twenty.dcm", twenty, no_rate);
  auto short_stream = gtrack::open_frame_source((dir / "twenty.dcm").string(), {128, 96}, {}, 30);
  EXPECT_DOUBLE_EQ(short_stream->fps(), 25) << "the stream's own rate";
  n = 0;
  while (short_stream->next()) ++n;
  EXPECT_EQ(n, 12);
  EXPECT_EQ(short_stream->ended_early(), "its video stream holds 12 frames; the file says 20 (0028,0008)");
  // Not when the range ends first.
  auto ranged = gtrack::open_frame_source((dir / "twenty.dcm").string(), {128, 96}, {0, 5, 1}, 30);
  while (ranged->next()) {
  }
  EXPECT_EQ(ranged->ended_early(), "");
  // In a folder of images: refused, pointing to --input.
  const fs::path folder = dir / "folder";
  fs::create_directories(folder);
  fs::copy_file(dir / "video.dcm", folder / "IM_0001");
  std::string e = input_error(folder, {128, 96});
  EXPECT_NE(e.find("IM_0001: a DICOM file of 12 frames as a video stream in a folder of images; give the file "
                   "itself as --input"),
            std::string::npos)
      << e;
  // A stream that is no video: one line naming the file.
  DicomWriteOptions junk;
  junk.transfer_syntax = "1.2.840.10008.1.2.4.102";
  junk.video = std::string(4000, 'x');
  write_dicom(dir / "junk.dcm", written, junk);
  e = input_error(dir / "junk.dcm", {128, 96});
  EXPECT_EQ(e, (dir / "junk.dcm").string() + ": cannot open its video stream (corrupt, unsupported, or holding no "
                                             "frame)");
  EXPECT_TRUE(fs::is_empty(tmp)) << "nor is a copy left when the decoder refuses it";
  // No temporary folder to copy the stream to: one line saying so.
  {
    const gtrack::testing::ScopedEnv missing("TMPDIR", (dir / "no_such_folder").string());
    e = input_error(dir / "video.dcm", {128, 96});
  }
  EXPECT_NE(e.find("video.dcm: no temporary folder to copy its stream to"), std::string::npos) << e;
}

// What it cannot take is one line naming the file and what was expected.
TEST(Dicom, AFileItCannotTakeIsRefusedInALine) {
  const fs::path dir = dir_for("refused");
  const auto written = frames(2);
  write_dicom(dir / "whole.dcm", written);
  std::string bytes = file_bytes(dir / "whole.dcm");
  // Cut short in the pixel data: its whole frames are read, and said.
  std::ofstream(dir / "short.dcm", std::ios::binary) << bytes.substr(0, bytes.size() - 100);
  auto cut = gtrack::open_frame_source((dir / "short.dcm").string(), {40, 30}, {}, 30);
  EXPECT_EQ(cut->frame_count(), 1);
  EXPECT_NE(cut->ended_early().find("its pixel data holds 2300 bytes; 2 frame(s) of 40x30, 1 sample(s) of 8 bits "
                                    "need 2400; its first 1 frame are read"),
            std::string::npos)
      << cut->ended_early();
  std::string e;
  std::ofstream(dir / "header.dcm", std::ios::binary) << bytes.substr(0, 200);
  e = input_error(dir / "header.dcm");
  EXPECT_NE(e.find("header.dcm: "), std::string::npos) << e;
  EXPECT_EQ(e.find('\n'), std::string::npos) << e;
  // Not DICOM at all, named so.
  std::ofstream(dir / "text.dcm") << std::string(300, 'x');
  e = input_error(dir / "text.dcm");
  EXPECT_NE(e.find("text.dcm: "), std::string::npos) << e;
  // Pixels it does not take, refused when the file is opened.
  DicomWriteOptions palette;
  palette.photometric = "PALETTE COLOR";
  write_dicom(dir / "palette.dcm", written, palette);
  e = input_error(dir / "palette.dcm");
  EXPECT_NE(e.find("palette.dcm: palette colour pixels"), std::string::npos) << e;
  for (const char* syntax : {"1.2.840.10008.1.2.4.70", "1.2.840.10008.1.2.4.201"}) {
    DicomWriteOptions other;
    other.transfer_syntax = syntax;
    write_dicom(dir / "other.dcm", written, other);
    e = input_error(dir / "other.dcm");
    EXPECT_NE(e.find("its pixels are stored as "), std::string::npos) << e;
    EXPECT_NE(e.find(std::string(syntax) == "1.2.840.10008.1.2.4.201" ? "high-throughput JPEG 2000 lossless"
                                                                       : "JPEG lossless"),
              std::string::npos)
        << e;
  }
  // A transfer syntax it does not decode.
  DicomWriteOptions ls;
  ls.transfer_syntax = "1.2.840.10008.1.2.4.80";
  write_dicom(dir / "ls.dcm", written, ls);
  e = input_error(dir / "ls.dcm");
  EXPECT_NE(e.find("ls.dcm: its pixels are stored as JPEG-LS lossless (1.2.840.10008.1.2.4.80); expected native "
                   "pixels"),
            std::string::npos)
      << e;
  // Another size than the sensor's, from the file's header, before a frame is decoded.
  e = input_error(dir / "whole.dcm", {64, 48});
  EXPECT_NE(e.find("whole.dcm: image is 40x30 but the sensor expects 64x48"), std::string::npos) << e;
  // Every prefix of a good file is refused in a line or read, never more.
  for (std::size_t n = 0; n < bytes.size(); n += 37) {
    try {
      std::ofstream(dir / "prefix.dcm", std::ios::binary) << bytes.substr(0, n);
      read_all(dir / "prefix.dcm", {40, 30});
    } catch (const gtrack::InputError& error) {
      EXPECT_EQ(std::string(error.what()).find('\n'), std::string::npos) << n;
    }
  }
}

// A B-mode cine loop as one DICOM file is tracked as its frames are when
// they are images in a folder.
TEST(Dicom, AnUltrasoundCineLoopIsTrackedAsItsFramesAre) {
  const fs::path dir = dir_for("cine");
  const std::string gtrack = std::string(GTRACK_TEST_BINARY_DIR) + "/bin/gtrack ";
  const auto run = [&](const std::string& args) {
    return std::system((gtrack + args + " > " + (dir / "log.txt").string() + " 2>&1").c_str());
  };
  ASSERT_EQ(run("synth --preset ultrasound --frames 4 --seed 3 --out " + dir.string()), 0);
  std::vector<cv::Mat> images;
  for (int i = 0; i < 4; ++i) {
    char name[32];
    std::snprintf(name, sizeof name, "%06d.png", i);
    images.push_back(cv::imread((dir / "frames" / name).string(), cv::IMREAD_COLOR));
    ASSERT_FALSE(images.back().empty()) << name;
  }
  DicomWriteOptions o;
  o.frame_time_ms = 1000.0 / 30;
  o.region_cm_x = o.region_cm_y = 0.009;  // the sensor's 0.09 mm
  write_dicom(dir / "cine.dcm", images, o);
  const std::string common = "track -c " + (dir / "sequence.toml").string() + " --stimulus " +
                             (dir / "stimulus.csv").string() + " --no-overlay";
  ASSERT_EQ(run(common + " -i " + (dir / "frames").string() + " -o " + (dir / "from_folder").string()), 0);
  ASSERT_EQ(run(common + " -i " + (dir / "cine.dcm").string() + " -o " + (dir / "from_dicom").string()), 0);
  const auto poses = [](const fs::path& csv) {
    std::ifstream in(csv);
    std::vector<std::string> rows;
    for (std::string line; std::getline(in, line);) rows.push_back(line.substr(0, line.rfind(',')));  // less ms
    return rows;
  };
  const auto folder = poses(dir / "from_folder" / "estimates.csv");
  EXPECT_EQ(folder.size(), 5u);
  EXPECT_EQ(poses(dir / "from_dicom" / "estimates.csv"), folder);
  const auto log = [&] { return file_bytes(dir / "log.txt"); };
  EXPECT_EQ(log().find("its pixels are"), std::string::npos) << "the sensor's size: " << log();
  // A file whose pixels are not the sensor's size is warned about.
  o.region_cm_x = o.region_cm_y = 0.012;
  write_dicom(dir / "wide.dcm", images, o);
  ASSERT_EQ(run(common + " --frames 0:1 -i " + (dir / "wide.dcm").string() + " -o " + (dir / "wide").string()), 0);
  EXPECT_NE(log().find("wide.dcm: its pixels are 0.12 x 0.12 mm (width x height, as the file says), the sensor's "
                       "0.09 x 0.09 mm"),
            std::string::npos)
      << log();
  EXPECT_NE(log().find("mm_per_pixel = 0.12, mm_per_pixel_depth = 0.12"), std::string::npos) << log();
}
