// One frame of tracking: observe, optimise, decide (see tracker.hpp).
#include "gtrack/tracker.hpp"

#include <chrono>
#include <cmath>

#include "checked_stimulus.hpp"
#include "coarse_search.hpp"
#include "gtrack/cmaes.hpp"
#include "gtrack/error.hpp"
#include "gtrack/log.hpp"

namespace gtrack {

namespace {

double ms_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

// A frame's own random stream: the same frame gets the same draws whatever
// range of the sequence is tracked.
std::uint64_t frame_seed(std::uint64_t seed, int index) {
  std::uint64_t z = seed + 0x9E3779B97F4A7C15ull * (static_cast<std::uint64_t>(index) + 1);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  return z ^ (z >> 31);
}

}  // namespace

const char* to_string(TrackStatus status) {
  switch (status) {
    case TrackStatus::Tracked: return "ok";
    case TrackStatus::Search: return "search";
    case TrackStatus::Lost: return "lost";
  }
  return "?";
}

struct Tracker::Impl {
  // The setup with its sensor seen from the sensor's own frame, in which
  // every configuration below is: the public functions turn what they take
  // and give into the world (SensorFrame, the identity for a sensor that
  // looks down world z).
  Setup setup;
  SensorFrame frame;
  std::shared_ptr<Sensor> world_sensor;  // for drawing the world's configurations
  EngineConfig config;
  std::unique_ptr<Renderer> renderer;
  // The occlusion budget's reference: the model rendered on a canvas that
  // extends the image by half its size on every side (a cpu renderer of its
  // own; one mask a frame, and only while the model reaches a border).
  std::unique_ptr<Renderer> whole_view;
  // The previous estimate's mask, once a frame: drawn on the CPU when the
  // search renders on the gl backend, where reading one mask back would
  // stall the pipeline every frame for a few thousand pixels.
  std::unique_ptr<Renderer> mask_view;
  Renderer& masks() { return mask_view ? *mask_view : *renderer; }
  std::unique_ptr<Segmenter> segmenter;
  std::unique_ptr<CostEvaluator> cost;
  Projection render_projection;
  std::optional<Eigen::VectorXd> last;
  // What the last frame not lost reported: `last` with its unseen fingers'
  // joints filled in. A lost frame reports it, so that a controller that
  // holds the last estimate sees no jump in those joints.
  std::optional<Eigen::VectorXd> reported;
  std::optional<Eigen::VectorXd> before_last;  // the estimate before `last`, both tracked: the velocity
  // `last` was found by a search (the coarse search or re-detection), not
  // tracked; and the x, y step between two such estimates of consecutive
  // frames, which starts particle 1 of the next frame.
  bool last_found = false;
  std::optional<Eigen::Vector2d> found_step;
  std::uint64_t reference_area = 0;  // |P| when O last covered the whole model (0 = none yet)
  static constexpr double kCompleteRatio = 0.9;
  // Below this tilt (deg) a result and its mirror are the same configuration.
  static constexpr double kMirrorMinTiltDeg = 3.0;
  // Re-detection replaces the track when its cost is below this share of the
  // track's.
  static constexpr double kRedetectGain = 0.7;
  // Spread multiplier of the re-detection's local swarm.
  static constexpr double kWideSpread = 3.0;
  // A stimulus whose allowed joint range is wider than this (the defaults
  // are +-1e9) says nothing about the fold.
  static constexpr double kUnboundedJointRangeDeg = 1e6;
  bool started = false;  // a frame has been processed since construction or reset
  bool observed = false;  // `observation` is of a frame this instance processed (not restored)
  int last_frame = -1;   // the last frame processed
  int lost = 0;          // consecutive lost frames
  Observation observation;

  Impl(const Setup& s, EngineConfig c, std::unique_ptr<Renderer> r)
      : setup(s), config(std::move(c)), renderer(std::move(r)) {
    if (!setup.sensor || !setup.gripper) throw Error("tracker: the setup has no sensor or gripper");
    world_sensor = setup.sensor;
    frame = sensor_frame(*setup.sensor);
    if (!frame.is_world()) setup.sensor = sensor_in_frame(setup.sensor, frame);
    renderer->set_model(setup.model());
    const Projection projection = setup.sensor->projection();
    renderer->set_projection(projection, config.render.scale);
    render_projection = scaled_projection(projection, config.render.scale);
    RenderOptions whole;
    whole.backend = "cpu";
    whole.threads = 1;
    whole_view = make_cpu_renderer(whole);
    whole_view->set_model(setup.model());
    if (renderer->name() == "gl") {
      mask_view = make_cpu_renderer(whole);
      mask_view->set_model(setup.model());
      mask_view->set_projection(projection, config.render.scale);
    }
    // Padded in render pixels, so that both canvases share one pixel grid.
    whole_view->set_projection(
        padded_projection(render_projection, render_projection.size.width / 2, render_projection.size.height / 2),
        1.0);
    segmenter = std::make_unique<Segmenter>(config.observation, setup.sensor->image_size(), renderer->render_size());
    cost = std::make_unique<CostEvaluator>(std::vector<Renderer*>{renderer.get()}, *setup.gripper, nullptr,
                                           config.cost);
    cost->set_use_rim(config.cost.occlusion_rim_px > 0);
    cost->set_gripper_label(plugin_label(setup, PluginKind::Gripper));
  }

