// The gtrack executable as a user runs it: exit codes and one-line errors.
#include <gtest/gtest.h>

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <Eigen/Geometry>

#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "gtrack/model.hpp"
#include "support/scoped_env.hpp"

namespace fs = std::filesystem;

namespace {

struct CliRun {
  int code;
  std::string output;  // stdout and stderr
};

CliRun gtrack(const std::string& args, const std::string& redirect = "2>&1") {
  const std::string cmd = std::string(GTRACK_TEST_BINARY_DIR) + "/bin/gtrack " + args + " " + redirect;
  FILE* p = ::popen(cmd.c_str(), "r");
  std::string out;
  std::array<char, 4096> buf;
  while (p && std::fgets(buf.data(), buf.size(), p)) out += buf.data();
  int status = p ? ::pclose(p) : -1;
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, out};
}

// A gtrack run that starts the gl backend goes without LeakSanitizer's
// check (see asan_options_without_leak_check).
struct NoLeakCheckForGl : gtrack::testing::ScopedEnv {
  NoLeakCheckForGl() : ScopedEnv("ASAN_OPTIONS", gtrack::testing::asan_options_without_leak_check()) {}
};

fs::path write(const std::string& name, const std::string& text) {
  fs::path p = fs::temp_directory_path() / "gtrack_cli_test";
  fs::create_directories(p);
  p /= name;
  std::ofstream(p) << text;
  return p;
}

// `text` with the first `from` replaced by `to`.
std::string replaced(const std::string& text, const std::string& from, const std::string& to) {
  std::string out = text;
  const auto at = out.find(from);
  if (at != std::string::npos) out.replace(at, from.size(), to);
  return out;
}

// "track -c SEQ/sequence.toml -i SEQ/frames" for a folder 'gtrack synth' wrote.
std::string track_of(const fs::path& seq) {
  return "track -c " + (seq / "sequence.toml").string() + " -i " + (seq / "frames").string();
}

int lines(const std::string& s) { return static_cast<int>(std::count(s.begin(), s.end(), '\n')); }

