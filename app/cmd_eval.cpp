// gtrack eval: estimates against ground truth (paper Section 5.1 metrics).
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <map>
#include <numeric>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "command.hpp"
#include "gtrack/error.hpp"
#include "gtrack/evaluation.hpp"
#include "gtrack/results.hpp"
#include "gtrack/text_file.hpp"
#include "gtrack/tracker.hpp"
#include "gtrack/log.hpp"
#include "gtrack/sensor.hpp"
#include "gtrack/setup.hpp"

namespace po = boost::program_options;
namespace fs = std::filesystem;

namespace {

void print_row(const char* name, const gtrack::ErrorStats& s, const char* unit) {
  std::cout << "  " << std::left << std::setw(22) << name << std::right << std::fixed << std::setprecision(2)
            << std::setw(9) << s.mean << " +- " << std::setw(7) << s.std << "  median " << std::setw(8) << s.median
            << "  max " << std::setw(8) << s.max << " " << unit << "\n";
}

// What estimates.jsonl says of a frame: the occlusion allowance, the tilt
// margin, and, from 'gtrack track --score-truth', the estimate's and the
// truth's costs and how much of the truth's silhouette fell outside O.
struct FrameScores {
  double allowance = 0;
  std::optional<double> tilt_margin, cost, reference_cost, reference_outside;
};

// Per frame, from the estimates.jsonl beside the estimates (empty when there
// is none).
std::map<int, FrameScores> frame_scores(const fs::path& estimates_csv) {
  std::map<int, FrameScores> out;
  const fs::path file = estimates_csv.parent_path() / "estimates.jsonl";
  std::ifstream in(file);
  std::string line;
  for (int n = 1; gtrack::read_bounded_line(in, line, 1 << 16, file.string(), n, "estimates.jsonl's JSON lines"); ++n) {
    const auto field = [&](const std::string& text, const std::string& key) -> std::optional<double> {
      const auto value = gtrack::json_field(text, key);
      if (!value) return std::nullopt;
      const std::string number(*value);
      char* end = nullptr;
      const double v = std::strtod(number.c_str(), &end);
      return end == number.c_str() ? std::nullopt : std::optional<double>(v);
    };
    const auto ref_at = line.find("\"reference\":{");
    const std::string own = line.substr(0, ref_at);
    const auto frame = field(own, "frame"), allowance = field(own, "outside_allowance");
    if (!frame || !allowance) continue;
    FrameScores& s = out[static_cast<int>(*frame)];
    s.allowance = *allowance;
    s.cost = field(own, "cost");
    s.tilt_margin = field(own, "tilt_margin");
    if (ref_at != std::string::npos) {
      const std::string ref = line.substr(ref_at, line.find('}', ref_at) - ref_at);
      s.reference_cost = field(ref, "cost");
      const auto rendered = field(ref, "rendered_pixels"), overlap = field(ref, "overlap_pixels");
      // The rim's pixels are never taken as hidden: only the rest of P\O
      // is measured against the allowance.
      const auto rim = field(ref, "rim_pixels");
      if (rendered && overlap) s.reference_outside = *rendered - *overlap - rim.value_or(0.0);
    }
  }
  return out;
}

// A truth that scores lower than the estimate by more than this is one the
// search missed.
constexpr double kLowerBy = 1e-4;

// --breakdown: the in-view frames with an estimate, grouped by how much of
// the gripper the truth says was hidden, and the unoccluded ones by whether
// the tracker still made an occlusion allowance (where the error of a track
// comes from; docs/RESULTS.md, "Where the error comes from").
void print_breakdown(const gtrack::Evaluation& ev, const gtrack::PoseTable& truth, const fs::path& estimates_csv) {
  std::map<int, const gtrack::PoseRow*> rows;
  for (const auto& r : truth.rows) rows[r.frame] = &r;
  const auto extra = [](const gtrack::PoseRow& r, const char* key) {
    const auto it = r.extra.find(key);
    return it == r.extra.end() ? std::optional<double>() : std::optional<double>(it->second);
  };
  const auto scores = frame_scores(estimates_csv);
  std::map<std::string, gtrack::ErrorSet> groups;
  const std::vector<std::string> order = {"unoccluded", "< 40 % hidden", ">= 40 % hidden", "partly out of view",
                                          "unoccluded, no allowance", "unoccluded, an allowance left",
                                          fmt::format("tilt margin < {}", gtrack::kNarrowTiltMargin),
                                          fmt::format("tilt margin >= {}", gtrack::kNarrowTiltMargin)};
  // By kind of frame: a gripper partly out of view coming in or going out
  // (its share in view larger or smaller than at the frame before), and one
  // wholly in view within kAfterReturn frames of a return into view, where
  // a track started from what showed first is still settling.
  constexpr int kAfterReturn = 20;
  const std::vector<std::string> kind = {"partly out of view, coming in", "partly out of view, going out",
                                         fmt::format("in view, <= {} frames after a return", kAfterReturn)};
  std::map<std::string, int> other_branch;  // frames on the other branch of the tilt's sign, per group
  // With the truth scored (--score-truth): is the search or the cost short?
  const std::vector<std::string> why = {"truth scores lower", "truth spills over allowance", "truth scores no lower"};
  bool have_occlusion = false;
  std::optional<int> last_out;  // the last frame out of view
  for (std::size_t i = 0; i < ev.per_frame.size(); ++i) {
    const gtrack::FrameEvaluation& f = ev.per_frame[i];
    if (f.out_of_view) last_out = f.frame;
    if (f.out_of_view || !f.has_estimate || f.lost) continue;
    const auto r = rows.find(f.frame);
    if (r == rows.end()) continue;
    const auto occluded = extra(*r->second, "occluded");
    if (!occluded) continue;
    have_occlusion = true;
    std::string g = *occluded < 0.01 ? order[0] : *occluded < 0.4 ? order[1] : order[2];
    if (f.in_view < 0.99) g = order[3];
    groups[g].add(f.errors);
    if (g == order[3]) {
      // At the first frame, against the next.
      const bool coming_in = i > 0 ? ev.per_frame[i - 1].in_view < f.in_view
                                   : i + 1 < ev.per_frame.size() && ev.per_frame[i + 1].in_view > f.in_view;
      groups[coming_in ? kind[0] : kind[1]].add(f.errors);
    } else if (last_out && f.frame - *last_out <= kAfterReturn) {
      groups[kind[2]].add(f.errors);
    }
    const auto s = scores.find(f.frame);
    if (g == order[0] && s != scores.end()) groups[s->second.allowance > 0 ? order[5] : order[4]].add(f.errors);
    if (s != scores.end() && s->second.tilt_margin) {
      const std::string& t = *s->second.tilt_margin < gtrack::kNarrowTiltMargin ? order[6] : order[7];
      groups[t].add(f.errors);
      other_branch[t] += f.errors.tilt_branch ? 1 : 0;
    }
    if (s != scores.end() && s->second.cost && s->second.reference_cost) {
      const FrameScores& fs = s->second;
      const std::string& w = *fs.reference_cost < *fs.cost - kLowerBy ? why[0]
                             : fs.allowance > 0 && fs.reference_outside && *fs.reference_outside > fs.allowance
                                 ? why[1]
                                 : why[2];
      groups[w].add(f.errors);
    }
  }
  if (!have_occlusion) {
    const bool column = !truth.rows.empty() && truth.rows.front().extra.count("occluded");
    std::cout << (column ? "  breakdown: no frame in view has a usable estimate\n"
                         : "  breakdown: the truth has no 'occluded' column (gtrack synth writes one)\n");
    return;
  }
  std::cout << "  breakdown (in-view frames with an estimate; the allowance and tilt margin rows need "
               "estimates.jsonl, the last three 'gtrack track --score-truth'):\n";
  for (auto& [name, e] : groups) e.finish();
  // The three --score-truth groups split the same frames: each one's share of
  // their summed in-plane error.
  const auto inplane_sum = [&](const std::string& name) {
    const auto it = groups.find(name);
    return it == groups.end() ? 0.0 : it->second.position_inplane_um.mean * it->second.position_inplane_um.count;
  };
  double inplane_total = 0;
  for (const auto& name : why) inplane_total += inplane_sum(name);
  // The occlusion groups split every frame: each kind's share of their
  // summed orientation error.
  const auto orientation_sum = [&](const std::string& name) {
    const auto it = groups.find(name);
    return it == groups.end() ? 0.0 : it->second.orientation_deg.mean * it->second.orientation_deg.count;
  };
  const auto occlusion_end = order.begin() + 4;  // unoccluded .. partly out of view
  double orientation_total = 0;
  for (auto g = order.begin(); g != occlusion_end; ++g) orientation_total += orientation_sum(*g);
  std::vector<std::string> all(order.begin(), occlusion_end);
  all.insert(all.end(), kind.begin(), kind.end());
  all.insert(all.end(), occlusion_end, order.end());
  all.insert(all.end(), why.begin(), why.end());
  for (const auto& name : all) {
    auto it = groups.find(name);
    if (it == groups.end()) continue;
    const gtrack::ErrorSet& e = it->second;
    std::cout << "    " << std::left << std::setw(38) << name << std::right << std::setw(5)
              << e.position_inplane_um.count << " frames  in-plane " << std::setprecision(1) << std::setw(7)
              << e.position_inplane_um.mean << " um (median " << e.position_inplane_um.median << ")  orientation "
              << std::setw(5) << e.orientation_deg.mean << " deg (median " << e.orientation_deg.median
              << ")  joints " << std::setprecision(2) << e.joint_deg.mean << " deg";
    if (const auto b = other_branch.find(name); b != other_branch.end()) {
      std::cout << "  (" << b->second << " on the other branch of the tilt's sign)";
    }
    const bool by_kind = std::find(order.begin(), occlusion_end, name) != occlusion_end ||
                         std::find(kind.begin(), kind.end(), name) != kind.end();
    if (by_kind && orientation_total > 0) {
      std::cout << "  (" << std::setprecision(0) << 100 * orientation_sum(name) / orientation_total
                << " % of the summed orientation error)";
    }
    if (std::find(why.begin(), why.end(), name) != why.end() && inplane_total > 0) {
      std::cout << "  (" << std::setprecision(0) << 100 * inplane_sum(name) / inplane_total
                << " % of the summed in-plane error)";
    }
    std::cout << "\n";
  }
}

// The run that wrote the estimates kept its config beside them (a two-pass
// table: in the run's folder's two_pass/ or backward/): a sensor posed or
// sized otherwise there splits the errors along other axes than the run's,
// and another gripper model measures its endpoints on another shape.
void warn_if_the_run_imaged_otherwise(const fs::path& estimates_file, const fs::path& config,
                                      const gtrack::Setup& setup, const gtrack::SetupOptions& so) {
  std::error_code ec;
  fs::path run_config = estimates_file.parent_path() / "run_config.toml";
  if (!fs::is_regular_file(run_config, ec)) run_config = estimates_file.parent_path().parent_path() / "run_config.toml";
  if (!fs::is_regular_file(run_config, ec) || fs::equivalent(run_config, config, ec)) return;
  std::optional<gtrack::Projection> ran;
  std::optional<gtrack::Setup> run;
  {
    // What loading it says was said when it ran.
    struct Quiet {
      spdlog::level::level_enum level = gtrack::logger().level();
      Quiet() { gtrack::logger().set_level(spdlog::level::off); }
      ~Quiet() { gtrack::logger().set_level(level); }
    } quiet;
    try {
      run = gtrack::load_setup(run_config, so);
      ran = run->sensor->projection();
    } catch (const std::exception&) {
      return;  // a run config this machine cannot load (its plugins elsewhere) is no evidence either way
    }
  }
  const gtrack::Projection here = setup.sensor->projection();
  if (!ran->world_to_image.isApprox(here.world_to_image, 1e-9) || ran->size.width != here.size.width ||
      ran->size.height != here.size.height) {
    gtrack::logger().warn("{}: its [sensor] images the world otherwise than {}'s (a sensor posed or sized "
                          "otherwise): the errors are measured along {}'s axes, and the in-view shares from it",
                          run_config.string(), config.string(), config.string());
  }
  // The same shape: the same link endpoints at a pose with every joint
  // folded by 30 degrees.
  const gtrack::ArticulatedModel &a = run->model(), &b = setup.model();
  bool same = a.dims() == b.dims();
  if (same) {
    Eigen::VectorXd h = Eigen::VectorXd::Zero(a.dims());
    h[2] = 100;
    h.tail(a.fingers()).setConstant(30);
    const auto ea = a.link_endpoints(h), eb = b.link_endpoints(h);
    same = ea.size() == eb.size();
    for (size_t i = 0; same && i < ea.size(); ++i) same = (ea[i] - eb[i]).norm() < 1e-6;
  }
  if (!same) {
    gtrack::logger().warn("{}: its gripper model ('{}') differs from {}'s ('{}'): the errors are measured on {}'s",
                          run_config.string(), a.geometry().name, config.string(), b.geometry().name, config.string());
  }
}

int run_eval(const gtrack::cli::CommonOptions& common, const po::variables_map& vm) {
  const fs::path truth_file = vm["truth"].as<std::string>();
  const fs::path estimates_file = vm["estimates"].as<std::string>();
  for (const fs::path& f : {truth_file, estimates_file}) {
    if (fs::is_directory(f)) {
      throw gtrack::InputError(f.string() + ": is a folder; expected a pose table (" +
                               (f == truth_file ? "ground_truth.csv" : "estimates.csv") + ")");
    }
    if (!fs::exists(f)) throw gtrack::InputError(f.string() + ": no such file");  // a pipe is read
  }
  // Where the results go is checked before anything is computed.
  gtrack::cli::NamedPaths outputs;
  for (const char* key : {"json", "per-frame"}) {
    if (!vm.count(key)) continue;
    gtrack::cli::check_output_folder(vm[key].as<std::string>(), key);
    outputs.emplace_back(std::string("--") + key, vm[key].as<std::string>());
  }
  // The model comes from a config: the one given, or the sequence.toml that
  // 'gtrack synth' wrote next to its ground truth.
  fs::path config = vm.count("config") ? fs::path(vm["config"].as<std::string>())
                                       : truth_file.parent_path() / "sequence.toml";
  if (!fs::exists(config)) {
    if (vm.count("config")) throw gtrack::InputError(config.string() + ": no such file (--config)");
    throw gtrack::cli::UsageError("no --config given and no " + config.string() +
                                  " next to the truth; the config names the gripper model");
  }
  gtrack::cli::check_outputs_apart(outputs,
                                   {{"--truth", truth_file}, {"--estimates", estimates_file}, {"config", config}});
  gtrack::SetupOptions so;
  so.plugin_paths = common.plugin_paths;
  so.with_stimulus = false;
  gtrack::Setup setup = gtrack::load_setup(config, so);
  warn_if_the_run_imaged_otherwise(estimates_file, config, setup, so);
  for (const auto& k : setup.root.keys()) setup.root.mark_used(k);  // engine tables are not used here

  gtrack::EvalOptions opt;
  opt.out_of_view_below = vm["out-of-view-below"].as<double>();
  opt.off_track_endpoint_um = vm["off-track-um"].as<double>();
  // An ultrasound slice does not show where within its slab the gripper
  // lies: off track is judged within the imaging plane; so it is for a
  // camera with --off-track-in-plane.
  const bool slab = gtrack::cli::images_a_slab(*setup.sensor);
  opt.off_track_in_plane = slab || vm.count("off-track-in-plane") > 0;
  if (!(opt.out_of_view_below >= 0 && opt.out_of_view_below < 1)) {
    throw gtrack::cli::UsageError("--out-of-view-below must be a share in [0, 1)");
  }
  if (!(opt.off_track_endpoint_um > 0 && std::isfinite(opt.off_track_endpoint_um))) {
    throw gtrack::cli::UsageError("--off-track-um must be a positive number");
  }
  auto truth = gtrack::read_truth_table(truth_file);
  auto estimates = gtrack::read_pose_table(estimates_file);
  // --frames and --every as the run had them: only the frames it tracked are judged.
  const gtrack::FrameRange range = gtrack::cli::frame_range_option(vm);
  const bool had_rows = !truth.rows.empty();
  // The truth's last frame before --frames cuts it: a hint below names the
  // range the run took within the whole sequence.
  int truth_last = 0;
  for (const auto& r : truth.rows) truth_last = std::max(truth_last, r.frame);
  for (auto* t : {&truth, &estimates}) {
    std::erase_if(t->rows, [&](const auto& r) { return !range.contains(r.frame); });
    // Frame order, whatever the files' (a table put together by hand): the
    // ranges said below and the recoveries after a return follow it.
    std::stable_sort(t->rows.begin(), t->rows.end(), [](const auto& a, const auto& b) { return a.frame < b.frame; });
  }
  if (had_rows && truth.rows.empty()) {
    throw gtrack::cli::UsageError("--frames/--every select none of the frames of " + truth_file.string());
  }
  for (const auto* t : {&truth, &estimates}) {
    if (t->rows.empty()) {
      throw gtrack::InputError((t == &truth ? truth_file : estimates_file).string() +
                               ": a header and no rows; there is nothing to evaluate");
    }
  }
  for (const auto* t : {&truth, &estimates}) {
    if (t->fingers != setup.model().fingers()) {
      throw gtrack::InputError((t == &truth ? truth_file : estimates_file).string() + ":1: " +
                               std::to_string(t->fingers) + " joint columns, the model in " + config.string() +
                               " has " + std::to_string(setup.model().fingers()) + " fingers");
    }
  }
  // The truth given as the estimates would evaluate to no error at all.
  const auto& ex = estimates.extra_columns;
  if (std::find(ex.begin(), ex.end(), "in_view") != ex.end() && std::find(ex.begin(), ex.end(), "occluded") != ex.end()) {
    throw gtrack::InputError(estimates_file.string() +
                             ":1: has the ground truth's 'in_view' and 'occluded' columns; expected estimates (is "
                             "the truth given as --estimates?)");
  }
  // Estimates of frames the truth does not have are not evaluated: said once.
  std::set<int> truth_frames;
  for (const auto& r : truth.rows) truth_frames.insert(r.frame);
  std::vector<int> unmatched;
  for (const auto& r : estimates.rows) {
    if (!truth_frames.count(r.frame)) unmatched.push_back(r.frame);
  }
  if (!truth_frames.empty() && !unmatched.empty() && unmatched.size() == estimates.rows.size()) {
    // Not one row in common: another sequence's estimates, or renumbered.
    throw gtrack::InputError(estimates_file.string() + ": no row is for a frame of " + truth_file.string() +
                             " (its frames " + std::to_string(estimates.rows.front().frame) + " to " +
                             std::to_string(estimates.rows.back().frame) + ", the truth's " +
                             std::to_string(*truth_frames.begin()) + " to " + std::to_string(*truth_frames.rbegin()) +
                             "); expected the estimates of this sequence");
  }
  if (!unmatched.empty()) {
    gtrack::logger().warn("{}: {} rows are for frames {} has no row for (the first: frame {}); they are not evaluated",
                          estimates_file.string(), unmatched.size(), truth_file.string(), unmatched.front());
  }
  const auto ev = gtrack::evaluate(setup.model(), truth, estimates, opt, setup.sensor.get());
  // A run with --frames or --every leaves the frames it did not take
  // without a row: they count as lost, which is said with the remedy.
  if (ev.missing_frames > 0 && !estimates.rows.empty()) {
    int stride = 0;
    for (std::size_t i = 1; i < estimates.rows.size(); ++i) {
      stride = std::gcd(stride, std::abs(estimates.rows[i].frame - estimates.rows[i - 1].frame));
    }
    const int first = estimates.rows.front().frame, last = estimates.rows.back().frame;
    const bool ends_early = last + std::max(stride, 1) <= truth_last;
    if (stride > 1 || first > truth.rows.front().frame || ends_early) {
      std::string options = "--frames " + std::to_string(first) + ":" + (ends_early ? std::to_string(last + 1) : "");
      if (stride > 1) options += " --every " + std::to_string(stride);
      gtrack::logger().warn("{} frames of {} have no estimate and count as lost; the estimates are of frames {} to "
                            "{}{}: for a run that tracked only those ({}), evaluate with the same options",
                            ev.missing_frames, truth_file.string(), first, last,
                            stride > 1 ? " and hold one frame in " + std::to_string(stride) : std::string(), options);
    }
  }

  std::cout << "frames " << ev.frames << ": " << ev.in_view_frames << " in view (" << ev.evaluated_frames
            << " evaluated, " << ev.lost_in_view_frames << " lost, " << ev.off_track_frames
            << " off track: endpoints > " << opt.off_track_endpoint_um << " um "
            << (slab                     ? "in the imaging plane"
                : opt.off_track_in_plane ? "across the viewing axis"
                                         : "in 3D")
            << "), "
            << ev.out_of_view_frames << " out of view; lost in all " << ev.lost_frames << " (missing "
            << ev.missing_frames << ")\n";
  if (ev.evaluated_frames == 0) {
    std::cout << "  no frame in view has an estimate: there are no error figures\n";
  } else {
    print_row("position 3D", ev.in_view.position_um, "um");
    print_row(slab ? "in the imaging plane" : "position in-plane", ev.in_view.position_inplane_um, "um");
    print_row(slab ? "across the plane" : "depth", ev.in_view.depth_um, "um");
    print_row("orientation", ev.in_view.orientation_deg, "deg");
    print_row("  about x", ev.in_view.axis_deg[0], "deg");
    print_row("  about y", ev.in_view.axis_deg[1], "deg");
    print_row("  about z", ev.in_view.axis_deg[2], "deg");
    print_row("joints", ev.in_view.joint_deg, "deg");
    print_row("phalanx endpoints", ev.in_view.endpoint_um, "um");
    if (ev.tilt_mirror_frames > 0) {
      // A diagnostic: how much of the orientation error is a flat gripper's
      // tilt sign, which a view along the optical axis barely holds.
      const auto& others = ev.orientation_without_tilt_mirror_deg;
      std::cout << "  tilt mirror of a flat gripper: " << ev.tilt_mirror_frames << " frames, " << std::fixed
                << std::setprecision(0) << 100 * ev.tilt_mirror_orientation_share
                << " % of the orientation error; orientation on the other frames ";
      if (others.count > 0) {
        std::cout << std::setprecision(2) << others.mean << " +- " << others.std << " deg\n";
      } else {
        std::cout << "none\n";
      }
    }
    if (ev.tilt_branch_frames > 0) {
      // The same, whatever the fold: folded, the outline tells the two
      // branches apart, but an occluder or the border may hide what does.
      std::cout << "  other branch of the tilt's sign, any fold: " << ev.tilt_branch_frames << " frames, "
                << std::fixed << std::setprecision(0) << 100 * ev.tilt_branch_orientation_share
                << " % of the orientation error\n";
    }
  }
  std::cout << "  recovery: " << ev.recovery.size() << " returns into view, " << ev.frames_lost_after_return
            << " frames lost or off track after them\n";
  if (vm.count("breakdown")) print_breakdown(ev, truth, estimates_file);
  const std::string json = gtrack::evaluation_json(ev);
  if (vm.count("json")) gtrack::write_text_file(vm["json"].as<std::string>(), json);
  if (vm.count("per-frame")) gtrack::write_frame_errors(vm["per-frame"].as<std::string>(), ev);
  return 0;
}

}  // namespace