  // Hands the current observation to the renderer, with its rim: the pixels
  // within occlusion_rim_px of O, outside it, which the occlusion budget
  // never takes as hidden.
  void show_observation() {
    renderer->set_observation(observation.mask);
    const int k = config.cost.occlusion_rim_px;
    if (k > 0) renderer->set_rim(occlusion_rim(observation.mask, k));
  }

  Eigen::VectorXd spread() const {
    const int dims = config.space.dims();
    Eigen::VectorXd s(dims);
    const auto& t = config.tracker.init_spread;
    s.head<kPoseDims>() = t.head<kPoseDims>();
    s.tail(dims - kPoseDims).setConstant(t[6]);
    return s;
  }

  // The temporal term's scales: the pose's spreads, and for the joints
  // (measured against the fold the stimulus expects, not a velocity)
  // temporal_joint_sigma_deg, 0 leaving them out.
  Eigen::VectorXd temporal_sigma() const {
    Eigen::VectorXd s = spread();
    s.tail(s.size() - kPoseDims).setConstant(config.cost.temporal_joint_sigma_deg);
    return s;
  }

  // rz is compared modulo 360 when the search space wraps it.
  bool wraps_rz() const { return config.space.periodic.size() > 5 && config.space.periodic[5]; }

  void set_temporal_prediction(const Eigen::VectorXd& prediction) {
    cost->set_prediction(prediction, temporal_sigma(), wraps_rz());
  }

  // Something to report before anything was ever found.
  Eigen::VectorXd fallback_pose() const {
    if (config.tracker.initial_pose) return *config.tracker.initial_pose;
    Eigen::VectorXd h = Eigen::VectorXd::Zero(config.space.dims());
    h.head<3>() = setup.sensor->nominal_position_mm();
    h.tail(config.space.fingers()).setConstant(setup.model().geometry().unfolded_deg);
    config.space.clamp(h);
    return h;
  }

  // The joint values the coarse search tries: between the reference shapes,
  // narrowed to what the stimulus allows now.
  std::pair<double, double> joint_range(bool stimulus_on) const {
    const auto& g = setup.model().geometry();
    double lo = std::max(g.joint_min_deg, std::min(g.unfolded_deg, g.folded_deg));
    double hi = std::min(g.joint_max_deg, std::max(g.unfolded_deg, g.folded_deg));
    if (const auto allowed = stimulus_joints(stimulus_on)) {
      const double flo = std::max(lo, allowed->first), fhi = std::min(hi, allowed->second);
      if (flo <= fhi) {
        lo = flo;
        hi = fhi;
      }
    }
    return {lo, hi};
  }