// A whole file, byte for byte ("" when it cannot be read).
std::string read_file(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

// A refused command: exit status 1 and one line that says `what`.
void expect_refusal(const CliRun& r, const std::string& what) {
  EXPECT_EQ(r.code, 1);
  EXPECT_EQ(lines(r.output), 1) << r.output;
  EXPECT_NE(r.output.find(what), std::string::npos) << r.output;
}

const std::string kConfig =
    "[sensor]\nplugin = \"pinhole_microscope\"\nwidth = 256\nheight = 256\nfx = 3200\n"
    "[gripper]\nplugin = \"hydrogel_six_finger\"\n";

TEST(Cli, PluginsListsTheBuiltInsEachFromItsOwnLibrary) {
  CliRun r = gtrack("plugins");
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_NE(r.output.find("sensor\tpinhole_microscope\t"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("gripper\thydrogel_six_finger\t"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("stimulus\ttemperature_hysteresis\t"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("libgtrack_pinhole_microscope.so\tmicroscope camera: pinhole"), std::string::npos)
      << r.output;  // what it is, last
}

// With --config, what a run of that config finds: its plugin_path too,
// relative to its folder, searched after --plugin-path.
TEST(Cli, PluginsWithAConfigSearchItsPluginPath) {
  const fs::path dir = fs::temp_directory_path() / "gtrack_cli_test" / "plugins_config";
  fs::remove_all(dir);
  fs::create_directories(dir / "lab_plugins");
  std::ofstream(dir / "lab.toml") << "plugin_path = [\"lab_plugins\"]\n";
  const CliRun paths = gtrack("plugins --paths --config " + (dir / "lab.toml").string());
  ASSERT_EQ(paths.code, 0) << paths.output;
  EXPECT_EQ(paths.output.rfind((dir / "lab_plugins").string() + "\n", 0), 0u) << paths.output;
  const CliRun listed = gtrack("plugins -c " + (dir / "lab.toml").string());
  EXPECT_EQ(listed.code, 0) << listed.output;
  EXPECT_NE(listed.output.find("gripper\thydrogel_six_finger\t"), std::string::npos) << listed.output;
  const CliRun missing = gtrack("plugins -c " + (dir / "none.toml").string());
  EXPECT_EQ(missing.code, 1) << missing.output;
  EXPECT_NE(missing.output.find("none.toml"), std::string::npos) << missing.output;
}

// The common options that take a value may come before the command, spelt
// either way; the folder given is searched first.
TEST(Cli, CommonOptionsMayComeBeforeTheCommand) {
  const std::string dir = fs::temp_directory_path().string();
  for (const std::string& before : {"--plugin-path " + dir + " --log-level warn", "--plugin-path=" + dir}) {
    const CliRun r = gtrack(before + " plugins --paths");
    ASSERT_EQ(r.code, 0) << before << ": " << r.output;
    EXPECT_EQ(r.output.rfind(dir + "\n", 0), 0u) << before << ": " << r.output;
  }
}

TEST(Cli, MisspelledKeyIsOneLineWithFileLineKey) {
  fs::path cfg = write("typo.toml", kConfig + "link_lenghts_mm = [0.3, 0.3]\n");
  CliRun r = gtrack("render --config " + cfg.string() + " --params 0,0,100,0,0,0,0,0,0,0,0,0 --out /tmp/x.png");
  expect_refusal(r, cfg.string() + ":8: key 'gripper.link_lenghts_mm'");
  EXPECT_NE(r.output.find("did you mean 'link_lengths_mm'"), std::string::npos) << r.output;
}

TEST(Cli, UnknownPluginListsThoseThatExist) {
  fs::path cfg = write("unknown.toml", "[sensor]\nplugin = \"pinhole_microscope\"\nwidth = 64\nheight = 64\nfx = 100\n"
                                       "[gripper]\nplugin = \"hydrogel_seven_finger\"\n");
  CliRun r = gtrack("render --config " + cfg.string() + " --params 0,0,100,0,0,0,0,0,0,0,0,0 --out /tmp/x.png");
  expect_refusal(r, "gripper plugin 'hydrogel_seven_finger' not found");
  EXPECT_NE(r.output.find("available gripper plugins: "), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("hydrogel_six_finger"), std::string::npos) << r.output;
}

TEST(Cli, RenderWritesMaskAndObj) {
  fs::path cfg = write("ok.toml", kConfig);
  fs::path png = fs::temp_directory_path() / "gtrack_cli_test" / "mask.png";
  fs::path obj = fs::temp_directory_path() / "gtrack_cli_test" / "posed.obj";
  CliRun r = gtrack("render --config " + cfg.string() + " --params 0,0,100,10,0,0,0,10,20,30,40,50 --out " +
                 png.string() + " --obj " + obj.string());
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_TRUE(fs::exists(png));
  std::ifstream in(obj);
  std::string line;
  int v = 0, f = 0;
  while (std::getline(in, line)) {
    v += line.rfind("v ", 0) == 0;
    f += line.rfind("f ", 0) == 0;
  }
  EXPECT_EQ(f, 46);
  EXPECT_EQ(v, 46 * 3);
}

TEST(Cli, BadParameterVectorIsOneLine) {
  fs::path cfg = write("ok2.toml", kConfig);
  CliRun r = gtrack("render --config " + cfg.string() + " --params 0,0,abc --out /tmp/x.png");
  expect_refusal(r, "field 3 ('abc')");
  r = gtrack("render --config " + cfg.string() + " --params 0,0,1 --out /tmp/x.png");
  EXPECT_NE(r.output.find("got 3 values, expected 12"), std::string::npos) << r.output;
}

// --stream: stdout carries the estimates and nothing else, each line the
// same as the one written to estimates.jsonl, so a controller can read the
// pipe while the files are kept.
TEST(Cli, StreamPrintsEachEstimateOnStdout) {
  const fs::path dir = fs::temp_directory_path() / "gtrack_cli_test" / "stream";
  fs::remove_all(dir);
  ASSERT_EQ(gtrack("synth --frames 3 --seed 2 --out " + dir.string()).code, 0);
  const CliRun r = gtrack(track_of(dir) + " -o " + (dir / "out").string() + " --no-overlay --stream", "2>/dev/null");
  ASSERT_EQ(r.code, 0) << r.output;
  const std::string written = read_file(dir / "out" / "estimates.jsonl");
  EXPECT_EQ(lines(r.output), 3) << r.output;
  EXPECT_EQ(r.output, written);
  EXPECT_EQ(r.output.rfind("{\"frame\":0,", 0), 0u) << r.output;
}

// --stream-udp: each estimate also goes to a UDP port as one datagram, its
// estimates.jsonl line, for a controller in another process; nobody
// listening stops nothing; a bad address is one line.
TEST(Cli, StreamUdpSendsEachEstimateAsADatagram) {
  const fs::path dir = fs::temp_directory_path() / "gtrack_cli_test" / "stream_udp";
  fs::remove_all(dir);
  ASSERT_EQ(gtrack("synth --frames 3 --seed 2 --out " + dir.string()).code, 0);
  const int fd = ::socket(AF_INET, SOCK_DGRAM, 0);
  ASSERT_GE(fd, 0);
  sockaddr_in at{};
  at.sin_family = AF_INET;
  at.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  at.sin_port = 0;  // a free port
  ASSERT_EQ(::bind(fd, reinterpret_cast<sockaddr*>(&at), sizeof at), 0);
  socklen_t length = sizeof at;
  ASSERT_EQ(::getsockname(fd, reinterpret_cast<sockaddr*>(&at), &length), 0);
  const std::string port = std::to_string(ntohs(at.sin_port));
  const CliRun r =
      gtrack(track_of(dir) + " -o " + (dir / "out").string() + " --no-overlay --stream-udp 127.0.0.1:" + port);
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_NE(r.output.find("--stream-udp: 3 datagrams handed to the network for 127.0.0.1:" + port + ", 0 dropped"),
            std::string::npos)
      << r.output;
  // The datagrams wait in the socket's buffer: each one line of the file.
  std::string received;
  int datagrams = 0;
  std::array<char, 65536> buffer;
  for (ssize_t n; (n = ::recv(fd, buffer.data(), buffer.size(), MSG_DONTWAIT)) > 0; ++datagrams) {
    const std::string one(buffer.data(), static_cast<std::size_t>(n));
    EXPECT_EQ(lines(one), 1) << one;
    received += one;
  }
  ::close(fd);
  EXPECT_EQ(datagrams, 3);
  EXPECT_EQ(received, read_file(dir / "out" / "estimates.jsonl"));
  // Nobody listens there now: the run is the same.
  const CliRun unheard =
      gtrack(track_of(dir) + " -o " + (dir / "out2").string() + " --no-overlay --stream-udp 127.0.0.1:" + port);
  EXPECT_EQ(unheard.code, 0) << unheard.output;
  EXPECT_NE(unheard.output.find("3 datagrams handed to the network for 127.0.0.1:" + port), std::string::npos)
      << unheard.output;
  EXPECT_EQ(lines(read_file(dir / "out2" / "estimates.jsonl")), 3);
  for (const std::string& bad : {std::string("5005"), std::string("localhost:0"), std::string("localhost:70000"),
                                 std::string("[::1:5005"), std::string("localhost:50x5"),
                                 std::string("[fe80::1]:5005")}) {
    const CliRun refused = gtrack(track_of(dir) + " -o " + (dir / "out3").string() + " --stream-udp " + bad);
    expect_refusal(refused, "--stream-udp '" + bad + "': ");
  }
}

// The reader of --stream goes away (`| head -n 1`): the run stops at the
// next frame with its files closed and says so in one line, instead of
// dying of SIGPIPE.
TEST(Cli, StreamReaderGoingAwayStopsTheRunCleanly) {
  const fs::path dir = fs::temp_directory_path() / "gtrack_cli_test" / "stream_closed";
  fs::remove_all(dir);
  ASSERT_EQ(gtrack("synth --frames 30 --seed 4 --out " + dir.string()).code, 0);
  const fs::path err = dir / "stderr.txt";
  const CliRun r = gtrack(track_of(dir) + " -o " + (dir / "out").string() + " --no-overlay --stream",
                          "2>" + err.string() + " | head -n 1");
  EXPECT_EQ(lines(r.output), 1) << r.output;
  const std::string e = read_file(err);
  EXPECT_NE(e.find("gtrack track: stdout was closed by its reader; stopped after "), std::string::npos) << e;
  const std::string s = read_file(dir / "out" / "summary.json");
  EXPECT_NE(s.find("\"cancelled\": true"), std::string::npos) << s;

  // ...also while no line is being written: a followed folder whose images
  // stopped coming. The run ends when the reader does, not after the idle
  // time (120 s here), and says why.
  const fs::path live = dir / "live";
  fs::create_directories(live);
  fs::copy_file(dir / "frames" / "000000.png", live / "000000.png");
  const auto start = std::chrono::steady_clock::now();
  const CliRun waiting =
      gtrack(std::string("track -c ") + (dir / "sequence.toml").string() + " -i " + live.string() + " -o " +
                 (dir / "out_live").string() + " --no-overlay --stream --follow-input 120",
             "2>" + err.string() + " | head -n 1");
  EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(), 60.0);
  EXPECT_EQ(lines(waiting.output), 1) << waiting.output;
  EXPECT_NE(read_file(err).find("stdout was closed by its reader; stopped after 1 frame,"), std::string::npos)
      << read_file(err);

  // stdout closed before the run (`>&-`): what is printed goes nowhere, not
  // into the first file opened, which would take stdout's number.
  const CliRun closed = gtrack(track_of(dir) + " --frames 0:2 -o " + (dir / "out_closed").string() +
                                   " --no-overlay --log-level warn",
                               ">&- 2>/dev/null");
  EXPECT_EQ(closed.code, 0);
  for (const char* file : {"estimates.csv", "run_config.toml", "tracker_state.txt"}) {
    EXPECT_EQ(read_file(dir / "out_closed" / file).find("frames (0 lost)"), std::string::npos) << file;
  }
  EXPECT_EQ(read_file(dir / "out_closed" / "estimates.csv").rfind("frame,x_mm", 0), 0u);
  // With --stream the estimates would go nowhere: refused, before anything
  // is tracked.
  const CliRun streamed = gtrack(track_of(dir) + " --frames 0:2 -o " + (dir / "out_closed_stream").string() +
                                     " --no-overlay --stream",
                                 "2>&1 >&-");
  EXPECT_EQ(streamed.code, 2) << streamed.output;
  EXPECT_NE(streamed.output.find("--stream: stdout is closed; expected it open to the estimates' reader"),
            std::string::npos)
      << streamed.output;
  EXPECT_FALSE(fs::exists(dir / "out_closed_stream" / "estimates.csv"));
}

// A renderer that cannot start says so at once, not once a followed
// folder's first image comes (here after the 60 s the run would wait).
TEST(Cli, ARendererThatCannotStartIsSaidBeforeTheFirstImage) {
  const fs::path dir = fs::temp_directory_path() / "gtrack_cli_test" / "renderer_first";
  fs::remove_all(dir);
  ASSERT_EQ(gtrack("synth --frames 1 --seed 2 --out " + dir.string()).code, 0);
  fs::create_directories(dir / "empty");
  const auto start = std::chrono::steady_clock::now();
  CliRun r{};
  {
    const gtrack::testing::ScopedEnv no_rows("GTRACK_GL_COUNT_ROWS", "0");
    const NoLeakCheckForGl gl_run;
    r = gtrack("track -c " + (dir / "sequence.toml").string() + " -i " + (dir / "empty").string() + " -o " +
               (dir / "out").string() + " --backend gl --follow-input 60");
  }
  EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(), 30.0);
  EXPECT_EQ(r.code, 1) << r.output;
  // (The count's setting where the gl backend starts, else why it cannot.)
  EXPECT_TRUE(r.output.find("GTRACK_GL_COUNT_ROWS='0'") != std::string::npos ||
              r.output.find("gl backend") != std::string::npos)
      << r.output;
}

std::vector<std::vector<std::string>> read_csv(const fs::path& file) {
  std::ifstream in(file);
  std::vector<std::vector<std::string>> rows;
  std::string line;
  while (std::getline(in, line)) {
    std::vector<std::string> cells;
    std::stringstream ss(line);
    std::string c;
    while (std::getline(ss, c, ',')) cells.push_back(c);
    rows.push_back(cells);
  }
  return rows;
}

// A stimulus log in kelvin is refused at its first row, before a frame is
// tracked, by the stimulus plugin's own range (followed or not); one keyed
// by another clock at the first frame.
TEST(Cli, TrackRefusesAReadingTheStimulusPluginCannotTake) {
  const fs::path dir = fs::temp_directory_path() / "gtrack_cli_test" / "kelvin";
  fs::remove_all(dir);
  ASSERT_EQ(gtrack("synth --frames 2 --seed 3 --out " + dir.string()).code, 0);
  std::ofstream(dir / "kelvin.csv") << "frame,value\n# logged in K\n0,295.15\n1,295.2\n";
  for (const std::string follow : {"", " --follow-stimulus"}) {
    const CliRun r =
        gtrack(track_of(dir) + " -s " + (dir / "kelvin.csv").string() + follow + " -o " + (dir / "out").string());
    EXPECT_EQ(r.code, 1) << r.output;
    EXPECT_NE(r.output.find((dir / "kelvin.csv").string() +
                            ":3: a reading of 295.15, outside the -50 to 150 C temperature_hysteresis takes: "
                            "expected degrees Celsius (kelvin: subtract 273.15, or set log_unit = \"K\")"),
              std::string::npos)
        << r.output;
    EXPECT_FALSE(fs::exists(dir / "out" / "estimates.csv"));
  }
  // A default reading is checked as a log's rows are, naming its key.
  std::ofstream(dir / "default.toml") << replaced(read_file(dir / "sequence.toml"), "[tracker]\n",
                                                   "[tracker]\ndefault_stimulus = 300.0\n");
  const CliRun d = gtrack("track -c " + (dir / "default.toml").string() + " -i " + (dir / "frames").string() +
                          " -o " + (dir / "out").string());
  EXPECT_EQ(d.code, 1) << d.output;
  EXPECT_NE(d.output.find("key 'tracker.default_stimulus': a reading of 300, outside the -50 to 150 C"),
            std::string::npos)
      << d.output;
  // A log keyed by Unix time has no row near the recording's frames.
  std::ofstream(dir / "unix.csv") << "time_s,value\n1765011000.0,22\n1765011000.5,22.5\n";
  const CliRun r = gtrack(track_of(dir) + " -s " + (dir / "unix.csv").string() + " -o " + (dir / "out").string());
  EXPECT_EQ(r.code, 1) << r.output;
  EXPECT_NE(r.output.find("unix.csv: its times start at t = 1765011000.000 s, more than a day after frame 0 (t = "
                          "0.000 s); expected seconds from the recording's first frame"),
            std::string::npos)
      << r.output;
}

// A log on another clock by minutes (a logger started before the camera)
// covers none of the frames: refused, where every frame would have taken
// its first row's reading. One whose readings' column names another unit
// than the stimulus plugin reads is refused too; the same unit, or a name
// that says none, passes. A time_s log beside a folder of images, which
// has no frame rate, says the rate taken.
TEST(Cli, TrackRefusesALogOnAnotherClockOrInAnotherUnit) {
  const fs::path dir = fs::temp_directory_path() / "gtrack_cli_test" / "log_clock_unit";
  fs::remove_all(dir);
  ASSERT_EQ(gtrack("synth --frames 3 --seed 3 --out " + dir.string()).code, 0);
  const auto track_with = [&](const std::string& name, const std::string& text) {
    std::ofstream(dir / name) << text;
    return gtrack(track_of(dir) + " -s " + (dir / name).string() + " -o " + (dir / "out").string() +
                  " --no-overlay --log-level warn");
  };
  const CliRun late = track_with("late.csv", "time_s,T_C\n120.0,22\n121.0,23\n");
  EXPECT_EQ(late.code, 1) << late.output;
  EXPECT_NE(late.output.find("late.csv: its rows cover t = 120.000 to 121.000 s, after the frames to track (t = "
                             "0.000 to 0.067 s): none of them falls within the log"),
            std::string::npos)
      << late.output;
  EXPECT_FALSE(fs::exists(dir / "out" / "estimates.csv"));
  EXPECT_NE(late.output.find("--stimulus-offset with the log's time at the first frame"), std::string::npos)
      << late.output;
  // The same log with its time at the first frame given: frame k (at k/30
  // s) takes the reading at 120 + k/30 s.
  const CliRun shifted = gtrack(track_of(dir) + " -s " + (dir / "late.csv").string() + " --stimulus-offset 120 -o " +
                                (dir / "out").string() + " --no-overlay --log-level warn");
  ASSERT_EQ(shifted.code, 0) << shifted.output;
  EXPECT_EQ(shifted.output.find("outside the stimulus log"), std::string::npos) << shifted.output;
  const std::string jsonl = read_file(dir / "out" / "estimates.jsonl");
  for (const char* reading : {"\"stimulus\":22,", "\"stimulus\":22.0333333", "\"stimulus\":22.0666666"}) {
    EXPECT_NE(jsonl.find(reading), std::string::npos) << reading << " in " << jsonl;
  }
  // An offset that leaves the frames outside the log says so, with the offset.
  const CliRun past = gtrack(track_of(dir) + " -s " + (dir / "late.csv").string() + " --stimulus-offset 60 -o " +
                             (dir / "out").string() + " --no-overlay --log-level warn");
  EXPECT_EQ(past.code, 1) << past.output;
  EXPECT_NE(past.output.find("late.csv: its rows cover t = 60.000 to 61.000 s (its time_s less --stimulus-offset "
                             "60), after the frames to track"),
            std::string::npos)
      << past.output;
  // Only a time_s log has times to shift; a followed one has no times taken.
  std::ofstream(dir / "by_frame.csv") << "frame,value\n0,22\n2,23\n";
  const CliRun by_frame = gtrack(track_of(dir) + " -s " + (dir / "by_frame.csv").string() +
                                 " --stimulus-offset 5 -o " + (dir / "out").string() + " --no-overlay");
  EXPECT_EQ(by_frame.code, 1) << by_frame.output;
  EXPECT_NE(by_frame.output.find("by_frame.csv: is keyed by frame; a time offset (--stimulus-offset) shifts a time_s "
                                 "log"),
            std::string::npos)
      << by_frame.output;
  const CliRun followed = gtrack(track_of(dir) + " -s " + (dir / "late.csv").string() +
                                 " --stimulus-offset 120 --follow-stimulus -o " + (dir / "out").string());
  EXPECT_EQ(followed.code, 2) << followed.output;
  EXPECT_NE(followed.output.find("--stimulus-offset cannot be combined with --follow-stimulus"), std::string::npos)
      << followed.output;
  const CliRun fahrenheit = track_with("f.csv", "time_s,T_F\n0.0,71.6\n1.0,72\n");
  EXPECT_EQ(fahrenheit.code, 1) << fahrenheit.output;
  EXPECT_NE(fahrenheit.output.find("f.csv: its readings' column 'T_F' says F, but the stimulus plugin "
                                   "'temperature_hysteresis' reads C"),
            std::string::npos)
      << fahrenheit.output;
  // The unit is said first, before a reading that only the unit puts
  // outside what the plugin takes (a hot bath in F): widening the plugin's
  // range would be the wrong mend.
  const CliRun hot = track_with("hot.csv", "time_s,T_F\n0.0,71.6\n1.0,1000\n");
  EXPECT_EQ(hot.code, 1) << hot.output;
  EXPECT_NE(hot.output.find("hot.csv: its readings' column 'T_F' says F"), std::string::npos) << hot.output;
  // A log that ends before the frames (a logger stopped early) is not
  // refused: each frame past it holds the last reading, as said.
  const CliRun early = track_with("early.csv", "time_s,T_C\n-2.0,22\n-1.0,23\n");
  EXPECT_EQ(early.code, 0) << early.output;
  EXPECT_NE(early.output.find("is outside the stimulus log"), std::string::npos) << early.output;
  // A temperature named T is not taken for tesla.
  for (const std::string& header :
       {"time_s,T_C", "time_s,temperature (degC)", "time_s,value", "time_s,probe T", "time_s,sample_T"}) {
    const CliRun ok = track_with("ok.csv", header + "\n0.0,22\n1.0,23\n");
    EXPECT_EQ(ok.code, 0) << header << ": " << ok.output;
    EXPECT_EQ(ok.output.find("no frame rate"), std::string::npos) << "sequence.toml sets fps: " << ok.output;
  }
  std::ofstream(dir / "no_fps.toml") << replaced(read_file(dir / "sequence.toml"), "\nfps = 30.0\n", "\n");
  const CliRun no_fps = gtrack("track -c " + (dir / "no_fps.toml").string() + " -i " + (dir / "frames").string() +
                               " -s " + (dir / "ok.csv").string() + " -o " + (dir / "out").string() +
                               " --no-overlay --log-level warn");
  EXPECT_EQ(no_fps.code, 0) << no_fps.output;
  EXPECT_NE(no_fps.output.find("the images carry no frame rate, so 30 frames/s is taken for the time_s log"),
            std::string::npos)
      << no_fps.output;
}

// --restart-from TABLE: each frame is tracked from the table's row for the
// previous frame. A run that starts at frame 5 would begin with the coarse
// search; from the ground truth it tracks frame 5 from frame 4's truth, and
// every estimate lies near its own truth.
TEST(Cli, RestartFromTheTruthTracksEachFrameFromThePreviousTruth) {
  const fs::path dir = fs::temp_directory_path() / "gtrack_cli_test" / "restart";
  fs::remove_all(dir);
  ASSERT_EQ(gtrack("synth --frames 9 --seed 3 --out " + dir.string()).code, 0);
  const std::string track =
      track_of(dir) + " -s " + (dir / "stimulus.csv").string() + " --frames 5:9 --no-overlay -o ";
  CliRun r = gtrack(track + (dir / "plain").string());
  ASSERT_EQ(r.code, 0) << r.output;
  r = gtrack(track + (dir / "restarted").string() + " --restart-from " + (dir / "ground_truth.csv").string());
  ASSERT_EQ(r.code, 0) << r.output;
  const auto truth = read_csv(dir / "ground_truth.csv");
  const auto plain = read_csv(dir / "plain" / "estimates.csv");
  const auto restarted = read_csv(dir / "restarted" / "estimates.csv");
  ASSERT_EQ(plain.size(), 5u);
  ASSERT_EQ(restarted.size(), 5u);
  const int status = 14;  // frame, 12 parameters, cost, status
  ASSERT_EQ(restarted[0][status], "status");
  EXPECT_EQ(plain[1][status], "search");
  for (int i = 1; i <= 4; ++i) {
    EXPECT_EQ(restarted[i][status], "ok") << i;
    const auto& t = truth[5 + i];
    ASSERT_EQ(restarted[i][0], t[0]);
    const double dx = std::stod(restarted[i][1]) - std::stod(t[1]), dy = std::stod(restarted[i][2]) - std::stod(t[2]);
    EXPECT_LT(std::hypot(dx, dy), 0.06) << "frame " << t[0];
  }
  // A table of frames 0 to 3 does not reach frames 5 to 8: said, not silently ignored.
  const fs::path early = write("early_truth.csv", "");
  {
    std::ofstream out(early);
    std::stringstream in(read_file(dir / "ground_truth.csv"));
    std::string l;
    for (int i = 0; i < 5 && std::getline(in, l); ++i) out << l << "\n";
  }
  r = gtrack(track + (dir / "early").string() + " --restart-from " + early.string() + " --score-truth " +
             early.string());
  EXPECT_EQ(r.code, 0) << r.output;
  EXPECT_NE(r.output.find("early_truth.csv: none of its rows (frames 0 to 3) is the frame before a tracked one (the "
                          "last tracked: 8); --restart-from changed nothing"),
            std::string::npos)
      << r.output;
  EXPECT_NE(r.output.find("--score-truth changed nothing"), std::string::npos) << r.output;
}

TEST(Cli, RestartFromATableOfAnotherGripperIsOneLine) {
  const fs::path dir = fs::temp_directory_path() / "gtrack_cli_test" / "restart_other";
  fs::remove_all(dir);
  ASSERT_EQ(gtrack("synth --frames 2 --seed 3 --out " + dir.string()).code, 0);
  const fs::path table = write("two_fingers.csv",
                               "frame,x_mm,y_mm,z_mm,rx_deg,ry_deg,rz_deg,q1_deg,q2_deg\n0,0,0,100,0,0,0,0,0\n");
  const CliRun r =
      gtrack(track_of(dir) + " --no-overlay -o " + (dir / "out").string() + " --restart-from " + table.string());
  expect_refusal(r, table.string() + ": has 2 joint columns, the gripper of this config has 6");
  const CliRun s =
      gtrack(track_of(dir) + " --no-overlay -o " + (dir / "out2").string() + " --score-truth " + table.string());
  expect_refusal(s, table.string() + ": has 2 joint columns, the gripper of this config has 6");
  // A table that is not there names its option.
  const std::string none = (dir / "none.csv").string();
  expect_refusal(gtrack(track_of(dir) + " --no-overlay -o " + (dir / "out3").string() + " --restart-from " + none),
                 none + ": no such file (--restart-from)");
  expect_refusal(gtrack(track_of(dir) + " --no-overlay -o " + (dir / "out4").string() + " --score-truth " + none),
                 none + ": no such file (--score-truth)");
}

int count_files(const fs::path& dir, const std::string& extension) {
  int n = 0;
  for (const auto& e : fs::directory_iterator(dir)) n += e.path().extension() == extension;
  return n;
}

// A second sequence written into the folder of a longer one: its frames
// alone are left, so tracking the folder tracks this sequence only.
TEST(Cli, SynthIntoAnEarlierSequenceLeavesOnlyItsOwnFrames) {
  const fs::path dir = fs::temp_directory_path() / "gtrack_cli_test" / "synth_again";
  fs::remove_all(dir);
  ASSERT_EQ(gtrack("synth --frames 4 --seed 1 --out " + dir.string()).code, 0);
  std::ofstream(dir / "frames" / "notes.txt") << "kept\n";
  ASSERT_EQ(gtrack("synth --frames 2 --seed 2 --out " + dir.string()).code, 0);
  EXPECT_EQ(count_files(dir / "frames", ".png"), 2);
  EXPECT_TRUE(fs::exists(dir / "frames" / "notes.txt"));  // not a frame: left alone
}

// gtrack sweep writes both figures' tables and plots, one row per cell; run
// again in the same folder with another sequence length, it makes its
// sequences again instead of scoring the old ones.
TEST(Cli, SweepWritesTheFiguresAndRemakesSequencesMadeOtherwise) {
  const fs::path dir = fs::temp_directory_path() / "gtrack_cli_test" / "sweep";
  fs::remove_all(dir);
  const std::string tiny = "sweep --particles 4,6 --generations 2 --sigmas 0,1 --fig6b-particles 4 "
                           "--fig6b-generations 2 --out " + dir.string();
  CliRun r = gtrack(tiny + " --frames 3");
  ASSERT_EQ(r.code, 0) << r.output;
  for (const char* f : {"fig6a.csv", "fig6a.png", "fig6b.csv", "fig6b.png"}) EXPECT_TRUE(fs::exists(dir / f)) << f;
  EXPECT_EQ(lines(read_file(dir / "fig6a.csv")), 1 + 2);  // header, N = 4 and 6 at G = 2
  EXPECT_EQ(lines(read_file(dir / "fig6b.csv")), 1 + 2);  // header, sigma 0 and 1
  const fs::path truth = dir / "sequences" / "seq_seed1_noise1" / "ground_truth.csv";
  const int rows3 = lines(read_file(truth));
  r = gtrack(tiny + " --frames 5");
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_EQ(lines(read_file(truth)), rows3 + 2);
  EXPECT_EQ(count_files(dir / "sequences" / "seq_seed1_noise1" / "frames", ".png"), 5);
}

// sweep given a config and no --preset makes the sequences gtrack synth
// would make from it (not the microscope preset's hydrogel frames); a cell
// in which no frame could be judged has no error, not an error of 0.
TEST(Cli, SweepTakesThePresetItsConfigTracksAndLeavesACellOfLostFramesBlank) {
  const fs::path dir = fs::temp_directory_path() / "gtrack_cli_test" / "sweep_preset";
  fs::remove_all(dir);
  const fs::path configs = fs::path(GTRACK_TEST_SOURCE_DIR) / "configs";
  const std::string tiny = " --particles 4 --generations 2 --figure 6a --frames 3";
  CliRun r = gtrack("sweep --config " + (configs / "microscope_metallic_two.toml").string() + tiny + " --out " +
                    (dir / "two").string());
  ASSERT_EQ(r.code, 0) << r.output;
  const std::string made = read_file(dir / "two" / "sequences" / "seq_seed1_noise0" / "made_from.txt");
  EXPECT_NE(made.find("preset metallic_two\n"), std::string::npos) << made;
  // Colour frames for a config that segments grey levels: every frame lost.
  r = gtrack("sweep --config " + (configs / "ultrasound_hydrogel.toml").string() + " --preset microscope" + tiny +
             " --out " + (dir / "lost").string());
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_NE(r.output.find("segments grey levels"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("no frame to judge: lost 3 of 3"), std::string::npos) << r.output;
  const auto rows = read_csv(dir / "lost" / "fig6a.csv");
  ASSERT_EQ(rows.size(), 2u);
  ASSERT_EQ(rows[1].size(), rows[0].size());
  for (std::size_t c = 0; c < rows[0].size(); ++c) {
    const bool error = rows[0][c].find("_um") != std::string::npos || rows[0][c].find("_deg") != std::string::npos;
    if (error) EXPECT_EQ(rows[1][c], "nan") << rows[0][c];
  }
}

// A fresh run into the folder of an earlier one replaces it: no overlay,
// mask or row of the earlier run is left beside the new results.
TEST(Cli, TrackIntoAnEarlierRunReplacesIt) {
  const fs::path dir = fs::temp_directory_path() / "gtrack_cli_test" / "track_again";
  fs::remove_all(dir);
  ASSERT_EQ(gtrack("synth --frames 3 --seed 5 --out " + dir.string()).code, 0);
  const std::string track = track_of(dir) + " -o " + (dir / "out").string();
  CliRun r = gtrack(track + " --save-masks");
  ASSERT_EQ(r.code, 0) << r.output;
  ASSERT_EQ(count_files(dir / "out" / "masks", ".png"), 3);
  ASSERT_TRUE(fs::exists(dir / "out" / "overlay.mp4") || fs::exists(dir / "out" / "overlay.avi"));
  r = gtrack(track + " --frames 0:2 --no-overlay");
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_NE(r.output.find("holds an earlier run: it is replaced"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(dir / "out" / "overlay.mp4"));
  EXPECT_FALSE(fs::exists(dir / "out" / "overlay.avi"));
  EXPECT_EQ(count_files(dir / "out" / "masks", ".png"), 0);
  EXPECT_EQ(read_csv(dir / "out" / "estimates.csv").size(), 3u);  // header and frames 0, 1
}

std::string hydrogel_config() {
  return read_file(fs::path(GTRACK_TEST_SOURCE_DIR) / "configs" / "microscope_hydrogel.toml");
}

const std::string kParams =
    " -p 0,0,100,0,0,0,0,0,0,0,0,0 -o " + (fs::temp_directory_path() / "gtrack_cli_test" / "m.png").string();

// A key or table that is missing points at the unread one it was likely
// meant to be, with its line.
TEST(Cli, AMissingKeyNamesItsLikelyMisspelling) {
  const std::string base = hydrogel_config();
  const fs::path key = write("fxx.toml", replaced(base, "\nfx = ", "\nfxx = "));
  CliRun r = gtrack("render -c " + key.string() + kParams);
  expect_refusal(r, "key 'sensor.fx': missing; expected a number in [1, 1e+08] (is 'fxx' on line ");
  // A focal length under a pixel is refused by its key, not later by the
  // projection it makes.
  const fs::path tiny_focal = write("tiny_focal.toml", replaced(base, "\nfx = 12800.0", "\nfx = 1e-300"));
  r = gtrack("render -c " + tiny_focal.string() + kParams);
  expect_refusal(r, "tiny_focal.toml:13: key 'sensor.fx': value 1e-300 is out of range; expected a number in [1, 1e+08]");
  // A key read only when present (the camera's calibration file) is known too.
  const fs::path calibration =
      write("calibraton.toml", replaced(base, "\nfx = ", "\ncalibraton = \"camera.yml\"\nfx = "));
  r = gtrack("render -c " + calibration.string() + kParams);
  EXPECT_NE(r.output.find("key 'sensor.calibraton': unknown key in [sensor] (did you mean 'calibration'?)"),
            std::string::npos)
      << r.output;
  // Not fy, its sibling, which is read after it.
  const fs::path sibling = write("focal.toml", replaced(base, "\nfx = ", "\nfocal_length = "));
  r = gtrack("render -c " + sibling.string() + kParams);
  EXPECT_NE(r.output.find("key 'sensor.fx': missing"), std::string::npos) << r.output;
  EXPECT_EQ(r.output.find("is 'fy'"), std::string::npos) << r.output;
  EXPECT_EQ(r.output.find("is 'cx'"), std::string::npos) << r.output;
  const fs::path plugin =
      write("plugn.toml", replaced(base, "plugin = \"hydrogel_six_finger\"", "plugn = \"hydrogel_six_finger\""));
  r = gtrack("render -c " + plugin.string() + kParams);
  EXPECT_NE(r.output.find("key 'gripper.plugin': missing"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("(is 'plugn' on line "), std::string::npos) << r.output;
  const fs::path table = write("sensr.toml", replaced(base, "[sensor]", "[sensr]"));
  r = gtrack("render -c " + table.string() + kParams);
  EXPECT_NE(r.output.find("missing table [sensor]"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("(is 'sensr' on line "), std::string::npos) << r.output;
  r = gtrack("render -c " + fs::temp_directory_path().string() + kParams);
  EXPECT_NE(r.output.find(": is a folder; expected a TOML config file"), std::string::npos) << r.output;
}

// render checks the whole config, as track does, and where it will write
// before it renders.
TEST(Cli, RenderChecksTheConfigAndItsOutputsFirst) {
  const fs::path cfg = write("trackr.toml", hydrogel_config() + "\n[trackr]\nparticles = 3\n");
  CliRun r = gtrack("render -c " + cfg.string() + kParams);
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.output.find("key 'trackr': unknown key at the top level (did you mean 'tracker'?)"), std::string::npos)
      << r.output;
  const fs::path ok = write("render_ok.toml", hydrogel_config());
  r = gtrack("render -c " + ok.string() + " -p 0,0,100,0,0,0,0,0,0,0,0,0 -o mask.jpgx");
  expect_refusal(r, "mask.jpgx: cannot write images of this kind");
  r = gtrack("render -c " + ok.string() + " -p 0,0,100,0,0,0,0,0,0,0,0,0 -o no_such_folder/mask.png");
  EXPECT_NE(r.output.find("no_such_folder/mask.png: 'no_such_folder' does not exist"), std::string::npos) << r.output;
  // A file where the folder should be, and a folder where the file should be.
  r = gtrack("render -c " + ok.string() + " -p 0,0,100,0,0,0,0,0,0,0,0,0 -o " + ok.string() + "/mask.png");
  EXPECT_NE(r.output.find("' is not a folder"), std::string::npos) << r.output;
  r = gtrack("render -c " + ok.string() + " -p 0,0,100,0,0,0,0,0,0,0,0,0 -o " + ok.parent_path().string());
  EXPECT_NE(r.output.find(": is a folder; expected a file name"), std::string::npos) << r.output;
  // A pose the tracker would never consider is rendered, with a word each.
  const std::string m = (fs::temp_directory_path() / "gtrack_cli_test" / "behind.png").string();
  r = gtrack("render -c " + ok.string() + " -p 0,0,-100,0,0,0,999,0,0,0,0,0 -o " + m);
  EXPECT_EQ(r.code, 0) << r.output;
  EXPECT_NE(r.output.find("q1 = 999 is outside the gripper's joint limits"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("the posed model covers no pixel of the image"), std::string::npos) << r.output;
  r = gtrack("render -c " + ok.string() + " -p 0,0,100,0,0,0,10,10,10,10,10,10 -o " + m);
  EXPECT_EQ(r.output.find("[warning]"), std::string::npos) << r.output;
}

// A frame folder with a damaged image: the decoder's own words go into the
// one line that names the file, not above it.
TEST(Cli, ADamagedImageIsOneLineWithTheDecodersWords) {
  const fs::path dir = fs::temp_directory_path() / "gtrack_cli_test" / "damaged";
  fs::remove_all(dir);
  ASSERT_EQ(gtrack("synth --frames 2 --seed 6 --out " + dir.string()).code, 0);
  const fs::path frame = dir / "frames" / "000001.png";
  const std::string bytes = read_file(frame);
  std::ofstream(frame, std::ios::binary | std::ios::trunc) << bytes.substr(0, bytes.size() / 3);
  const CliRun r = gtrack(track_of(dir) + " --no-overlay --log-level warn -o " + (dir / "out").string());
  expect_refusal(r, frame.string() + ": cannot read the image");
}

TEST(Cli, AFrameRangeOutsideTheInputIsAnError) {
  const fs::path dir = fs::temp_directory_path() / "gtrack_cli_test" / "range";
  fs::remove_all(dir);
  ASSERT_EQ(gtrack("synth --frames 3 --seed 6 --out " + dir.string()).code, 0);
  const CliRun r = gtrack(track_of(dir) + " --no-overlay --frames 20:30 -o " + (dir / "out").string());
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.output.find("holds 3 frames, none of them in --frames 20:30"), std::string::npos) << r.output;
  // --out naming a file: one line, resumed or not.
  const fs::path file = write("a_file", "text");
  for (const std::string resume : {"", " --resume"}) {
    const CliRun f = gtrack(track_of(dir) + " --no-overlay" + resume + " -o " + file.string());
    EXPECT_EQ(f.code, 1);
    EXPECT_EQ(f.output, "gtrack: error: " + file.string() + ": is a file; expected an output folder (--out)\n");
  }
}

// eval reads its tables strictly: what it cannot read is named, with the
// file and line, instead of being skipped.
// An output given the name of an input, or of another output, is refused
// before anything is written: the input is left as it was.
TEST(Cli, AnOutputIsNeverAnInputNorAnotherOutput) {
  const fs::path dir = fs::temp_directory_path() / "gtrack_cli_test" / "outputs_apart";
  fs::remove_all(dir);
  ASSERT_EQ(gtrack("synth --frames 2 --seed 4 --out " + dir.string()).code, 0);
  const fs::path truth = dir / "ground_truth.csv", config = dir / "sequence.toml";
  const std::string truth_text = read_file(truth), config_text = read_file(config);
  // Estimates: the truth without its three share columns.
  std::string rows_text;
  {
    std::stringstream in(truth_text);
    for (std::string l; std::getline(in, l);) {
      for (int k = 0; k < 3; ++k) l.erase(l.rfind(','));
      rows_text += l + "\n";
    }
  }
  const fs::path estimates = dir / "estimates.csv";
  std::ofstream(estimates) << rows_text;
  const std::string eval = "eval -t " + truth.string() + " -e " + estimates.string() + " ";
  CliRun r = gtrack(eval + "--json " + truth.string());
  EXPECT_EQ(r.code, 2) << r.output;
  EXPECT_NE(r.output.find(truth.string() + ": is the --truth input; --json would overwrite it"), std::string::npos)
      << r.output;
  // The same file by another name.
  r = gtrack(eval + "--per-frame " + (dir / "." / "sequence.toml").string());
  EXPECT_EQ(r.code, 2) << r.output;
  EXPECT_NE(r.output.find("is the config input; --per-frame would overwrite it"), std::string::npos) << r.output;
  r = gtrack(eval + "--json " + (dir / "e.json").string() + " --per-frame " + (dir / "e.json").string());
  EXPECT_EQ(r.code, 2) << r.output;
  EXPECT_NE(r.output.find("e.json: given to both --json and --per-frame; expected two files"), std::string::npos)
      << r.output;
  r = gtrack("render -c " + config.string() + " -p 0,0,100,0,0,0,0,0,0,0,0,0 -o " + (dir / "m.png").string() +
             " --obj " + config.string());
  EXPECT_EQ(r.code, 2) << r.output;
  EXPECT_NE(r.output.find("is the --config input; --obj would overwrite it"), std::string::npos) << r.output;
  // A device is no file to overwrite: /dev/null may take both outputs.
  r = gtrack(eval + "--json /dev/null --per-frame /dev/null");
  EXPECT_EQ(r.code, 0) << r.output;
  EXPECT_EQ(read_file(truth), truth_text);
  EXPECT_EQ(read_file(config), config_text);
  EXPECT_FALSE(fs::exists(dir / "e.json"));
  // A full disk: the write that fails when the buffer goes out is an error.
  if (fs::exists("/dev/full")) {
    r = gtrack(eval + "--json /dev/full");
    EXPECT_EQ(r.code, 1) << r.output;
    EXPECT_NE(r.output.find("/dev/full: write failed (No space left on device)"), std::string::npos) << r.output;
  }
}

// A config or a pose table that never ends is stopped with one line, not
// read until memory runs out.
TEST(Cli, AnEndlessConfigOrTableIsStopped) {
  CliRun r = gtrack("render -c /dev/zero -p 0,0,100,0,0,0,0,0,0,0,0,0 -o x.png");
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.output.find("/dev/zero: more than 16 MiB; expected a TOML config file"), std::string::npos) << r.output;
  const fs::path dir = fs::temp_directory_path() / "gtrack_cli_test" / "endless";
  fs::remove_all(dir);
  ASSERT_EQ(gtrack("synth --frames 1 --seed 2 --out " + dir.string()).code, 0);
  r = gtrack("eval -t /dev/zero -e " + (dir / "ground_truth.csv").string() + " -c " + (dir / "sequence.toml").string());
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.output.find("/dev/zero:1: a line of more than 65536 characters"), std::string::npos) << r.output;
  r = gtrack(track_of(dir) + " --no-overlay -o " + (dir / "out").string() + " --restart-from /dev/zero");
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.output.find("/dev/zero:1: a line of more than 65536 characters"), std::string::npos) << r.output;
}

// The truth's header and its rows whose line number `every` divides
// (frames 1, 3, 5 ... for 2), as estimates (its pose
// columns, without visible, in_view and occluded).
std::string truth_as_estimates(const fs::path& truth, int every = 1) {
  std::ifstream in(truth);
  std::string text;
  int line = 0;
  for (std::string l; std::getline(in, l); ++line) {
    for (int k = 0; k < 3; ++k) l = l.substr(0, l.rfind(','));
    if (line % every == 0) text += l + "\n";
  }
  return text;
}

// --off-track-in-plane leaves depth out of the off-track judgement: an
// estimate 300 um deeper than the truth is off track at 200 um in 3D and
// on track across the viewing axis.
TEST(Cli, EvalJudgesOffTrackAcrossTheViewingAxisWhenAsked) {
  const fs::path dir = fs::temp_directory_path() / "gtrack_cli_test" / "off_track_in_plane";
  fs::remove_all(dir);
  ASSERT_EQ(gtrack("synth --frames 2 --seed 4 --out " + dir.string()).code, 0);
  std::string rows_text;
  {
    std::stringstream in(read_file(dir / "ground_truth.csv"));
    bool header = true;
    for (std::string l; std::getline(in, l); header = false) {
      for (int k = 0; k < 3; ++k) l.erase(l.rfind(','));  // the truth's share columns
      if (!header) {
        // frame,x,y,z,...: z 0.3 mm further.
        const std::size_t a = l.find(',', l.find(',', l.find(',') + 1) + 1) + 1, b = l.find(',', a);
        l.replace(a, b - a, std::to_string(std::stod(l.substr(a, b - a)) + 0.3));
      }
      rows_text += l + "\n";
    }
  }
  std::ofstream(dir / "deeper.csv") << rows_text;
  const std::string eval = "eval -t " + (dir / "ground_truth.csv").string() + " -e " + (dir / "deeper.csv").string();
  CliRun r = gtrack(eval + " --off-track-um 200");
  EXPECT_EQ(r.code, 0) << r.output;
  EXPECT_NE(r.output.find("2 off track: endpoints > 200 um in 3D"), std::string::npos) << r.output;
  r = gtrack(eval + " --off-track-um 200 --off-track-in-plane --json " + (dir / "e.json").string());
  EXPECT_EQ(r.code, 0) << r.output;
  EXPECT_NE(r.output.find("0 off track: endpoints > 200 um across the viewing axis"), std::string::npos) << r.output;
  EXPECT_NE(read_file(dir / "e.json").find("\"off_track_in_plane\": true"), std::string::npos);
}

// A run with --frames and --every has no row for the frames it skipped:
// eval counts them as lost and says which options judge only the others;
// with them, only those frames are judged.
TEST(Cli, EvalJudgesTheFramesARunTookWithFramesAndEvery) {
  const fs::path dir = fs::temp_directory_path() / "gtrack_cli_test" / "eval_every";
  fs::remove_all(dir);
  ASSERT_EQ(gtrack("synth --frames 7 --seed 6 --out " + dir.string()).code, 0);
  fs::create_directories(dir / "run");
  const fs::path estimates = dir / "run" / "estimates.csv";
  std::ofstream(estimates) << truth_as_estimates(dir / "ground_truth.csv", 2);  // frames 1, 3, 5
  const std::string eval = "eval -t " + (dir / "ground_truth.csv").string() + " -e " + estimates.string();
  CliRun r = gtrack(eval);
  EXPECT_EQ(r.code, 0) << r.output;
  EXPECT_EQ(r.output.find("images the world otherwise"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("4 frames of"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("(--frames 1: --every 2), evaluate with the same options"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("the estimates are of frames 1 to 5 and hold one frame in 2"), std::string::npos)
      << r.output;
  EXPECT_NE(r.output.find("lost in all 4 (missing 4)"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("  position in-plane "), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("  depth "), std::string::npos) << r.output;
  r = gtrack(eval + " --frames 1: --every 2");
  EXPECT_EQ(r.code, 0) << r.output;
  EXPECT_NE(r.output.find("frames 3: "), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("lost in all 0 (missing 0)"), std::string::npos) << r.output;
  EXPECT_EQ(r.output.find("have no estimate"), std::string::npos) << r.output;
  // A run that stopped early (--frames 1:4): the end is said too.
  const fs::path early = dir / "early.csv";
  std::string rows = truth_as_estimates(dir / "ground_truth.csv", 2);  // frames 1, 3, 5
  rows.erase(rows.rfind('\n', rows.size() - 2) + 1);                  // without frame 5
  std::ofstream(early) << rows;
  r = gtrack("eval -t " + (dir / "ground_truth.csv").string() + " -e " + early.string());
  EXPECT_NE(r.output.find("the estimates are of frames 1 to 3 and hold one frame in 2: for a run that tracked only "
                          "those (--frames 1:4 --every 2)"),
            std::string::npos)
      << r.output;
  // Given --frames as the run had it but not --every: the end said is the
  // run's, not that of the frames eval was given.
  r = gtrack("eval -t " + (dir / "ground_truth.csv").string() + " -e " + early.string() + " --frames 1:4");
  EXPECT_NE(r.output.find("(--frames 1:4 --every 2), evaluate with the same options"), std::string::npos) << r.output;
  r = gtrack(eval + " --frames 7:");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.output.find("--frames/--every select none of the frames of"), std::string::npos) << r.output;
  // The run's own config beside the estimates, with another camera: said.
  std::ofstream(dir / "run" / "run_config.toml") << replaced(read_file(dir / "sequence.toml"), "\nfx = ", "\nfx = 2");
  r = gtrack(eval);
  EXPECT_NE(r.output.find("run_config.toml: its [sensor] images the world otherwise than"), std::string::npos)
      << r.output;
  EXPECT_EQ(r.output.find("its gripper model"), std::string::npos) << r.output;
  // With another gripper (its links longer): said too.
  {
    std::string text = read_file(dir / "sequence.toml");
    text = replaced(text, "[gripper]\n", "[gripper]\nlink_lengths_mm = [0.4, 0.4, 0.4, 0.3]\n");
    std::ofstream(dir / "run" / "run_config.toml") << text;
  }
  r = gtrack(eval);
  EXPECT_NE(r.output.find("run_config.toml: its gripper model ('hydrogel_six_finger') differs from"), std::string::npos)
      << r.output;
  // A --config that does not exist is said to be missing.
  r = gtrack(eval + " --config " + (dir / "nowhere.toml").string());
  EXPECT_NE(r.output.find("nowhere.toml: no such file (--config)"), std::string::npos) << r.output;
}

TEST(Cli, EvalRefusesMalformedTables) {
  const fs::path dir = fs::temp_directory_path() / "gtrack_cli_test" / "eval_strict";
  fs::remove_all(dir);
  ASSERT_EQ(gtrack("synth --frames 3 --seed 6 --out " + dir.string()).code, 0);
  std::ifstream in(dir / "ground_truth.csv");
  std::vector<std::string> rows;
  for (std::string l; std::getline(in, l);) rows.push_back(l);
  ASSERT_EQ(rows.size(), 4u);
  const auto table = [&](const std::string& name, const std::vector<std::string>& r) {
    std::string text;
    for (const auto& l : r) text += l + "\n";
    return write(name, text);
  };
  const fs::path truth = dir / "ground_truth.csv";
  const auto eval = [&](const fs::path& t, const fs::path& e) {
    return gtrack("eval -c " + (dir / "sequence.toml").string() + " -t " + t.string() + " -e " + e.string());
  };
  CliRun r = eval(truth, table("twice.csv", {rows[0], rows[1], rows[2], rows[1]}));
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.output.find("twice.csv:4: frame 0 again (first at line 2)"), std::string::npos) << r.output;
  r = eval(table("in_view.csv", {rows[0], replaced(rows[1], ",1.0000,", ",abc,"), rows[2]}), truth);
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.output.find("in_view.csv:2: expected a number for 'visible', got 'abc'"), std::string::npos)
      << r.output;
  r = eval(table("share.csv", {rows[0], rows[1].substr(0, rows[1].rfind(',')) + ",1.5", rows[2]}), truth);
  EXPECT_NE(r.output.find("share.csv:2: expected a share from 0 to 1 for 'occluded', got '1.5'"), std::string::npos)
      << r.output;
  r = eval(truth, truth);
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.output.find("ground_truth.csv:1: has the ground truth's 'in_view' and 'occluded' columns; expected "
                          "estimates"),
            std::string::npos)
      << r.output;
  r = eval(truth, table("wide.csv", {rows[0], rows[1] + ",7"}));
  EXPECT_NE(r.output.find("wide.csv:2: expected 16 columns, got 17"), std::string::npos) << r.output;
  r = eval(truth, table("huge_frame.csv", {rows[0], "1e300" + rows[1].substr(1)}));
  EXPECT_NE(r.output.find("huge_frame.csv:2: expected a frame index (a whole number from 0), got '1e300'"),
            std::string::npos)
      << r.output;
  // --restart-from refuses a start that is not finite, naming the table.
  const fs::path nan_table = table("nan_start.csv", {rows[0], replaced(rows[1], ",1.600000,", ",nan,")});
  const CliRun nan_run = gtrack(track_of(dir) + " --no-overlay --frames 1:2 -o " + (dir / "out").string() +
                                " --restart-from " + nan_table.string());
  EXPECT_EQ(nan_run.code, 1);
  EXPECT_NE(nan_run.output.find("nan_start.csv: frame 0: a configuration that is not finite"), std::string::npos)
      << nan_run.output;
  // A truth with fewer joint columns than the model has fingers is refused
  // as the estimates are, not read past its end.
  std::vector<std::string> narrow;
  for (const auto& l : rows) {
    std::vector<std::string> cells;
    std::stringstream ss(l);
    for (std::string c; std::getline(ss, c, ',');) cells.push_back(c);
    cells.erase(cells.begin() + 11, cells.begin() + 13);  // q5_deg, q6_deg
    std::string joined;
    for (const auto& c : cells) joined += (joined.empty() ? "" : ",") + c;
    narrow.push_back(joined);
  }
  ASSERT_EQ(narrow[0].find("q5_deg"), std::string::npos) << narrow[0];
  r = eval(table("four_fingers.csv", narrow), truth);
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.output.find("four_fingers.csv:1: 4 joint columns, the model in"), std::string::npos) << r.output;
  r = eval(truth, table("header_only.csv", {rows[0]}));
  EXPECT_NE(r.output.find("header_only.csv: a header and no rows"), std::string::npos) << r.output;
  r = eval(dir / "no_such.csv", truth);
  EXPECT_NE(r.output.find("no_such.csv: no such file"), std::string::npos) << r.output;
  // A column named twice is refused, not read from one of the two.
  r = eval(truth, table("dup.csv", {rows[0] + ",x_mm", rows[1] + ",7", rows[2] + ",7"}));
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.output.find("dup.csv:1: column 'x_mm' appears twice (columns 2 and 17)"), std::string::npos)
      << r.output;
  // The tracker's estimates given as the truth: said, not scored.
  ASSERT_EQ(gtrack(track_of(dir) + " --no-overlay -o " + (dir / "tracked").string()).code, 0);
  r = eval(dir / "tracked" / "estimates.csv", truth);
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.output.find("estimates.csv:1: has the tracker's 'status' column; expected a ground truth"),
            std::string::npos)
      << r.output;
  // Estimates of which no row is for a frame of the truth (renumbered, or
  // another sequence's): refused, not reported as every frame lost.
  std::vector<std::string> shifted;
  {
    std::ifstream tracked(dir / "tracked" / "estimates.csv");
    for (std::string l; std::getline(tracked, l);) {
      shifted.push_back(shifted.empty() ? l : std::to_string(100 + std::stoi(l)) + l.substr(l.find(',')));
    }
  }
  ASSERT_EQ(shifted.size(), 4u);
  r = eval(truth, table("renumbered.csv", shifted));
  EXPECT_EQ(r.code, 1) << r.output;
  EXPECT_NE(r.output.find("renumbered.csv: no row is for a frame of " + truth.string() +
                          " (its frames 100 to 102, the truth's 0 to 2)"),
            std::string::npos)
      << r.output;
  shifted[1] = std::to_string(0) + shifted[1].substr(shifted[1].find(','));  // one row in common: evaluated
  r = eval(truth, table("one_in_common.csv", shifted));
  EXPECT_EQ(r.code, 0) << r.output;
  EXPECT_NE(r.output.find("2 rows are for frames"), std::string::npos) << r.output;
}