GTRACK_COMMAND(
    "eval", "compare estimates with ground truth: position, orientation, joint and endpoint errors, lost frames",
    [](po::options_description& d) {
      d.add_options()("truth,t", po::value<std::string>()->required(), "ground_truth.csv")(
          "estimates,e", po::value<std::string>()->required(), "estimates.csv of 'gtrack track'")(
          "config,c", po::value<std::string>(), "config naming the gripper (default: sequence.toml beside the truth)")(
          "json", po::value<std::string>(), "write the summary as JSON")(
          "per-frame", po::value<std::string>(), "write per-frame errors as CSV")(
          "breakdown", "also the errors by how much of the gripper was hidden, of a gripper partly out of view by "
                       "whether it is coming in or going out, of the frames just after a return into view, of "
                       "unoccluded frames by "
                       "whether an occlusion allowance was left over, and (after 'gtrack track --score-truth') by "
                       "whether the truth scored lower than the estimate")(
          "out-of-view-below", po::value<double>()->default_value(0.1, "0.1"),
          "share of the gripper inside the image under which a frame counts as out of view")(
          "frames", po::value<std::string>(),
          "judge only frames A:B (A inclusive, B exclusive), as the run's --frames")(
          "every", po::value<int>()->default_value(1), "judge only every K-th frame of them, as the run's --every")(
          "off-track-um", po::value<double>()->default_value(400.0, "400"),
          "mean endpoint error above which an estimate is off the gripper (recovery); for an ultrasound slice, "
          "within the imaging plane")(
          "off-track-in-plane",
          "judge off track by the endpoints' distance across the viewing axis, leaving depth out (a camera's "
          "depth error alone can pass a threshold suited to a small gripper: with --off-track-um 90 for the "
          "0.9 mm one)");
    },
    run_eval)