  Estimate process(const cv::Mat& input, int index, double time_s, std::optional<double> reading) {
    const auto t0 = std::chrono::steady_clock::now();
    Estimate e;
    e.frame = index;
    e.time_s = time_s;
    std::mt19937_64 rng(frame_seed(config.pso.seed, index));
    if (!std::isfinite(time_s)) {
      throw InputError(fmt::format("frame {}: its time is {}; expected a finite number of seconds", index, time_s));
    }
    if (reading && !std::isfinite(*reading)) {
      throw InputError(fmt::format("frame {}: its stimulus reading is {}; expected a finite number", index, *reading));
    }

    // Observation: around the previous estimate while it is trusted, the
    // whole image when there is none or it has been lost for too long. A
    // frame refused here (its size or type), or its reading by the stimulus
    // plugin, leaves the tracker as it was.
    const cv::Mat frame = setup.sensor->rectify(input);
    const bool searching = !last || lost >= config.tracker.reinit_after_lost;
    std::uint64_t previous_area = 0;  // |P| of the previous estimate, render pixels
    Observation fresh;
    if (!searching) {
      ObservationPrior prior;
      prior.previous_mask = masks().render_mask(*last);
      prior.margin_scale = 1.0 + lost;
      previous_area = whole_area(*last, prior.previous_mask);
      fresh = segmenter->observe(frame, &prior);
    } else {
      fresh = segmenter->observe(frame, nullptr);
    }
    reading = feed_stimulus(reading, time_s, index);
    observation = std::move(fresh);
    last_frame = index;

    const bool stimulus_on = reading.has_value() && setup.stimulus != nullptr;
    e.stimulus = reading;
    cost->set_stimulus(stimulus_on ? setup.stimulus.get() : nullptr);
    // Occlusion handling (docs/tracker.md, "Partial occlusion"): the
    // constant-velocity prediction for the temporal term, and, when O is
    // smaller than the model at the previous estimate, the weight of rendered
    // pixels outside O and the area of them taken as hidden (the budget).
    std::optional<Eigen::VectorXd> prediction;
    if (!searching) prediction = predict(stimulus_on);
    if (prediction && config.cost.temporal > 0) {
      set_temporal_prediction(*prediction);
    } else {
      cost->clear_prediction();
    }
    double outside_weight = 1.0;
    if (!searching && previous_area > 0 && config.cost.occlusion_discount > 0) {
      // The reference area is |P| at the last frame where O covered (nearly)
      // all of the model; it is frozen while O is short, so a track that
      // shrinks its model to the visible part does not reset the ratio.
      const double now = static_cast<double>(observation.count) / static_cast<double>(previous_area);
      if (now >= kCompleteRatio || reference_area == 0) reference_area = previous_area;
      const double r =
          std::min(1.0, static_cast<double>(observation.count) / static_cast<double>(reference_area));
      outside_weight = 1.0 - config.cost.occlusion_discount * (1.0 - r);
    }
    cost->set_outside_weight(outside_weight);
    set_allowance(searching ? 0 : previous_area);
    e.outside_allowance = cost->outside_allowance();
    e.outside_weight = cost->outside_weight();
    e.observed_pixels = observation.count;
    e.times.segment_ms = ms_since(t0);

    const auto t1 = std::chrono::steady_clock::now();
    if (observation.empty()) {
      ++lost;
      forget_motion();
      e.status = TrackStatus::Lost;
      e.hypothesis = reported ? *reported : last ? *last : fallback_pose();
      show_observation();
      e.terms = cost->evaluate_one(e.hypothesis);
    } else {
      show_observation();
      const std::uint64_t evals0 = cost->evaluations();
      // Single scores of a result (not the search's evaluations): `terms` is
      // always the score of `best` on the current observation.
      std::uint64_t bookkeeping = 0;
      const auto score = [&](const Eigen::VectorXd& h) {
        ++bookkeeping;
        return cost->evaluate_one(h);
      };
      // A search's result, scored: its terms as the search's own batch
      // computed them, when the result is the lowest hypothesis it evaluated
      // (no second render and read-back of the same hypothesis).
      const auto score_result = [&](const PsoResult& r) {
        if (lowest && lowest->hypothesis.size() == r.best.size() && lowest->hypothesis == r.best) return lowest->terms;
        return score(r.best);
      };
      Eigen::VectorXd best;
      CostTerms terms;
      // `initial_pose` starts the first frame that shows anything: until a
      // configuration was found there is no `last`.
      if (searching && !last && config.tracker.initial_pose) {
        const PsoResult r = optimise_with(config.pso, *config.tracker.initial_pose, stimulus_on, rng);
        best = r.best;
        e.status = TrackStatus::Tracked;
        terms = score_result(r);
      } else if (searching) {
        best = coarse(stimulus_on, rng).best;
        e.status = TrackStatus::Search;
        reference_area = 0;
        terms = score(best);
      } else {
        std::optional<Eigen::VectorXd> guess = prediction;
        if (guess && found_step) {
          guess->head<2>() += *found_step;
          config.space.clamp(*guess);
        }
        const PsoResult r = optimise_with(config.pso, *last, stimulus_on, rng, guess ? &*guess : nullptr);
        best = r.best;
        e.status = TrackStatus::Tracked;
        const CostTerms tracked = score_result(r);
        terms = tracked;
        // The fit is judged without the rim: the true configuration of a
        // partly hidden gripper pays for the rim along the occluder's edge,
        // which says nothing about whether the track is wrong.
        if (tracked.dice_without_rim > config.tracker.redetect_dice) {
          // Re-detection: the coarse search, and a swarm around the track
          // with three times the spreads (the right configuration is often a
          // nearby basin the coarse grid's steps do not reach: strong tilts,
          // partly hidden).
          // The search looks at the whole image: the ROI and the temporal
          // prior were placed around the track, and when the track is wrong
          // they cut away the gripper it should find. The track is scored
          // again on the same observation, so that the two compare fairly.
          const Observation trimmed = observation;
          const Observation whole = segmenter->observe(frame, nullptr);
          const bool widened = whole.count > observation.count;
          CostTerms current = tracked;
          if (widened) {
            observation = whole;
            show_observation();
            set_allowance(previous_area);
            current = score(best);
          }
          // The searches run without the temporal term, which would hold
          // them near the configuration they are to question.
          const bool predicting = prediction && config.cost.temporal > 0;
          if (predicting) cost->clear_prediction();
          auto found = coarse(stimulus_on, rng);
          const auto keep_lower = [&found](const PsoResult& r) {
            if (r.best_cost < found.cost) {
              found.best = r.best;
              found.cost = r.best_cost;
            }
          };
          keep_lower(optimise_with(config.pso, best, stimulus_on, rng, nullptr, kWideSpread));
          // Tilt directions: under a large occluder, a folded gripper
          // tilted one way and one tilted as much another way can show the
          // same visible part, and a track on the wrong direction stays
          // there: every search of the frame starts from it. Short CMA-ES
          // runs start from the track with its tilt turned.
          const int directions = config.tracker.redetect_tilt_directions;
          for (int k = 1; k < directions; ++k) {
            keep_lower(search_turned_tilt(best, 360.0 * k / directions, stimulus_on, rng));
          }
          if (predicting) set_temporal_prediction(*prediction);
          const CostTerms alternative = score(found.best);
          const double lt = config.cost.temporal;
          // Compared without the temporal term: the point is to leave the
          // predicted configuration when the image says it is wrong. And
          // only a clear gain counts: under occlusion many configurations
          // explain what is visible about equally well, and trading the
          // track for one of them on a marginal gain is a jump, not a fix.
          // (The gain required does not grow with the hidden share: with the
          // occlusion rim, a track gone wrong under an occluder scores well
          // above the truth, and such a requirement kept it there;
          // docs/tracker.md, re-detection.)
          const double track_cost = current.total - lt * current.temporal;
          const double found_cost = alternative.total - lt * alternative.temporal;
          const bool taken = found_cost < kRedetectGain * track_cost;
          logger().debug("frame {}: re-detection (D without the rim {:.4f} > {}): track {:.4f}, best found {:.4f}: {}",
                         index, tracked.dice_without_rim, config.tracker.redetect_dice, track_cost, found_cost,
                         taken ? "taken" : "the track is kept");
          if (taken) {
            best = found.best;
            terms = alternative;
            e.redetected = true;
          } else if (widened) {
            observation = trimmed;
            show_observation();
            set_allowance(previous_area);
          }
        }
      }
      if (config.tracker.mirror_check && std::hypot(best[3], best[4]) > kMirrorMinTiltDeg) {
        // The tilt mirror of the result, (rx, ry) -> (-rx, -ry): seen along
        // the optical axis its outline differs only through perspective, so
        // a swarm that settled on one branch rarely crosses to the other. A
        // short swarm refines the mirror (the branch's depth and tilt
        // compensate each other, so the bare mirror scores worse than it
        // should) and the lower of the two is kept.
        Eigen::VectorXd mirror = best;
        mirror[3] = -mirror[3];
        mirror[4] = -mirror[4];
        config.space.clamp(mirror);
        PsoConfig small = config.pso;
        small.particles = std::max(4, config.pso.particles / 2);
        small.generations = std::max(2, config.pso.generations / 2);
        // (Its own mirror particles start back on the first branch: a
        // second, short look at both.)
        const PsoResult m = optimise_with(small, mirror, stimulus_on, rng);
        logger().debug("frame {}: mirror check: result {:.4f}, its tilt mirror refined {:.4f}", index, terms.total,
                       m.best_cost);
        const double kept = std::min(terms.total, m.best_cost), other = std::max(terms.total, m.best_cost);
        e.tilt_margin = (other - kept) / std::max(kept, 1e-9);
        if (m.best_cost < terms.total) {
          // Reported as mirrored only when the tilt did change branch.
          e.mirrored = m.best[3] * best[3] + m.best[4] * best[4] < 0;
          best = m.best;
          terms = score_result(m);
        }
      }
      if (config.tracker.refine_spread > 0 && !searching) {
        // Refinement (not in the paper): a second search of N samples and G
        // generations, started around the result with a fraction of the
        // spreads; CMA-ES by default, an earlier release's swarm with
        // refine_optimizer = "pso". The first swarm's spreads are sized to
        // follow the motion between frames; in a 12- to 14-parameter space
        // its N x G evaluations end before they settle, and on most frames
        // with a large error the truth scores lower than the estimate
        // (gtrack eval --breakdown after --score-truth). Kept only if it
        // scores lower. The swarm's `mirror_particles` start near the other
        // tilt branch too; a switch made here is not reported as `mirrored`.
        const PsoResult r = config.tracker.refine_optimizer == "cmaes"
                                ? refine_cmaes(best, stimulus_on, rng)
                                : optimise_with(config.pso, best, stimulus_on, rng, nullptr, config.tracker.refine_spread);
        logger().debug("frame {}: refinement: result {:.4f}, refined {:.4f}", index, terms.total, r.best_cost);
        if (r.best_cost < terms.total) {
          best = r.best;
          terms = score_result(r);
        }
      }
      // What is reported: the result, with the joints of the fingers the
      // image does not see filled in. The track goes on from the result
      // itself, so that the fill, a choice within what the image allows,
      // never steers the next frame's search, nor decides whether the frame
      // is lost.
      CostTerms reported_terms = terms;
      e.hypothesis = with_unseen_joints_filled(best, reported_terms, e.unseen_fingers);
      e.evaluations = cost->evaluations() - evals0 - bookkeeping;
      e.outside_allowance = cost->outside_allowance();  // re-detection may have widened O
      e.observed_pixels = observation.count;
      e.terms = reported_terms;
      if (terms.dice > config.tracker.lost_dice) {
        // The search's result is not taken: the frame reports the estimate
        // the track holds, scored on this frame. Before any track, the
        // refused result is the frame's guess but anchors nothing: the next
        // frame searches the whole image again (an ROI and a prediction
        // placed around the guess would look where the gripper was not found).
        ++lost;
        e.status = TrackStatus::Lost;
        forget_motion();
        e.unseen_fingers.clear();
        e.redetected = e.mirrored = false;
        e.tilt_margin.reset();
        if (reported || last) {
          e.hypothesis = reported ? *reported : *last;
          e.terms = cost->evaluate_one(e.hypothesis);
        } else {
          e.hypothesis = best;
          e.terms = terms;
        }
      } else {
        lost = 0;
        // A velocity needs two estimates of one continuous track: not across
        // a search, a re-detection or a switch to the mirror branch.
        found_step.reset();
        if (e.status == TrackStatus::Tracked && last && !e.redetected && !e.mirrored) {
          before_last = last;
        } else {
          before_last.reset();
          // Two consecutive frames found by a search: a gripper moving
          // faster than the swarm's spreads (typically coming back into
          // view), which the track keeps losing. The step between the two
          // is its motion more often than not; it starts particle 1 of the
          // next frame, but the temporal term, which a wrong step would
          // make pay for the right configuration, does not use it.
          if (e.redetected && last_found) found_step = (best - *last).head<2>();
        }
        last_found = e.status == TrackStatus::Search || e.redetected;
        last = best;
        reported = e.hypothesis;
      }
    }
    started = true;
    observed = true;
    e.times.pso_ms = ms_since(t1);
    e.ms = ms_since(t0);
    return e;
  }