// The rows of eval --breakdown: per group, its frames and the share of the
// summed orientation error it says (-1 when it says none).
struct BreakdownRow {
  int frames = 0;
  int orientation_share = -1;
};
std::map<std::string, BreakdownRow> breakdown_rows(const std::string& output) {
  std::map<std::string, BreakdownRow> rows;
  std::istringstream lines_in(output);
  for (std::string l; std::getline(lines_in, l);) {
    const auto at = l.find(" frames  in-plane");
    if (at == std::string::npos) continue;
    const auto digits = l.find_last_not_of("0123456789", at - 1);
    std::string name = l.substr(0, digits + 1);
    name = name.substr(name.find_first_not_of(' '));
    name = name.substr(0, name.find_last_not_of(' ') + 1);
    BreakdownRow& row = rows[name];
    row.frames = std::stoi(l.substr(digits + 1, at - digits - 1));
    if (const auto share = l.find(" % of the summed orientation error"); share != std::string::npos) {
      row.orientation_share = std::stoi(l.substr(l.rfind('(', share) + 1));
    }
  }
  return rows;
}

// eval --breakdown: every in-view frame with an estimate falls in exactly
// one occlusion group, the unoccluded ones again by the allowance, those
// with a tilt margin by it, and, with the truth scored by the track
// (--score-truth), every frame in exactly one of the three groups that say
// whether the truth scored lower.
TEST(Cli, EvalBreakdownGroupsEveryEvaluatedFrameOnce) {
  const fs::path dir = fs::temp_directory_path() / "gtrack_cli_test" / "breakdown";
  fs::remove_all(dir);
  ASSERT_EQ(gtrack("synth --frames 20 --seed 2 --out " + dir.string()).code, 0);
  ASSERT_EQ(
      gtrack(track_of(dir) + " -s " + (dir / "stimulus.csv").string() + " --no-overlay -o " + (dir / "out").string() +
             " --score-truth " + (dir / "ground_truth.csv").string())
          .code,
      0);
  {
    std::ifstream jsonl(dir / "out" / "estimates.jsonl");
    int with_reference = 0;
    for (std::string l; std::getline(jsonl, l);) with_reference += l.find("\"reference\":{\"cost\":") != std::string::npos;
    EXPECT_EQ(with_reference, 20);
  }
  const CliRun r = gtrack("eval -t " + (dir / "ground_truth.csv").string() + " -e " +
                          (dir / "out" / "estimates.csv").string() + " --breakdown");
  ASSERT_EQ(r.code, 0) << r.output;
  int evaluated = -1;  // in view, with a usable estimate (lost frames are not)
  ASSERT_EQ(std::sscanf(r.output.c_str(), "frames %*d: %*d in view (%d evaluated", &evaluated), 1) << r.output;
  std::map<std::string, int> groups;
  for (const auto& [name, row] : breakdown_rows(r.output)) groups[name] = row.frames;
  int occlusion = 0;
  for (const char* g : {"unoccluded", "< 40 % hidden", ">= 40 % hidden", "partly out of view"}) occlusion += groups[g];
  EXPECT_EQ(occlusion, evaluated) << r.output;
  EXPECT_EQ(groups["unoccluded, no allowance"] + groups["unoccluded, an allowance left"], groups["unoccluded"])
      << r.output;
  EXPECT_GT(groups["unoccluded"], 0) << r.output;
  EXPECT_EQ(groups["truth scores lower"] + groups["truth spills over allowance"] + groups["truth scores no lower"],
            evaluated)
      << r.output;
  // The frames the mirror check ran on, by their tilt margin: each once.
  int checked = 0;
  {
    std::ifstream jsonl(dir / "out" / "estimates.jsonl");
    for (std::string l; std::getline(jsonl, l);) checked += l.find("\"tilt_margin\":") != std::string::npos;
  }
  const int by_margin = groups["tilt margin < 0.1"] + groups["tilt margin >= 0.1"];
  EXPECT_GT(by_margin, 0) << r.output;
  EXPECT_LE(by_margin, std::min(checked, evaluated)) << r.output;
}

