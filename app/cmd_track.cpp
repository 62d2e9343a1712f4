// gtrack track: the tracker over a video, an image folder, a stack, a DICOM file or a camera.
#include <atomic>
#include <cmath>
#include <csignal>
#include <cstring>
#include <cstdio>
#include <iostream>
#include <optional>
#include <thread>

#include <poll.h>
#include <unistd.h>

#include "command.hpp"
#include "gtrack/engine_config.hpp"
#include "gtrack/error.hpp"
#include "gtrack/frame_source.hpp"
#include "gtrack/results.hpp"
#include "gtrack/setup.hpp"
#include "gtrack/tracker.hpp"
#include "gtrack/two_pass.hpp"
#include "gtrack/udp_sender.hpp"

namespace po = boost::program_options;

namespace {

std::atomic<bool> g_stop{false};
std::atomic<bool> g_reader_gone{false};  // --stream: stdout's reader closed the pipe

// The first Ctrl-C (or SIGTERM, or SIGHUP when the terminal or the ssh
// session closes, unless run under `nohup`) lets the current frame finish
// and the files close; the handler then reverts to the default, so a second
// one ends the process.
// --stream: a reader that has stopped reading leaves a write blocked, and
// the run could not reach its next frame to stop. Once interrupted, the
// write gets kStreamGraceS seconds; then SIGALRM, installed without
// SA_RESTART, ends it with EINTR and the run stops as when the reader goes.
constexpr unsigned kStreamGraceS = 5;
std::atomic<bool> g_streaming{false};
std::atomic<bool> g_grace_over{false};
std::atomic<bool> g_stream_stalled{false};  // a write failed after the grace
std::atomic<bool> g_signalled{false};       // Ctrl-C, SIGTERM or SIGHUP came
std::atomic<int> g_stream_errno{0};         // --stream: a write failed otherwise (a full disk)
extern "C" void on_sigint(int) {
  g_signalled.store(true);
  g_stop.store(true);
  if (g_streaming.load()) ::alarm(kStreamGraceS);
}
extern "C" void on_alarm(int) { g_grace_over.store(true); }

void install_sigint() {
  struct sigaction alarm_action {};
  alarm_action.sa_handler = on_alarm;
  sigemptyset(&alarm_action.sa_mask);
  sigaction(SIGALRM, &alarm_action, nullptr);

  struct sigaction sa {};
  sa.sa_handler = on_sigint;
  sigemptyset(&sa.sa_mask);
  sa.sa_flags = SA_RESETHAND | SA_RESTART;  // a write to a slow --stream reader goes on
  for (int signal : {SIGINT, SIGTERM, SIGHUP}) {
    // A signal the caller ignores (`nohup`, a background job's SIGINT) stays ignored.
    struct sigaction old {};
    if (sigaction(signal, nullptr, &old) == 0 && old.sa_handler == SIG_IGN) continue;
    sigaction(signal, &sa, nullptr);
  }
}

// --stream: the estimates' lines go to what stdout was; stdout itself (fd
// 1) is pointed at stderr before any plugin is loaded, so that what a
// plugin prints (or a library it uses) never reaches the controller's pipe.
std::FILE* g_stream_out = stdout;

void set_stream_apart() {
  std::fflush(stdout);
  const int lines = ::dup(STDOUT_FILENO);
  std::FILE* out = lines >= 0 ? ::fdopen(lines, "w") : nullptr;
  if (!out || ::dup2(STDERR_FILENO, STDOUT_FILENO) < 0) {
    const int error = errno;
    if (out) std::fclose(out);
    throw gtrack::Error(std::string("--stream: cannot set stdout apart for the estimates (") + std::strerror(error) +
                       ")");
  }
  g_stream_out = out;
}

int run_track(const gtrack::cli::CommonOptions& common, const po::variables_map& vm) {
  if (vm.count("stream")) {
    if (common.stdout_closed) {
      throw gtrack::cli::UsageError("--stream: stdout is closed; expected it open to the estimates' reader (a pipe, a "
                                    "file)");
    }
    set_stream_apart();
  }
  gtrack::SetupOptions so;
  so.plugin_paths = common.plugin_paths;
  gtrack::Setup setup = gtrack::load_setup(vm["config"].as<std::string>(), so);
  gtrack::EngineConfig config = gtrack::engine_config(setup);
  gtrack::check_root_keys(setup);
  gtrack::cli::backend_option(vm, config.render.backend);

  gtrack::TrackOptions opt;
  opt.input = vm["input"].as<std::string>();
  if (vm.count("stimulus")) opt.stimulus_csv = vm["stimulus"].as<std::string>();
  if (vm.count("stimulus-column")) {
    if (!opt.stimulus_csv) throw gtrack::cli::UsageError("--stimulus-column needs --stimulus");
    opt.stimulus_column = vm["stimulus-column"].as<std::string>();
    if (opt.stimulus_column.empty()) throw gtrack::cli::UsageError("--stimulus-column: expected a column's name");
  }
  if (vm.count("stimulus-offset")) {
    if (!opt.stimulus_csv) throw gtrack::cli::UsageError("--stimulus-offset needs --stimulus");
    if (vm.count("follow-stimulus")) {
      throw gtrack::cli::UsageError("--stimulus-offset cannot be combined with --follow-stimulus (each frame takes "
                                    "the followed log's last row, whatever its time)");
    }
    opt.stimulus_offset_s = vm["stimulus-offset"].as<double>();
    if (!std::isfinite(opt.stimulus_offset_s)) {
      throw gtrack::cli::UsageError("--stimulus-offset: expected a finite number of seconds");
    }
  }
  opt.out_dir = gtrack::cli::out_folder(vm);
  opt.range = gtrack::cli::frame_range_option(vm);
  opt.save_masks = vm.count("save-masks") > 0;
  if (vm.count("no-overlay")) opt.overlay = false;
  opt.resume = vm.count("resume") > 0;
  opt.durable = vm.count("durable") > 0;
  opt.follow_stimulus = vm.count("follow-stimulus") > 0;
  opt.newest = vm.count("newest") > 0;
  if (vm.count("restart-from")) opt.restart_from = vm["restart-from"].as<std::string>();
  if (vm.count("score-truth")) opt.score_truth = vm["score-truth"].as<std::string>();
  if (vm.count("follow-input")) {
    opt.follow_input_s = vm["follow-input"].as<double>();
    if (!(opt.follow_input_s > 0)) throw gtrack::cli::UsageError("--follow-input: expected seconds > 0");
  }
  // --stream: each estimate, as its estimates.jsonl line, on stdout as soon
  // as it is made (for a controller reading a pipe); the rest goes to stderr.
  // --stream-udp: the same line in a UDP datagram (for a controller in
  // another process or on another machine), sent first: it never waits,
  // where a slow pipe's reader can hold the write.
  const bool stream = vm.count("stream") > 0;
  std::optional<gtrack::UdpSender> udp;
  if (vm.count("stream-udp")) udp.emplace(vm["stream-udp"].as<std::string>(), "--stream-udp");
  if (stream) {
    // A reader that goes away (the controller stopped) ends the run like
    // Ctrl-C does, files closed, instead of SIGPIPE killing the process.
    std::signal(SIGPIPE, SIG_IGN);
    g_streaming = true;
  }
  if (stream || udp) {
    opt.on_frame = [stream, &udp](const gtrack::Estimate& e) {
      const std::string line = gtrack::estimate_json(e) + "\n";
      if (udp) udp->send(line);
      if (!stream || g_reader_gone || g_stream_stalled) return;
      if (std::fputs(line.c_str(), g_stream_out) < 0 || std::fflush(g_stream_out) != 0) {
        const int error = errno;
        if (g_grace_over && error != EPIPE) {
          g_stream_stalled = true;
        } else if (error != EPIPE) {
          g_stream_errno = error;
        } else if (!g_signalled) {
          // (Ctrl-C on `gtrack ... --stream | controller` ends the reader
          // too: that is an interrupt.)
          g_reader_gone = true;
        }
        g_stop = true;
      }
    };
  }
  // --two-pass: the estimates are kept as they are made, for the backward
  // pass that follows the forward one.
  const bool two_pass = vm.count("two-pass") > 0;
  std::vector<gtrack::Estimate> forward;
  std::optional<gtrack::OutputLock> held;
  if (two_pass) {
    if (opt.input.rfind("camera:", 0) == 0) {
      throw gtrack::cli::UsageError("--two-pass needs a recording, not a live camera");
    }
    if (opt.follow_input_s > 0 || opt.follow_stimulus || opt.newest) {
      throw gtrack::cli::UsageError("--two-pass cannot be combined with --follow-input, --follow-stimulus or --newest");
    }
    if (opt.restart_from) throw gtrack::cli::UsageError("--two-pass cannot be combined with --restart-from");
    opt.feed_untracked_readings = false;  // the backward pass replays the tracked frames' readings only
    // The folder's lock, taken again at the forward run's first estimate
    // (within track_sequence's own), is held through the backward pass.
    opt.on_frame = [&forward, &held, &out_dir = opt.out_dir, streamed = opt.on_frame](const gtrack::Estimate& e) {
      if (!held) held.emplace(out_dir);
      if (streamed) streamed(e);
      forward.push_back(e);
    };
  }
  opt.cancel = &g_stop;
  install_sigint();
  // --stream on a followed folder: a reader that goes away while the folder
  // is waited on, so that no line is written, is noticed as the pipe's error.
  std::jthread reader_watch;
  if (stream && opt.follow_input_s > 0) {
    reader_watch = std::jthread([](std::stop_token stop) {
      while (!stop.stop_requested() && !g_stop) {
        pollfd out{::fileno(g_stream_out), 0, 0};
        if (::poll(&out, 1, 100) > 0 && (out.revents & (POLLERR | POLLHUP))) {
          g_reader_gone = true;
          g_stop = true;
        }
      }
    });
  }

  const gtrack::TrackSummary s = gtrack::track_sequence(setup, config, opt);
  ::alarm(0);
  const char* next = opt.follow_stimulus ? " (a run that follows its stimulus log cannot be resumed)"
                                         : " (the same command with --resume continues)";
  // Why the stream stopped the run ("" when it did not).
  std::string stream_stop;
  if (g_stream_errno != 0) {
    stream_stop = std::string("--stream: writing to stdout failed (") + std::strerror(g_stream_errno) + ")";
  } else if (g_stream_stalled) {
    stream_stop = "interrupted, and the reader of --stream took no line for " + std::to_string(kStreamGraceS) + " s";
  } else if (g_reader_gone) {
    stream_stop = "stdout was closed by its reader";
  }
  if (s.cancelled && !stream_stop.empty()) {
    std::cerr << "gtrack track: " << stream_stop << "; stopped after " << s.frames
              << (s.frames == 1 ? " frame" : " frames") << ", kept in " << opt.out_dir.string() << next << "\n";
  } else if (s.cancelled) {
    std::cerr << "gtrack track: interrupted; " << s.frames << (s.frames == 1 ? " finished frame" : " finished frames")
              << " kept in " << opt.out_dir.string()
              << next << "\n";
  }
  // No frame to track (said as a warning): the folder was left as it was.
  if (s.frames == 0 && s.renderer.empty() && !s.cancelled) return 0;
  std::FILE* report = stream ? stderr : stdout;
  char cost[32] = "n/a (no frame tracked)";
  if (std::isfinite(s.mean_cost)) std::snprintf(cost, sizeof cost, "%.4f", s.mean_cost);
  std::fprintf(report, "%d frames (%d lost), mean cost %s, %.1f ms/frame (segment %.1f, pso %.1f, io %.1f), %s renderer -> %s\n",
              s.frames, s.lost_frames, cost, s.mean_ms, s.mean_times.segment_ms, s.mean_times.pso_ms,
              s.mean_times.io_ms, s.renderer.c_str(), opt.out_dir.string().c_str());
  if (s.skipped_frames > 0) {
    std::fprintf(report, "%d frames left out for newer ones (--newest)\n", s.skipped_frames);
  }
  if (udp) {
    std::fprintf(report, "--stream-udp: %lld datagram%s handed to the network for %s, %lld dropped\n", udp->sent(),
                 udp->sent() == 1 ? "" : "s", udp->peer().c_str(), udp->dropped());
  }
  if (s.resumed_after >= 0) {
    std::fprintf(report, "resumed after frame %d: %d frames were already done\n", s.resumed_after, s.frames_before);
  }
  if (s.cancelled && g_stream_errno != 0) return 1;
  if (s.cancelled) return g_reader_gone ? 141 : 130;  // 141: as a process ended by SIGPIPE
  if (two_pass) {
    // A resumed forward run: the frames of its earlier part are read back
    // from its estimates (the backward pass needs the whole run).
    if (opt.resume) forward = gtrack::read_estimates(opt.out_dir, setup.model().fingers());
    const gtrack::TwoPassSummary t = gtrack::two_pass(setup, config, opt, forward);
    if (t.cancelled) {
      // The summary says the run was interrupted, as the exit status does.
      gtrack::TrackSummary interrupted = s;
      interrupted.cancelled = true;
      gtrack::write_summary(opt.out_dir / "summary.json", interrupted);
      std::cerr << "gtrack track: interrupted after the forward run (kept in " << opt.out_dir.string()
                << "); the backward track's finished frames are in " << (opt.out_dir / "backward").string()
                << ", no two-pass table was written (the same command with --resume makes it, the forward run "
                   "kept)\n";
      return 130;
    }
    std::fprintf(report, "two-pass: %d frames, %d taken from the backward pass (%d lost there), %s, %.1f s -> %s\n",
                 t.frames, t.from_backward, t.backward_lost, gtrack::smoothing_report(t).c_str(), t.wall_s,
                 (opt.out_dir / "two_pass" / "estimates.csv").string().c_str());
  }
  return 0;
}

}  // namespace