  // Unseen fingers (docs/tracker.md, "Unseen fingers"): under an occluder,
  // beyond the image's border or outside an ultrasound slab, a finger's
  // joint does not change what is rendered inside O, and the search leaves it
  // wherever its last best particle had it. One stimulus drives every finger,
  // so the seen fingers' fold is the best guess for the others. A finger is
  // unseen when moving its joint to the other fingers' mean raises E by at
  // most unseen_joint_tolerance (one batch of F hypotheses); the unseen ones
  // then take the seen ones' mean fold, kept if E rises by at most the
  // tolerance again. `terms` becomes the reported configuration's, and
  // `filled_fingers` lists the fingers filled in (1 = q1).
  Eigen::VectorXd with_unseen_joints_filled(const Eigen::VectorXd& best, CostTerms& terms,
                                            std::vector<int>& filled_fingers) {
    const int fingers = config.space.fingers();
    const double tolerance = config.tracker.unseen_joint_tolerance;
    if (tolerance <= 0 || fingers < 2) return best;
    const Eigen::VectorXd q = best.tail(fingers);
    Eigen::MatrixXd moved = best.replicate(1, fingers);
    for (int k = 0; k < fingers; ++k) moved(kPoseDims + k, k) = (q.sum() - q[k]) / (fingers - 1);
    Eigen::VectorXd costs;
    cost->evaluate(moved, costs);
    std::vector<int> unseen;
    double seen_sum = 0;
    for (int k = 0; k < fingers; ++k) {
      if (costs[k] <= terms.total + tolerance) {
        unseen.push_back(k);
      } else {
        seen_sum += q[k];
      }
    }
    const int seen = fingers - static_cast<int>(unseen.size());
    if (unseen.empty() || seen == 0) return best;
    Eigen::VectorXd filled = best;
    for (int k : unseen) filled[kPoseDims + k] = seen_sum / seen;
    config.space.clamp(filled);
    const CostTerms filled_terms = cost->evaluate_one(filled);
    if (filled_terms.total > terms.total + tolerance) return best;
    terms = filled_terms;
    for (int k : unseen) filled_fingers.push_back(k + 1);
    return filled;
  }