// eval --breakdown by kind of frame, on a truth whose shares in view are
// set by hand: a gripper going out (frames 5-7), out of view (8-10),
// coming back in (11-13), then wholly in view; the estimates are the truth
// turned by 10 degrees about the line of sight while it comes in, by 2
// elsewhere. Each frame partly out of view is coming in or going out, the
// 20 frames after the last one out of view are counted apart, and the
// shares of the orientation error follow from the errors (30 and 6 of 88).
TEST(Cli, EvalBreakdownSaysWhereTheGripperComesBackIntoView) {
  const fs::path dir = fs::temp_directory_path() / "gtrack_cli_test" / "breakdown_returns";
  fs::remove_all(dir);
  ASSERT_EQ(gtrack("synth --frames 35 --seed 6 --out " + dir.string()).code, 0);
  const std::vector<double> going_out = {0.8, 0.5, 0.2}, coming_in = {0.3, 0.6, 0.9};
  const auto share_in_view = [&](int frame) {
    if (frame >= 5 && frame <= 7) return going_out[static_cast<std::size_t>(frame - 5)];
    if (frame >= 8 && frame <= 10) return 0.05;
    if (frame >= 11 && frame <= 13) return coming_in[static_cast<std::size_t>(frame - 11)];
    return 1.0;
  };
  std::string truth, estimates;
  {
    std::stringstream in(read_file(dir / "ground_truth.csv"));
    std::string l;
    std::getline(in, l);
    truth = l + "\n";
    estimates = l.substr(0, l.rfind(",visible")) + "\n";
    for (int frame = 0; std::getline(in, l); ++frame) {
      std::vector<std::string> cells;
      std::stringstream row(l);
      for (std::string c; std::getline(row, c, ',');) cells.push_back(c);
      ASSERT_EQ(cells.size(), 16u) << l;
      const double v = share_in_view(frame);
      cells[13] = cells[14] = std::to_string(v);  // visible, in_view
      cells[15] = "0";                            // occluded
      for (std::size_t k = 0; k < cells.size(); ++k) truth += (k ? "," : "") + cells[k];
      truth += "\n";
      cells[6] = std::to_string(std::stod(cells[6]) + (frame >= 11 && frame <= 13 ? 10.0 : 2.0));  // rz
      for (std::size_t k = 0; k < 13; ++k) estimates += (k ? "," : "") + cells[k];
      estimates += "\n";
    }
  }
  std::ofstream(dir / "truth.csv") << truth;
  std::ofstream(dir / "estimates.csv") << estimates;
  const CliRun r = gtrack("eval -c " + (dir / "sequence.toml").string() + " -t " + (dir / "truth.csv").string() +
                          " -e " + (dir / "estimates.csv").string() + " --breakdown");
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_NE(r.output.find("frames 35: 32 in view (32 evaluated"), std::string::npos) << r.output;
  auto rows = breakdown_rows(r.output);
  EXPECT_EQ(rows["unoccluded"].frames, 26) << r.output;
  EXPECT_EQ(rows["partly out of view"].frames, 6) << r.output;
  EXPECT_EQ(rows["partly out of view, coming in"].frames, 3) << r.output;
  EXPECT_EQ(rows["partly out of view, going out"].frames, 3) << r.output;
  EXPECT_EQ(rows["in view, <= 20 frames after a return"].frames, 17) << r.output;  // frames 14-30
  EXPECT_EQ(rows["partly out of view, coming in"].orientation_share, 34) << r.output;  // 30 of 88
  EXPECT_EQ(rows["partly out of view, going out"].orientation_share, 7) << r.output;   // 6 of 88
  EXPECT_EQ(rows["in view, <= 20 frames after a return"].orientation_share, 39) << r.output;  // 34 of 88
  EXPECT_EQ(rows["unoccluded"].orientation_share + rows["partly out of view"].orientation_share, 100) << r.output;
}