GTRACK_COMMAND(
    "track", "track a gripper in a video, an image folder, a TIFF stack, a DICOM file or a live camera",
    [](po::options_description& d) {
      d.add_options()("config,c", po::value<std::string>()->required(), "TOML config naming sensor, gripper, stimulus")(
          "input,i", po::value<std::string>()->required(), "video file, folder of images, TIFF stack, DICOM file (a cine loop), or camera:N")(
          "stimulus,s", po::value<std::string>(), "stimulus log CSV (frame,value or time_s,value)")(
          "stimulus-column", po::value<std::string>(),
          "of a stimulus log with several named columns (time_s,B_mT,T_C), the one that holds the readings")(
          "stimulus-offset", po::value<double>(),
          "SECONDS: a time_s log on another clock: its time at the recording's first frame (a logger started "
          "that long before the camera; a log in Unix time: the first frame's), subtracted from its times")(
          "out,o", po::value<std::string>()->required(), "output folder")(
          "backend", po::value<std::string>(), "auto, gl or cpu (default: [render] backend)")(
          "every", po::value<int>()->default_value(1), "track every K-th frame")(
          "frames", po::value<std::string>(),
          "A:B, frames A (inclusive) to B (exclusive); A: and :B open-ended; A alone: that frame")(
          "save-masks", "write each observation O to OUT/masks/NNNNNN.png")(
          "no-overlay", "do not write the overlay video")(
          "two-pass",
          "after the run, track the recording again backwards and write OUT/two_pass/estimates.csv: per frame, "
          "the forward or the backward estimate, chosen over the sequence by their costs and continuity, "
          "orientations smoothed over neighbouring frames ([tracker] two_pass_smoothing)")(
          "resume", "continue the run whose files are in OUT after its last finished frame")(
          "durable", "put each frame's estimates and the tracker state on the disk (fsync) before the next frame: "
                     "a power loss then loses no finished frame")(
          "stream", "also print each estimate (its estimates.jsonl line) on stdout as soon as it is made")(
          "stream-udp", po::value<std::string>(),
          "HOST:PORT: also send each estimate (its estimates.jsonl line) as a UDP datagram as soon as it is made, "
          "to a controller in another process or on another machine")(
          "follow-stimulus", "the stimulus log is still being written: each frame takes its latest row")(
          "newest",
          "a live source (camera:N, --follow-input) faster than the tracker: track the newest frame each time, "
          "leaving out those that came meanwhile, instead of tracking every frame further and further behind")(
          "follow-input", po::value<double>(),
          "SECONDS: the input folder is still being written: track new images as they arrive, end after SECONDS "
          "without one")(
          "restart-from", po::value<std::string>(),
          "pose table (e.g. ground_truth.csv): before each frame, set the track to its row for the previous frame")(
          "score-truth", po::value<std::string>(),
          "pose table (e.g. ground_truth.csv): score its row for each frame as the estimate was scored, and write "
          "it beside the estimate in estimates.jsonl (\"reference\")");
    },
    run_track)