  // No velocity and no found step: the next estimate starts a new track.
  void forget_motion() {
    before_last.reset();
    last_found = false;
    found_step.reset();
  }

  // The reading in force for a frame (the configured default when there is
  // none), fed to the stimulus plugin.
  // A reading the plugin refuses is an InputError naming the frame (`index`;
  // -1 for a replayed one) and the reading.
  std::optional<double> feed_stimulus(std::optional<double> reading, double time_s, int index) {
    if (!reading && config.tracker.default_stimulus) reading = config.tracker.default_stimulus;
    if (!reading || !setup.stimulus) return reading;
    try {
      setup.stimulus->update(*reading, time_s);
    } catch (const std::exception& refused) {
      const std::string when = index >= 0 ? fmt::format("frame {} (t = {:.3f} s)", index, time_s)
                                          : fmt::format("the replayed reading at t = {:.3f} s", time_s);
      throw InputError(fmt::format("{}: the stimulus plugin refused the reading {:g}: {}", when, *reading,
                                   refused.what()));
    }
    return reading;
  }

  // |P| of h, the part beyond the image's borders included: what the
  // occlusion budget expects of O. A gripper entering the view under an
  // occluder shows less than the whole model, and the part the previous
  // estimate had beyond the border has come in since; the in-view area
  // alone would leave the occluded part unallowed. `mask` is h rendered in
  // the image; its area is the whole area unless it reaches a border.
  std::uint64_t whole_area(const Eigen::VectorXd& h, const cv::Mat& mask) const {
    const int last_row = mask.rows - 1, last_col = mask.cols - 1;
    const bool at_border = cv::countNonZero(mask.row(0)) > 0 || cv::countNonZero(mask.row(last_row)) > 0 ||
                           cv::countNonZero(mask.col(0)) > 0 || cv::countNonZero(mask.col(last_col)) > 0;
    return static_cast<std::uint64_t>(cv::countNonZero(at_border ? whole_view->render_mask(h) : mask));
  }