// --two-pass: the recording is tracked again backwards, and each frame of
// two_pass/estimates.csv is the forward or the backward estimate. A forward
// run started 1.5 mm and 40 degrees from the truth scores worse on its first
// frame than the backward track, which arrives there from the frames after.
TEST(Cli, TwoPassTakesEachFrameFromTheForwardOrTheBackwardTrack) {
  const fs::path dir = fs::temp_directory_path() / "gtrack_cli_test" / "two_pass";
  fs::remove_all(dir);
  ASSERT_EQ(gtrack("synth --frames 12 --seed 3 --out " + dir.string()).code, 0);
  const auto truth = read_csv(dir / "ground_truth.csv");
  ASSERT_EQ(truth.size(), 13u);
  std::string start = std::to_string(std::stod(truth[1][1]) - 1.5);
  for (int c = 2; c <= 12; ++c) start += ", " + (c == 6 ? std::to_string(std::stod(truth[1][c]) + 40) : truth[1][c]);
  const std::string config = replaced(read_file(dir / "sequence.toml"), "[tracker]\n",
                                      "[tracker]\ninitial_pose = [" + start + "]\n");
  std::ofstream(dir / "started_off.toml") << config;
  const CliRun r = gtrack("track -c " + (dir / "started_off.toml").string() + " -i " + (dir / "frames").string() +
                          " -s " + (dir / "stimulus.csv").string() + " --no-overlay --two-pass -o " +
                          (dir / "out").string());
  ASSERT_EQ(r.code, 0) << r.output;
  const auto forward = read_csv(dir / "out" / "estimates.csv");
  const auto backward = read_csv(dir / "out" / "backward" / "estimates.csv");
  const auto both = read_csv(dir / "out" / "two_pass" / "estimates.csv");
  ASSERT_EQ(forward.size(), 13u);
  ASSERT_EQ(backward.size(), 13u);
  ASSERT_EQ(both.size(), 13u);
  // Frame, position and joints; the orientation is smoothed over
  // neighbouring frames ([tracker] two_pass_smoothing).
  const auto position_and_joints = [](const std::vector<std::string>& row) {
    std::vector<std::string> kept(row.begin(), row.begin() + 4);
    kept.insert(kept.end(), row.begin() + 7, row.begin() + 13);
    return kept;
  };
  const auto turn_deg = [](const std::vector<std::string>& a, const std::vector<std::string>& b) {
    const auto rotation = [](const std::vector<std::string>& r) {
      return Eigen::Quaterniond(gtrack::rotation_from_euler_deg(std::stod(r[4]), std::stod(r[5]), std::stod(r[6])));
    };
    return rotation(a).angularDistance(rotation(b)) * 180 / M_PI;
  };
  std::vector<std::string> both_jsonl{""};  // 1-based like the CSV rows
  {
    std::ifstream jsonl(dir / "out" / "two_pass" / "estimates.jsonl");
    for (std::string l; std::getline(jsonl, l);) both_jsonl.push_back(l);
  }
  ASSERT_EQ(both_jsonl.size(), 13u);
  int from_backward = 0;
  double smoothed_deg = 0;
  for (int i = 1; i <= 12; ++i) {
    // The backward track's rows are written as made: the last frame first.
    EXPECT_EQ(backward[i][0], forward[13 - i][0]);
    ASSERT_EQ(both[i][0], forward[i][0]);
    const auto& b = backward[13 - i];
    const bool is_forward = position_and_joints(both[i]) == position_and_joints(forward[i]);
    const bool is_backward = position_and_joints(both[i]) == position_and_joints(b);
    EXPECT_TRUE(is_forward || is_backward) << "frame " << both[i][0];
    // The table's .jsonl names the pass the row was taken from.
    const bool named_forward = both_jsonl[i].find("\"two_pass\":\"forward\"") != std::string::npos;
    const bool named_backward = both_jsonl[i].find("\"two_pass\":\"backward\"") != std::string::npos;
    EXPECT_TRUE(named_forward ? is_forward : named_backward && is_backward) << both_jsonl[i];
    smoothed_deg += turn_deg(both[i], named_forward ? forward[i] : b) / 12;
    from_backward += named_backward;
  }
  // The mean change the smoothing made, as printed (the files' angles have 4 decimals).
  const auto said = r.output.find("orientations smoothed (");
  ASSERT_NE(said, std::string::npos) << r.output;
  EXPECT_NEAR(std::stod(r.output.substr(said + 23)), smoothed_deg, 0.01) << r.output;
  EXPECT_GT(smoothed_deg, 0.01);
  EXPECT_NE(r.output.find("two-pass: 12 frames, " + std::to_string(from_backward) + " taken from the backward pass"),
            std::string::npos)
      << r.output;
  const auto inplane_mm = [&](const std::vector<std::string>& row) {
    return std::hypot(std::stod(row[1]) - std::stod(truth[1][1]), std::stod(row[2]) - std::stod(truth[1][2]));
  };
  EXPECT_GT(inplane_mm(forward[1]), 0.1) << "the forward run was meant to start off";
  EXPECT_LT(inplane_mm(both[1]), 0.03);

  // The same command with --resume after the run is done tracks nothing
  // more and makes the same table from the forward rows read back.
  const CliRun again = gtrack("track -c " + (dir / "started_off.toml").string() + " -i " + (dir / "frames").string() +
                              " -s " + (dir / "stimulus.csv").string() + " --no-overlay --two-pass --resume -o " +
                              (dir / "out").string());
  ASSERT_EQ(again.code, 0) << again.output;
  EXPECT_NE(again.output.find("0 frames (0 lost)"), std::string::npos) << again.output;
  const auto both_again = read_csv(dir / "out" / "two_pass" / "estimates.csv");
  ASSERT_EQ(both_again.size(), both.size());
  for (size_t i = 0; i < both.size(); ++i) {
    EXPECT_EQ(std::vector<std::string>(both_again[i].begin(), both_again[i].end() - 1),
              std::vector<std::string>(both[i].begin(), both[i].end() - 1))  // less ms
        << "row " << i;
  }

  // What cannot be gone back over is refused in one line, before any file is written.
  for (const std::string& args :
       {std::string(" --restart-from ") + (dir / "ground_truth.csv").string(), std::string(" --follow-input 1")}) {
    const CliRun refused = gtrack(track_of(dir) + " --two-pass -o " + (dir / "refused").string() + args);
    EXPECT_EQ(refused.code, 2);
    EXPECT_EQ(lines(refused.output), 1) << refused.output;
    EXPECT_NE(refused.output.find("--two-pass cannot be combined with --"), std::string::npos) << refused.output;
    EXPECT_FALSE(fs::exists(dir / "refused"));
  }
}

TEST(Cli, UsageErrors) {
  EXPECT_EQ(gtrack("rendr").code, 2);
  EXPECT_EQ(gtrack("render").code, 2);
  CliRun v = gtrack("--version");
  EXPECT_EQ(v.code, 0);
  EXPECT_NE(v.output.find("gtrack "), std::string::npos);
  EXPECT_EQ(gtrack("track --version").output, v.output);
  // Every required option missing is named, in the order --help lists them.
  v = gtrack("eval");
  EXPECT_EQ(v.code, 2);
  EXPECT_NE(v.output.find("missing --truth, --estimates (see 'gtrack eval --help')"), std::string::npos) << v.output;
  // Numbers out of their range, NaN included, are refused before any work.
  const fs::path out = fs::temp_directory_path() / "gtrack_cli_test" / "usage";
  CliRun r = gtrack("synth --joint-noise nan --frames 2 --out " + out.string());
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.output.find("--joint-noise must be a number of degrees in [0, 90]"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(out));
  r = gtrack("bench --seconds 1e300");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.output.find("--seconds must be in (0, 3600]"), std::string::npos) << r.output;
  r = gtrack("bench --batch 0");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.output.find("--batch must be in 1-4096 hypotheses"), std::string::npos) << r.output;
  // A short bench gives every figure, from the rounds asked for (what
  // they measure is the benchmark's business, not a test's).
  {
    const NoLeakCheckForGl gl_run;
    r = gtrack("bench --json --seconds 0.2 --rounds 2", "2>/dev/null");
  }
  EXPECT_EQ(r.code, 0) << r.output;
  for (const char* key : {"\"hypotheses_per_s\": {\"cpu\": ", "\"frames_per_s\": {\"cpu\": ", "\"rounds\": 2",
                          "\"cpu_over_opencv_baseline_range\": {\"1\": \""}) {
    EXPECT_NE(r.output.find(key), std::string::npos) << key << " in " << r.output;
  }
  EXPECT_EQ(r.output.find("\"cpu\": null"), std::string::npos) << r.output;
  EXPECT_EQ(r.output.find("\"opencv_baseline\": null"), std::string::npos) << r.output;
  // gl against cpu, as a ratio of the same run, whenever gl was measured.
  EXPECT_NE(r.output.find("\"gl_over_cpu\": {\"hypotheses_per_s\": "), std::string::npos) << r.output;
  EXPECT_EQ(r.output.find("\"gl\": null") == std::string::npos,
            r.output.find("\"gl_over_cpu\": {\"hypotheses_per_s\": null") == std::string::npos)
      << r.output;
  r = gtrack("bench --rounds 0");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.output.find("--rounds must be in 1-100"), std::string::npos) << r.output;
  r = gtrack("track -c " + (fs::path(GTRACK_TEST_SOURCE_DIR) / "configs" / "microscope_hydrogel.toml").string() +
             " -i frames --stimulus-column B_mT --out " + out.string());
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.output.find("--stimulus-column needs --stimulus"), std::string::npos) << r.output;
}