  // The occlusion budget for the current observation against the model's
  // whole area at the previous estimate (0: none, e.g. when searching).
  void set_allowance(std::uint64_t previous_area) {
    double allowance = 0, tolerance = 0;
    if (config.cost.occlusion_budget > 0 && previous_area > 0) {
      const double expected = static_cast<double>(previous_area);
      allowance = config.cost.occlusion_budget * (expected - static_cast<double>(observation.count));
      tolerance = config.cost.occlusion_tolerance * expected;
      if (allowance < tolerance) allowance = 0;
    }
    cost->set_outside_allowance(allowance, tolerance);
  }

  detail::CoarseSearchResult coarse(bool stimulus_on, std::mt19937_64& rng) {
    const auto [jlo, jhi] = joint_range(stimulus_on);
    detail::CoarseSearchInput in;
    in.observation = &observation.mask;
    in.render_projection = render_projection;
    in.nominal_mm = setup.sensor->nominal_position_mm();
    in.model = &setup.model();
    in.joint_lo = jlo;
    in.joint_hi = jhi;
    return detail::coarse_search(in, config, *cost, rng);
  }

  // The pose at constant velocity: last + (last - before_last), rz the short
  // way; the last pose itself when there is no velocity yet. The joints are
  // not extrapolated: they take the middle of the range the stimulus allows
  // now (with a response time, the fold the material can have reached), or
  // stay at the last estimate when there is no stimulus.
  Eigen::VectorXd predict(bool stimulus_on) const {
    Eigen::VectorXd p = *last;
    if (before_last && before_last->size() == last->size()) {
      Eigen::VectorXd v = *last - *before_last;
      v.tail(v.size() - kPoseDims).setZero();
      if (v.size() > 5) v[5] = std::remainder(v[5], 360.0);
      // Depth is seen too weakly for its frame-to-frame change to be a
      // velocity (it is mostly noise): it is predicted to stay.
      v[2] = 0;
      p += v;
    }
    const auto allowed = stimulus_joints(stimulus_on);
    if (allowed && std::isfinite(allowed->first) && std::isfinite(allowed->second) &&
        allowed->second - allowed->first < kUnboundedJointRangeDeg) {
      p.tail(p.size() - kPoseDims).setConstant(0.5 * (allowed->first + allowed->second));
    }
    config.space.clamp(p);
    return p;
  }

  // The joint range the stimulus allows now (StimulusState's feasible range;
  // +-1e9 from a stimulus that does not bound them), none without a stimulus.
  std::optional<std::pair<double, double>> stimulus_joints(bool stimulus_on) const {
    if (!stimulus_on) return std::nullopt;
    const StimulusState st = setup.stimulus->state();
    return std::make_pair(st.feasible_min_deg, st.feasible_max_deg);
  }

  // The lowest-total hypothesis of the last search (optimise_with,
  // cmaes_from) and its terms, all computed by the search's batches on one
  // state of the cost: score_result in process() takes them from here.
  struct Lowest {
    Eigen::VectorXd hypothesis;
    CostTerms terms;
  };
  std::optional<Lowest> lowest;
  std::vector<CostTerms> batch_terms;

  // A search's objective: the batch's totals, remembering the lowest.
  void evaluate_remembering_lowest(const Eigen::MatrixXd& x, Eigen::VectorXd& totals) {
    cost->evaluate(x, batch_terms);
    totals.resize(x.cols());
    for (Eigen::Index i = 0; i < x.cols(); ++i) {
      const CostTerms& t = batch_terms[static_cast<size_t>(i)];
      totals[i] = t.total;
      if (!lowest || t.total < lowest->terms.total) lowest = Lowest{x.col(i), t};
    }
  }

  // The refinement by CMA-ES (docs/tracker.md, "The refinement"): N samples
  // a generation for G generations, from the result with joints the
  // stimulus allows now, the first samples' standard deviation that of a
  // uniform draw within refine_spread spreads.
  PsoResult refine_cmaes(const Eigen::VectorXd& from, bool stimulus_on, std::mt19937_64& rng) {
    return cmaes_from(start_from(from, stimulus_on), config.tracker.refine_spread / std::sqrt(3.0),
                      std::max(4, config.pso.particles), config.pso.generations, rng);
  }

  // A CMA-ES from `start` (inside the box) over the spreads, each generation
  // one batch of the cost.
  PsoResult cmaes_from(const Eigen::VectorXd& start, double step, int population, int generations,
                       std::mt19937_64& rng) {
    CmaesOptions options;
    options.population = population;
    options.generations = generations;
    options.step = step;
    lowest.reset();
    return cmaes_minimize(
        start, spread(), config.space, options,
        [&](const Eigen::MatrixXd& x, Eigen::VectorXd& c) { evaluate_remembering_lowest(x, c); }, rng);
  }