// sweep checks its config and its output folder before it makes any
// sequence: an error names the user's file, not one made from it.
TEST(Cli, SweepChecksItsConfigAndFolderFirst) {
  const fs::path dir = fs::temp_directory_path() / "gtrack_cli_test" / "sweep_bad";
  fs::remove_all(dir);
  const fs::path cfg = write("sweep_bad.toml", hydrogel_config() + "\n[pso]\nparticles = -5\n");
  const std::string tiny = " --particles 4 --generations 2 --sigmas 0 --frames 2 --figure 6a";
  CliRun r = gtrack("sweep --config " + cfg.string() + tiny + " --out " + dir.string());
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.output.find(cfg.string() + ":"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("key 'pso.particles'"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(dir));
  r = gtrack("sweep" + tiny + " --out " + cfg.string() + "/x");
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.output.find(cfg.string() + "/x: cannot create the folder"), std::string::npos) << r.output;
  // A list is numbers separated by commas: another separator, a number
  // followed by text or a hexadecimal one is refused, not read as its first
  // number.
  for (const auto& [option, value] : std::vector<std::pair<std::string, std::string>>{
           {"sigmas", "0.5 1"}, {"particles", "16;32"}, {"particles", "8abc"}, {"sigmas", "0x5"}, {"sigmas", "1,,2"}}) {
    r = gtrack("sweep --" + option + " \"" + value + "\" --out " + dir.string());
    EXPECT_EQ(r.code, 2) << value;
    EXPECT_NE(r.output.find("--" + option + ": '"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("' is not a number (expected numbers separated by commas"), std::string::npos) << r.output;
  }
  EXPECT_FALSE(fs::exists(dir));
  r = gtrack("sweep --particles \" 4 , +6\" --generations 2 --frames 2 --figure 6a --out " + dir.string());
  EXPECT_EQ(r.code, 0) << r.output;
  EXPECT_EQ(lines(read_file(dir / "fig6a.csv")), 1 + 2);
  // A figure's table that cannot be written stops the sweep with its name.
  fs::remove(dir / "fig6a.csv");
  fs::create_directories(dir / "fig6a.csv");
  r = gtrack("sweep --particles 4 --generations 2 --frames 2 --figure 6a --out " + dir.string());
  EXPECT_EQ(r.code, 1) << r.output;
  EXPECT_NE(r.output.find((dir / "fig6a.csv").string() + ": cannot open for writing (it is a folder; expected a file)"),
            std::string::npos)
      << r.output;
}

// The sequences a sweep keeps are made again when a file its config names
// (here a camera calibration) has changed since, not scored against the
// old frames.
TEST(Cli, SweepRemakesItsSequencesWhenAFileTheConfigNamesChanges) {
  const fs::path dir = fs::temp_directory_path() / "gtrack_cli_test" / "sweep_files";
  fs::remove_all(dir);
  fs::create_directories(dir / "lab");
  const auto write_camera = [&](double f) {
    cv::FileStorage camera((dir / "lab" / "camera.yml").string(), cv::FileStorage::WRITE);
    camera << "image_width" << 256 << "image_height" << 256;
    camera << "camera_matrix" << (cv::Mat_<double>(3, 3) << f, 0, 127.5, 0, f, 127.5, 0, 0, 1);
    camera << "distortion_coefficients" << cv::Mat::zeros(1, 5, CV_64F);
  };
  write_camera(3200);
  std::ofstream(dir / "lab" / "lab.toml")
      << "[sensor]\nplugin = \"pinhole_microscope\"\nwidth = 256\nheight = 256\ncalibration = \"camera.yml\"\n"
         "[gripper]\nplugin = \"hydrogel_six_finger\"\n[stimulus]\nplugin = \"temperature_hysteresis\"\n";
  const std::string sweep = "sweep --config " + (dir / "lab" / "lab.toml").string() +
                            " --particles 4 --generations 2 --frames 2 --figure 6a --out " + (dir / "out").string();
  CliRun r = gtrack(sweep);
  ASSERT_EQ(r.code, 0) << r.output;
  const fs::path made = dir / "out" / "sequences" / "seq_seed1_noise0" / "made_from.txt";
  const std::string before = read_file(made);
  EXPECT_NE(before.find("file sensor.calibration " + (dir / "lab" / "camera.yml").string() + " "), std::string::npos)
      << before;
  r = gtrack(sweep);  // nothing changed: the sequences are kept
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_EQ(r.output.find("making it again"), std::string::npos) << r.output;
  write_camera(2800);
  r = gtrack(sweep);
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_NE(r.output.find("seq_seed1_noise0 was made from other settings; making it again"), std::string::npos)
      << r.output;
  EXPECT_NE(read_file(made), before);
}

// A config that names a file by a relative path (a calibration beside it):
// the sequence's config names it absolutely, and tracks from there. A
// config given as a pipe is read once.
// synth --config without --preset draws what the config's sensor segments:
// an ultrasound config (here a copy under another name) gets the
// ultrasound preset's grey frames, a copy of a metallic config its
// gripper's preset; a preset whose look the sensor does not segment is
// warned about.
TEST(Cli, SynthTakesThePresetOfTheConfigsSensor) {
  const fs::path dir = fs::temp_directory_path() / "gtrack_cli_test" / "synth_preset";
  fs::remove_all(dir);
  const fs::path lab = write("synth_preset_lab.toml", read_file(fs::path(GTRACK_TEST_SOURCE_DIR) / "configs" /
                                                                "ultrasound_hydrogel.toml"));
  CliRun r = gtrack("synth --config " + lab.string() + " --frames 2 --out " + (dir / "a").string());
  EXPECT_EQ(r.code, 0) << r.output;
  EXPECT_NE(r.output.find("(preset ultrasound, seed 1)"), std::string::npos) << r.output;
  EXPECT_NE(read_file(dir / "a" / "sequence.toml").find("(preset 'ultrasound'"), std::string::npos);
  // Its evaluation names the errors within the imaging plane and across
  // it: an ultrasound image's depth is within the plane.
  std::ofstream(dir / "a" / "estimates.csv") << truth_as_estimates(dir / "a" / "ground_truth.csv");
  r = gtrack("eval -t " + (dir / "a" / "ground_truth.csv").string() + " -e " + (dir / "a" / "estimates.csv").string() +
             " -c " + (dir / "a" / "sequence.toml").string());
  EXPECT_EQ(r.code, 0) << r.output;
  EXPECT_NE(r.output.find("  in the imaging plane "), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("  across the plane "), std::string::npos) << r.output;
  EXPECT_EQ(r.output.find("  depth "), std::string::npos) << r.output;
  // A camera config that segments by luminance gets grey frames too.
  const fs::path grey_camera =
      write("synth_preset_grey.toml", read_file(fs::path(GTRACK_TEST_SOURCE_DIR) / "tests" / "data" /
                                                "microscope_128.toml") +
                                          "\n[observation]\ncolor_space = \"luminance\"\n");
  r = gtrack("synth --config " + grey_camera.string() + " --frames 1 --out " + (dir / "c").string());
  EXPECT_NE(r.output.find("(preset ultrasound, seed 1)"), std::string::npos) << r.output;
  // One whose bounds look for a dark gripper gets the bright-field frames,
  // and tracks them; the ultrasound preset's, asked for, is warned about.
  const fs::path dark_camera =
      write("synth_preset_dark.toml", read_file(fs::path(GTRACK_TEST_SOURCE_DIR) / "tests" / "data" /
                                                "microscope_128.toml") +
                                          "\n[observation]\ncolor_space = \"luminance\"\nluminance_min = 0\n"
                                          "luminance_max = 100\n");
  r = gtrack("synth --config " + dark_camera.string() + " --frames 3 --out " + (dir / "e").string());
  EXPECT_NE(r.output.find("(preset brightfield, seed 1)"), std::string::npos) << r.output;
  r = gtrack(track_of(dir / "e") + " -o " + (dir / "e" / "out").string() + " --no-overlay");
  EXPECT_EQ(r.code, 0) << r.output;
  EXPECT_NE(r.output.find("3 frames (0 lost)"), std::string::npos) << r.output;
  r = gtrack("synth --config " + dark_camera.string() + " --preset ultrasound --frames 1 --out " +
             (dir / "f").string());
  EXPECT_NE(r.output.find("--preset ultrasound draws its gripper at luminance 235, its background at luminance 55, "
                          "but the [observation] bounds of " +
                          dark_camera.string() + " do not take the one without the other"),
            std::string::npos)
      << r.output;
  // A lab's copy of a metallic config, under its own name, gets the preset
  // of that gripper: the hydrogel preset's stimulus never folds it.
  const fs::path two = write("synth_preset_two.toml", read_file(fs::path(GTRACK_TEST_SOURCE_DIR) / "configs" /
                                                                "microscope_metallic_two.toml"));
  r = gtrack("synth --config " + two.string() + " --frames 1 --out " + (dir / "d").string());
  EXPECT_NE(r.output.find("(preset metallic_two, seed 1)"), std::string::npos) << r.output;
  r = gtrack("synth --config " + lab.string() + " --preset microscope --frames 1 --out " + (dir / "b").string());
  EXPECT_EQ(r.code, 0) << r.output;
  EXPECT_NE(r.output.find("--preset microscope draws colour frames, but " + lab.string() + " segments grey levels"),
            std::string::npos)
      << r.output;
}

// synth checks the engine's tables as track does, before anything is
// drawn: its sequence.toml carries them, and its `track it:` line failed.
TEST(Cli, SynthChecksTheEnginesTablesFirst) {
  const fs::path dir = fs::temp_directory_path() / "gtrack_cli_test" / "synth_engine";
  fs::remove_all(dir);
  const fs::path zero = write("synth_engine_zero.toml", hydrogel_config() + "\n[pso]\nparticles = 0\n");
  CliRun r = gtrack("synth --config " + zero.string() + " --frames 1 --out " + dir.string());
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.output.find("key 'pso.particles': value 0 is out of range"), std::string::npos) << r.output;
  const fs::path typo = write("synth_engine_typo.toml", hydrogel_config() + "\n[pso]\npartcles = 10\n");
  r = gtrack("synth --config " + typo.string() + " --frames 1 --out " + dir.string());
  EXPECT_NE(r.output.find("key 'pso.partcles': unknown key in [pso]"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(dir));
}

// A malformed option value is a usage error (exit status 2), whichever
// option: --frames and --log-level had exited 1, as an input error does.
TEST(Cli, AMalformedOptionIsAUsageError) {
  const fs::path cfg = write("usage_codes.toml", hydrogel_config());
  for (const std::string& args : std::vector<std::string>{"track --config " + cfg.string() + " --input x --out y --frames abc",
                                                          "track --config " + cfg.string() + " --input x --out y --every 0",
                                                          "plugins --log-level loud",
                                                          "render --config " + cfg.string() +
                                                              " --params 0,0,100,0,0,0,0,0,0,0,0,0 --out m.png "
                                                              "--scale 0.001"}) {
    const CliRun r = gtrack(args);
    EXPECT_EQ(r.code, 2) << args << ": " << r.output;
  }
}

// An empty --out would be the working folder, written over without a word.
TEST(Cli, AnEmptyOutIsRefused) {
  const fs::path cfg = write("empty_out.toml", hydrogel_config());
  for (const std::string& args : std::vector<std::string>{"demo --out ''", "synth --frames 1 --out ''", "sweep --out ''",
                                                          "track --config " + cfg.string() + " --input x --out ''"}) {
    const CliRun r = gtrack(args);
    EXPECT_EQ(r.code, 2) << args;
    EXPECT_NE(r.output.find("--out is empty; expected a folder"), std::string::npos) << args << ": " << r.output;
  }
}

TEST(Cli, SynthKeepsTheConfigsFilesAndReadsAPipeOnce) {
  const fs::path dir = fs::temp_directory_path() / "gtrack_cli_test" / "synth_files";
  fs::remove_all(dir);
  fs::create_directories(dir / "lab");
  cv::FileStorage camera((dir / "lab" / "camera.yml").string(), cv::FileStorage::WRITE);
  camera << "image_width" << 256 << "image_height" << 256;
  camera << "camera_matrix" << (cv::Mat_<double>(3, 3) << 3200, 0, 127.5, 0, 3200, 127.5, 0, 0, 1);
  camera << "distortion_coefficients" << cv::Mat::zeros(1, 5, CV_64F);
  camera.release();
  std::ofstream(dir / "lab" / "lab.toml")
      << "[sensor]\nplugin = \"pinhole_microscope\"\nwidth = 256\nheight = 256\ncalibration = \"camera.yml\"\n"
         "[gripper]\nplugin = \"hydrogel_six_finger\"\n[stimulus]\nplugin = \"temperature_hysteresis\"\n";
  const fs::path seq = dir / "seq";
  ASSERT_EQ(gtrack("synth --config " + (dir / "lab" / "lab.toml").string() + " --frames 2 --out " + seq.string()).code,
            0);
  EXPECT_NE(read_file(seq / "sequence.toml").find("calibration = '" + (dir / "lab" / "camera.yml").string() + "'"),
            std::string::npos)
      << read_file(seq / "sequence.toml");
  const CliRun tracked = gtrack(track_of(seq) + " --frames 0:1 --out " + (dir / "track").string());
  EXPECT_EQ(tracked.code, 0) << tracked.output;

  // `cat FILE | gtrack synth --config /dev/stdin ...`, given up after 120 s.
  const fs::path piped = dir / "piped";
  const auto synth_from_pipe = [&](const fs::path& file) {
    const std::string cmd = "cat " + file.string() + " | timeout 120 " + std::string(GTRACK_TEST_BINARY_DIR) +
                            "/bin/gtrack synth --config /dev/stdin --frames 2 --out " + piped.string() + " 2>&1";
    FILE* p = ::popen(cmd.c_str(), "r");
    std::string out;
    std::array<char, 4096> buf;
    while (p && std::fgets(buf.data(), buf.size(), p)) out += buf.data();
    const int status = p ? ::pclose(p) : -1;
    return CliRun{WIFEXITED(status) ? WEXITSTATUS(status) : -1, out};
  };
  // (A pipe's relative paths are taken from the working folder, which has
  // no camera.yml: one line naming it.)
  expect_refusal(synth_from_pipe(dir / "lab" / "lab.toml"), "camera.yml");
  std::ofstream(dir / "plain.toml") << kConfig << "[stimulus]\nplugin = \"temperature_hysteresis\"\n";
  const CliRun plain = synth_from_pipe(dir / "plain.toml");
  EXPECT_EQ(plain.code, 0) << plain.output;
  EXPECT_TRUE(fs::exists(piped / "sequence.toml"));
}

// Frames are decoded on a thread of their own while the tracker works, and
// a decoder's complaints are taken aside from fd 2 meanwhile: gtrack's own
// lines (here a progress line a frame) are written past that, and every one
// of them reaches stderr.
TEST(Cli, EveryProgressLineReachesStderrWhileFramesAreDecoded) {
  const fs::path dir = fs::temp_directory_path() / "gtrack_cli_test" / "progress";
  fs::remove_all(dir);
  constexpr int kFrames = 16;
  ASSERT_EQ(gtrack("synth --frames " + std::to_string(kFrames) + " --seed 4 --out " + dir.string()).code, 0);
  const std::string config = read_file(dir / "sequence.toml");
  ASSERT_NE(config.find("[tracker]\n"), std::string::npos);
  std::ofstream(dir / "progress.toml") << replaced(config, "[tracker]\n", "[tracker]\nprogress_every = 1\n");
  const CliRun r = gtrack("track -c " + (dir / "progress.toml").string() + " -i " + (dir / "frames").string() +
                          " -o " + (dir / "out").string() + " --no-overlay");
  ASSERT_EQ(r.code, 0) << r.output;
  for (int k = 0; k < kFrames; ++k) {
    const std::string line = "frame " + std::to_string(k) + " (" + std::to_string(k + 1) + "/" +
                             std::to_string(kFrames) + ")";
    EXPECT_NE(r.output.find(line), std::string::npos) << line << " missing from:\n" << r.output;
  }
  fs::remove_all(dir);
}

// What passes the bounds besides the gripper. A bar of the gripper's colour,
// larger than it, across the bottom of the frames (a dish's rim, a tank's
// wall): the coarse search also tries each large blob, and the track starts
// on the gripper, not the bar. The same frames strewn with gripper-coloured
// specks: every frame is "ok", and a warning says that the model fits what
// is observed poorly.
TEST(Cli, TrackFindsTheGripperBesideALargerBlobAndSaysWhenTheFitIsPoor) {
  const fs::path dir = fs::temp_directory_path() / "gtrack_cli_test" / "clutter";
  fs::remove_all(dir);
  ASSERT_EQ(gtrack("synth --frames 12 --seed 3 --out " + dir.string()).code, 0);
  const cv::Scalar colour(121, 171, 205);  // the microscope preset's gripper (HSV 18, 105, 205)
  cv::RNG rng(5);
  fs::create_directories(dir / "bar");
  fs::create_directories(dir / "specks");
  for (const auto& entry : fs::directory_iterator(dir / "frames")) {
    const cv::Mat frame = cv::imread(entry.path().string());
    ASSERT_FALSE(frame.empty());
    cv::Mat bar = frame.clone();
    cv::rectangle(bar, cv::Rect(10, 940, 1004, 70), colour, cv::FILLED);  // 70k pixels; the gripper shows < 60k
    cv::imwrite((dir / "bar" / entry.path().filename()).string(), bar);
    cv::Mat specks = frame.clone();
    for (int y = 0; y + 4 <= specks.rows; y += 4) {
      for (int x = 0; x + 4 <= specks.cols; x += 4) {
        if (rng.uniform(0.0, 1.0) < 0.3) cv::rectangle(specks, cv::Rect(x, y, 4, 4), colour, cv::FILLED);
      }
    }
    cv::imwrite((dir / "specks" / entry.path().filename()).string(), specks);
  }
  const CliRun bar = gtrack("track -c " + (dir / "sequence.toml").string() + " -i " + (dir / "bar").string() +
                            " -o " + (dir / "out_bar").string() + " --frames 0:3 --no-overlay --log-level warn");
  ASSERT_EQ(bar.code, 0) << bar.output;
  const auto truth = read_csv(dir / "ground_truth.csv");
  const auto estimates = read_csv(dir / "out_bar" / "estimates.csv");
  ASSERT_GE(estimates.size(), 4u);
  for (size_t row = 1; row < 4; ++row) {
    const double dx = std::stod(estimates[row][1]) - std::stod(truth[row][1]);
    const double dy = std::stod(estimates[row][2]) - std::stod(truth[row][2]);
    EXPECT_LT(std::hypot(dx, dy), 0.2) << "frame " << row - 1 << " (mm in the image plane)";
  }
  const std::string poor = "the model fits what is observed poorly";
  EXPECT_EQ(bar.output.find(poor), std::string::npos) << bar.output;
  const CliRun specks = gtrack("track -c " + (dir / "sequence.toml").string() + " -i " +
                               (dir / "specks").string() + " -o " + (dir / "out_specks").string() +
                               " --no-overlay --log-level warn");
  ASSERT_EQ(specks.code, 0) << specks.output;
  EXPECT_NE(specks.output.find("frames 0 to 9: " + poor), std::string::npos) << specks.output;
  const CliRun clean = gtrack(track_of(dir) + " -o " + (dir / "out_clean").string() + " --no-overlay --log-level warn");
  ASSERT_EQ(clean.code, 0) << clean.output;
  EXPECT_EQ(clean.output.find(poor), std::string::npos) << clean.output;
}

// gtrack segment: what the bounds take in whole frames, at full resolution.
// On a synthetic frame, the gripper's visible part (the truth's `visible`
// share of its outline); bounds of another colour, nothing. Masks and
// previews are written per frame; the percentiles of the bounds' channels
// are printed.
TEST(Cli, SegmentShowsWhatTheBoundsTakeInWholeFrames) {
  const fs::path dir = fs::temp_directory_path() / "gtrack_cli_test" / "segment";
  fs::remove_all(dir);
  ASSERT_EQ(gtrack("synth --frames 2 --seed 3 --out " + dir.string()).code, 0);
  const CliRun r = gtrack("segment -c " + (dir / "sequence.toml").string() + " -i " + (dir / "frames").string() +
                          " -o " + (dir / "seg").string());
  ASSERT_EQ(r.code, 0) << r.output;
  for (const char* name : {"masks/000000.png", "masks/000001.png", "preview/000000.png", "preview/000001.png"}) {
    EXPECT_TRUE(fs::exists(dir / "seg" / name)) << name;
  }
  const cv::Mat mask = cv::imread((dir / "seg" / "masks" / "000000.png").string(), cv::IMREAD_UNCHANGED);
  ASSERT_EQ(mask.type(), CV_8UC1);
  EXPECT_EQ(mask.cols, 1024);
  const std::string said = "frame 0: " + std::to_string(cv::countNonZero(mask)) + " pixels within the bounds";
  EXPECT_NE(r.output.find(said), std::string::npos) << said << " in " << r.output;
  const size_t at = r.output.find("the gripper face-on at the working distance covers about ");
  ASSERT_NE(at, std::string::npos) << r.output;
  const double face_on = std::stod(r.output.substr(at + 57));
  EXPECT_GT(cv::countNonZero(mask), 0.3 * face_on);
  EXPECT_LT(cv::countNonZero(mask), 1.5 * face_on);
  EXPECT_NE(r.output.find("saturation:  p1"), std::string::npos) << r.output;
  // Again into the same folder with other frames: the earlier run's images
  // go (a file of the user's stays), so that the folder is this run's.
  std::ofstream(dir / "seg" / "masks" / "notes.txt") << "kept\n";
  const CliRun again = gtrack("segment -c " + (dir / "sequence.toml").string() + " -i " + (dir / "frames").string() +
                              " -o " + (dir / "seg").string() + " --frames 1:2");
  ASSERT_EQ(again.code, 0) << again.output;
  EXPECT_NE(again.output.find("holds an earlier run's masks and previews: its 4 images are replaced"),
            std::string::npos)
      << again.output;
  for (const char* sub : {"masks", "preview"}) {
    EXPECT_FALSE(fs::exists(dir / "seg" / sub / "000000.png")) << sub;
    EXPECT_TRUE(fs::exists(dir / "seg" / sub / "000001.png")) << sub;
  }
  EXPECT_TRUE(fs::exists(dir / "seg" / "masks" / "notes.txt"));
  std::ofstream(dir / "blue.toml") << read_file(dir / "sequence.toml") + "\n[observation]\nhue_min = 100\nhue_max = 130\n";
  const CliRun blue = gtrack("segment -c " + (dir / "blue.toml").string() + " -i " + (dir / "frames").string() +
                             " -o " + (dir / "seg_blue" / "nested").string() + "/ --frames 0");
  ASSERT_EQ(blue.code, 0) << blue.output;  // a folder made with its parents, given with a trailing slash
  EXPECT_TRUE(fs::exists(dir / "seg_blue" / "nested" / "masks" / "000000.png"));
  EXPECT_NE(blue.output.find("frame 0: 0 pixels within the bounds"), std::string::npos) << blue.output;
  EXPECT_EQ(blue.output.find("frame 1:"), std::string::npos) << blue.output;
  std::ofstream(dir / "a_file") << "x";
  const CliRun file = gtrack("segment -c " + (dir / "sequence.toml").string() + " -i " + (dir / "frames").string() +
                             " -o " + (dir / "a_file").string());
  EXPECT_EQ(file.code, 1) << file.output;
  EXPECT_NE(file.output.find("a_file: is a file; expected a folder (--out)"), std::string::npos) << file.output;
}

// Every shipped config loads, passes the engine's checks and makes a frame
// of the preset drawn for it.
TEST(Cli, EveryShippedConfigMakesASequenceOfItsPreset) {
  const fs::path dir = fs::temp_directory_path() / "gtrack_cli_test" / "shipped_configs";
  fs::remove_all(dir);
  const std::map<std::string, std::string> preset_of = {
      {"microscope_hydrogel.toml", "microscope"},          {"microscope_hydrogel_brightfield.toml", "brightfield"},
      {"microscope_metallic_six.toml", "metallic_six"},    {"microscope_metallic_two.toml", "metallic_two"},
      {"ultrasound_hydrogel.toml", "ultrasound"},          {"microscope_custom_gripper.toml", "microscope"}};
  int seen = 0;
  for (const auto& entry : fs::directory_iterator(fs::path(GTRACK_TEST_SOURCE_DIR) / "configs")) {
    const std::string name = entry.path().filename().string();
    ASSERT_TRUE(preset_of.count(name)) << name << ": a shipped config this test does not know";
    const CliRun r = gtrack("synth --config " + entry.path().string() + " --frames 1 --out " + (dir / name).string());
    EXPECT_EQ(r.code, 0) << name << ": " << r.output;
    EXPECT_NE(r.output.find("(preset " + preset_of.at(name) + ", seed 1)"), std::string::npos) << name << ": "
                                                                                               << r.output;
    ++seen;
  }
  EXPECT_EQ(seen, static_cast<int>(preset_of.size()));
}

// A config without [stimulus]: a gripper whose fold no stimulus drives is
// tracked, its joints searched within their limits; a stimulus log or a
// default reading then has no plugin to read it, and synth, whose fold
// follows one, refuses: each one line naming what is missing.
TEST(Cli, AConfigWithoutAStimulusTracksAndSaysWhatNeedsOne) {
  const fs::path dir = fs::temp_directory_path() / "gtrack_cli_test" / "no_stimulus";
  fs::remove_all(dir);
  ASSERT_EQ(gtrack("synth --frames 3 --seed 3 --out " + dir.string()).code, 0);
  const std::string config = read_file(dir / "sequence.toml");
  const size_t from = config.find("[stimulus]\n");
  ASSERT_NE(from, std::string::npos);
  const size_t to = config.find("\n[", from + 1);
  ASSERT_NE(to, std::string::npos);
  const fs::path bare = write("no_stimulus.toml", config.substr(0, from) + config.substr(to + 1));
  const std::string frames = " -i " + (dir / "frames").string();
  CliRun r = gtrack("track -c " + bare.string() + frames + " -o " + (dir / "out").string() + " --no-overlay");
  EXPECT_EQ(r.code, 0) << r.output;
  EXPECT_NE(r.output.find("3 frames (0 lost)"), std::string::npos) << r.output;
  EXPECT_EQ(read_csv(dir / "out" / "estimates.csv").size(), 4u);
  r = gtrack("track -c " + bare.string() + frames + " -s " + (dir / "stimulus.csv").string() + " -o " +
             (dir / "out2").string());
  EXPECT_EQ(r.code, 1) << r.output;
  EXPECT_NE(r.output.find("stimulus.csv: a stimulus log, but the config has no [stimulus] table naming the plugin "
                          "that reads it"),
            std::string::npos)
      << r.output;
  const fs::path with_default = write("no_stimulus_default.toml", replaced(read_file(bare), "[tracker]\n",
                                                                           "[tracker]\ndefault_stimulus = 25.0\n"));
  r = gtrack("track -c " + with_default.string() + frames + " -o " + (dir / "out3").string());
  EXPECT_EQ(r.code, 1) << r.output;
  EXPECT_NE(r.output.find("key 'tracker.default_stimulus': a default reading, but the config has no [stimulus] "
                          "table"),
            std::string::npos)
      << r.output;
  r = gtrack("synth -c " + bare.string() + " --frames 1 -o " + (dir / "seq").string());
  EXPECT_EQ(r.code, 1) << r.output;
  EXPECT_NE(r.output.find("missing table [stimulus]: a synthetic sequence's fold follows a stimulus plugin's "
                          "readings"),
            std::string::npos)
      << r.output;
}

}  // namespace