  // Re-detection's search from `from` with its tilt (rx, ry) turned by
  // `turn_deg` about the line of sight, the rest unchanged: a CMA-ES of N/2
  // samples and G/3 generations, its first samples' standard deviation that
  // of a uniform draw within one spread.
  PsoResult search_turned_tilt(const Eigen::VectorXd& from, double turn_deg, bool stimulus_on, std::mt19937_64& rng) {
    return cmaes_from(start_from(tilt_turned(from, turn_deg), stimulus_on), 1.0 / std::sqrt(3.0),
                      std::max(4, config.pso.particles / 2), std::max(2, config.pso.generations / 3), rng);
  }

  // `from` with its joints brought into the range the stimulus allows now,
  // inside the box: where every search of a frame starts.
  Eigen::VectorXd start_from(const Eigen::VectorXd& from, bool stimulus_on) const {
    Eigen::VectorXd start = from;
    if (const auto allowed = stimulus_joints(stimulus_on)) {
      // With a response time the allowed range moves with the fold, and a
      // previous estimate left outside it would otherwise have to be walked
      // back by the penalty alone.
      for (Eigen::Index d = kPoseDims; d < start.size(); ++d) {
        start[d] = std::clamp(start[d], allowed->first, allowed->second);
      }
    }
    config.space.clamp(start);
    return start;
  }

  PsoResult optimise_with(const PsoConfig& pso_config, const Eigen::VectorXd& from, bool stimulus_on,
                          std::mt19937_64& rng, const Eigen::VectorXd* prediction = nullptr,
                          double spread_scale = 1.0) {
    const double fold = stimulus_on ? setup.stimulus->fold_fraction() : 0.5;
    const Eigen::VectorXd s = spread() * spread_scale;
    const Eigen::VectorXd start = start_from(from, stimulus_on);
    Eigen::MatrixXd init = biased_initial_swarm(start, s, fold, pso_config.particles, config.space, rng);
    // Seen along the optical axis, a flat gripper tilted by (rx, ry) and by
    // (-rx, -ry) casts the same silhouette. The last few particles explore
    // the mirror tilt, so a track that picked the wrong one while the
    // gripper was flat can switch once folding tells them apart.
    const int mirrors = std::min(config.tracker.mirror_particles, static_cast<int>(init.cols()) - 1);
    for (int i = static_cast<int>(init.cols()) - mirrors; i < init.cols(); ++i) {
      init(3, i) -= 2 * start[3];
      init(4, i) -= 2 * start[4];
      config.space.clamp(init.col(i));
    }
    // Particle 1 starts at the constant-velocity prediction, or where the
    // found step leads (particle 0 stays at the previous best, as in the
    // paper).
    if (prediction && config.cost.temporal > 0 && init.cols() - mirrors > 1) init.col(1) = *prediction;
    ParticleSwarm pso(pso_config, config.space);
    pso.set_randomization_spread(s);
    lowest.reset();
    return pso.run(
        init, [&](const Eigen::MatrixXd& x, Eigen::VectorXd& c) { evaluate_remembering_lowest(x, c); }, rng);
  }
};

Tracker::Tracker(const Setup& setup, EngineConfig config)
    : Tracker(setup, config, make_renderer(config.render)) {}

Tracker::Tracker(const Setup& setup, EngineConfig config, std::unique_ptr<Renderer> renderer)
    : impl_(std::make_unique<Impl>(setup, std::move(config), std::move(renderer))) {}

Tracker::~Tracker() = default;

Estimate Tracker::process(const cv::Mat& frame, int index, double time_s, std::optional<double> stimulus) {
  Estimate e = impl_->process(frame, index, time_s, stimulus);
  e.hypothesis = impl_->frame.to_world(e.hypothesis);
  return e;
}

Tracker::Tracker(Tracker&&) noexcept = default;
Tracker& Tracker::operator=(Tracker&&) noexcept = default;

void Tracker::reset() {
  // The stimulus plugin starts again too: made anew from its table when the
  // loader made it (its state has no reset of its own). A stimulus the
  // application put in the Setup itself is left as it is.
  const bool from_loader = dynamic_cast<const detail::CheckedStimulus*>(impl_->setup.stimulus.get()) != nullptr;
  if (from_loader && impl_->setup.loader && impl_->setup.root.has("stimulus")) {
    impl_->cost->set_stimulus(nullptr);  // set again from the new one by the next frame
    impl_->setup.stimulus = impl_->setup.loader->make_stimulus(impl_->setup.root.table("stimulus"));
  }
  impl_->last.reset();
  impl_->reported.reset();
  impl_->forget_motion();
  impl_->reference_area = 0;
  impl_->started = false;
  impl_->observed = false;
  impl_->last_frame = -1;
  impl_->lost = 0;
}

TrackerState Tracker::state() const {
  TrackerState s;
  s.frame = impl_->last_frame;
  s.last = impl_->last;
  s.reported = impl_->reported;
  s.before_last = impl_->before_last;
  s.last_found = impl_->last_found;
  if (impl_->found_step) s.found_step = Eigen::VectorXd(*impl_->found_step);
  s.lost = impl_->lost;
  s.started = impl_->started;
  s.reference_area = impl_->reference_area;
  return s;
}

void Tracker::restore(const TrackerState& s) {
  const int dims = impl_->config.space.dims();
  for (const auto* h : {&s.last, &s.reported, &s.before_last}) {
    if (*h && (*h)->size() != dims) {
      throw Error("holds a configuration of " + std::to_string((*h)->size()) + " values, this setup has " +
                  std::to_string(dims));
    }
  }
  if (s.found_step && s.found_step->size() != 2) {
    throw Error("holds a found step of " + std::to_string(s.found_step->size()) + " values, expected 2 (x, y)");
  }
  for (const auto* h : {&s.last, &s.reported, &s.before_last}) {
    if (*h && !(*h)->allFinite()) throw Error("holds a configuration that is not finite (nan or inf)");
  }
  if (s.found_step && !s.found_step->allFinite()) throw Error("holds a found step that is not finite (nan or inf)");
  impl_->last_frame = s.frame;
  impl_->last = s.last;
  impl_->reported = s.reported;
  impl_->before_last = s.before_last;
  impl_->last_found = s.last_found;
  impl_->found_step.reset();
  if (s.found_step) impl_->found_step = Eigen::Vector2d((*s.found_step)[0], (*s.found_step)[1]);
  impl_->lost = s.lost;
  impl_->started = s.started;
  impl_->reference_area = s.reference_area;
}

void Tracker::replay_stimulus(std::optional<double> stimulus, double time_s) {
  if (stimulus && !std::isfinite(*stimulus)) {
    throw InputError(fmt::format("replay_stimulus: the reading is {}; expected a finite number", *stimulus));
  }
  if (!std::isfinite(time_s)) throw InputError(fmt::format("replay_stimulus: the time is {}; expected seconds", time_s));
  impl_->feed_stimulus(stimulus, time_s, -1);
}

void Tracker::set_estimate(const Eigen::VectorXd& hypothesis) {
  if (hypothesis.size() != impl_->config.space.dims()) {
    throw Error("set_estimate: expected " + std::to_string(impl_->config.space.dims()) + " parameters");
  }
  if (!hypothesis.allFinite()) throw Error("set_estimate: the configuration is not finite (nan or inf)");
  impl_->last = impl_->frame.from_world(hypothesis);
  impl_->reported = impl_->last;
  impl_->forget_motion();
  impl_->started = true;
  impl_->lost = 0;
}

std::optional<Eigen::VectorXd> Tracker::last_estimate() const {
  if (!impl_->last) return std::nullopt;
  return impl_->frame.to_world(*impl_->last);
}
const Observation& Tracker::last_observation() const { return impl_->observation; }

CostTerms Tracker::score(const Eigen::VectorXd& hypothesis) {
  if (!impl_->observed) throw Error("tracker: score() needs a frame processed by this tracker");
  if (hypothesis.size() != impl_->config.space.dims()) {
    throw Error("tracker: score() got " + std::to_string(hypothesis.size()) + " parameters, the model has " +
                std::to_string(impl_->config.space.dims()));
  }
  return impl_->cost->evaluate_one(impl_->frame.from_world(hypothesis));
}
CostTerms Tracker::score_after(const Eigen::VectorXd& hypothesis, const Eigen::VectorXd& previous) {
  if (!impl_->observed) throw Error("tracker: score_after() needs a frame processed by this tracker");
  const auto dims = impl_->config.space.dims();
  for (const auto* h : {&hypothesis, &previous}) {
    if (h->size() != dims) {
      throw Error("tracker: score_after() got " + std::to_string(h->size()) + " parameters for the " +
                  (h == &previous ? "previous estimate" : "configuration") + ", the model has " +
                  std::to_string(dims));
    }
  }
  auto& cost = *impl_->cost;
  const double allowance = cost.outside_allowance(), tolerance = cost.outside_tolerance();
  const Eigen::VectorXd before = impl_->frame.from_world(previous);
  impl_->set_allowance(impl_->whole_area(before, impl_->masks().render_mask(before)));
  const CostTerms terms = score(hypothesis);
  cost.set_outside_allowance(allowance, tolerance);
  return terms;
}

double Tracker::temporal_term(const Eigen::VectorXd& hypothesis, const Eigen::VectorXd& prediction) const {
  const SensorFrame& f = impl_->frame;
  return temporal_distance(f.from_world(hypothesis), f.from_world(prediction), impl_->temporal_sigma(),
                           impl_->wraps_rz());
}

Renderer& Tracker::renderer() { return *impl_->renderer; }
const EngineConfig& Tracker::config() const { return impl_->config; }
const ParameterSpace& Tracker::space() const { return impl_->config.space; }

}  // namespace gtrack

#include "overlay.hpp"

namespace gtrack {

cv::Mat Tracker::draw_overlay(const cv::Mat& frame, const Estimate& estimate) const {
  return detail::draw_estimate(frame, *impl_->world_sensor, impl_->setup.model(),
                               detail::reading_text(impl_->setup.stimulus.get(), estimate), estimate);
}

}  // namespace gtrack
