// The two-pass table: its orientation smoothing (gtrack::smooth_orientations)
// against rotations computed here, and its choice between the two passes'
// estimates (gtrack::cheapest_path) against paths worked out by hand.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <array>
#include <cmath>
#include <limits>
#include <numbers>
#include <random>

#include "gtrack/two_pass.hpp"
#include "support/plugins.hpp"

using gtrack::testing::make_gripper;

namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

double angle_deg(const Eigen::VectorXd& a, const Eigen::VectorXd& b) {
  const Eigen::Quaterniond qa(gtrack::rotation_from_euler_deg(a[3], a[4], a[5]));
  const Eigen::Quaterniond qb(gtrack::rotation_from_euler_deg(b[3], b[4], b[5]));
  return qa.angularDistance(qb) / kDeg;
}

// A smooth turn about a tilted axis, x, y, z and the joints changing too,
// each finger at its own fold (a row given back as another symmetric
// equivalent has its joints in other fingers).
Eigen::VectorXd truth_at(int i) {
  Eigen::VectorXd h(12);
  h << 0.01 * i, -0.02 * i, 100 + 0.001 * i, 20 * std::sin(0.05 * i), 15 * std::cos(0.04 * i), -150 + 1.5 * i, 0, 0,
      0, 0, 0, 0;
  for (int f = 0; f < 6; ++f) h[6 + f] = std::min(40.0, 0.5 * i) + 3 * f;
  return h;
}

std::vector<gtrack::Estimate> rows_of(const std::vector<Eigen::VectorXd>& hs) {
  std::vector<gtrack::Estimate> rows(hs.size());
  for (std::size_t i = 0; i < hs.size(); ++i) {
    rows[i].frame = static_cast<int>(i);
    rows[i].hypothesis = hs[i];
    rows[i].status = gtrack::TrackStatus::Tracked;
  }
  return rows;
}

TEST(SmoothOrientations, AveragesOutEachRowsScatterAcrossSymmetricEquivalents) {
  auto gripper = make_gripper("plugin = \"hydrogel_six_finger\"");
  const auto& model = gripper->model();
  std::mt19937 rng(5);
  std::normal_distribution<double> noise(0.0, 1.5);
  std::uniform_int_distribution<int> which(0, 5);
  const int n = 250;  // rz goes from -150 past +180: it wraps
  std::vector<Eigen::VectorXd> truth, noisy;
  for (int i = 0; i < n; ++i) {
    truth.push_back(truth_at(i));
    Eigen::VectorXd h = truth.back();
    for (int a = 3; a < 6; ++a) h[a] += noise(rng);
    // Each row as any of its six symmetric equivalents, as a tracker may report it.
    noisy.push_back(model.symmetric_equivalent(h, which(rng)));
  }
  auto rows = rows_of(noisy);
  rows[50].status = gtrack::TrackStatus::Lost;
  rows[50].hypothesis[3] = 80;  // a lost row far off takes no part and is not changed
  const Eigen::VectorXd lost_before = rows[50].hypothesis;

  const double change = gtrack::smooth_orientations(model, rows, 1.5);
  double before = 0, after = 0;
  for (int i = 0; i < n; ++i) {
    if (i == 50) continue;
    const auto& r = rows[static_cast<std::size_t>(i)].hypothesis;
    // Given back as the row's own equivalent: the same joints in the same
    // fingers, position untouched, rz within a few degrees of the row's.
    EXPECT_EQ(r.head<3>(), noisy[static_cast<std::size_t>(i)].head<3>()) << i;
    EXPECT_EQ(r.tail(6), noisy[static_cast<std::size_t>(i)].tail(6)) << i;
    EXPECT_LT(std::abs(std::remainder(r[5] - noisy[static_cast<std::size_t>(i)][5], 360.0)), 10) << i;
    // Errors modulo the symmetry.
    double b = 1e9, a = 1e9;
    for (int k = 0; k < 6; ++k) {
      const Eigen::VectorXd t = model.symmetric_equivalent(truth[static_cast<std::size_t>(i)], k);
      b = std::min(b, angle_deg(noisy[static_cast<std::size_t>(i)], t));
      a = std::min(a, angle_deg(r, t));
    }
    before += b;
    after += a;
  }
  before /= n - 1;
  after /= n - 1;
  EXPECT_EQ(rows[50].hypothesis, lost_before);
  // Nor does it pull its neighbours towards its tilt of 80 deg.
  for (int i = 45; i <= 55; ++i) {
    if (i == 50) continue;
    double a = 1e9;
    for (int k = 0; k < 6; ++k) {
      a = std::min(a, angle_deg(rows[static_cast<std::size_t>(i)].hypothesis,
                                model.symmetric_equivalent(truth[static_cast<std::size_t>(i)], k)));
    }
    EXPECT_LT(a, 3.0) << i;
  }
  // Independent scatter fitted over about 4.5 rows' weight: well under
  // two thirds of it is left; the truth's own curvature adds little.
  EXPECT_LT(after, 0.65 * before) << "before " << before << " deg, after " << after << " deg";
  EXPECT_GT(change, 0.5);
  EXPECT_LT(change, 3 * before);
}

TEST(SmoothOrientations, LeavesASmoothTrackAndAZeroSigmaAlone) {
  auto gripper = make_gripper("plugin = \"hydrogel_six_finger\"");
  const auto& model = gripper->model();
  std::vector<Eigen::VectorXd> truth;
  for (int i = 0; i < 60; ++i) truth.push_back(truth_at(i));
  auto rows = rows_of(truth);
  EXPECT_EQ(gtrack::smooth_orientations(model, rows, 0.0), 0.0);
  for (int i = 0; i < 60; ++i) EXPECT_EQ(rows[static_cast<std::size_t>(i)].hypothesis, truth[static_cast<std::size_t>(i)]);
  // A smooth turn of 1.5 deg per row about z, with the tilt swinging, is
  // kept to within a small fraction of a degree, at the ends of the table
  // and next to a gap of lost rows longer than the window's reach (rows
  // 25-34: one-sided on either side). A mean of the neighbours would lag
  // there by about a degree.
  for (int i = 25; i < 35; ++i) rows[static_cast<std::size_t>(i)].status = gtrack::TrackStatus::Lost;
  gtrack::smooth_orientations(model, rows, 1.5);
  for (int i = 0; i < 60; ++i) {
    EXPECT_LT(angle_deg(rows[static_cast<std::size_t>(i)].hypothesis, truth[static_cast<std::size_t>(i)]), 0.1) << i;
  }
}

// Edge-on (a tilt of 89 deg about y) rx and rz trade off: each row of a
// slow turn written with its own split of the two, and as one of its
// symmetric equivalents, is still one orientation, and the fit keeps it.
// Equivalents ranked by their Euler angles' differences would take, for
// a row 60 deg apart from the previous one in rx and rz and 1 deg apart
// as a rotation, another equivalent, 59 deg away, and pull the rows apart.
TEST(SmoothOrientations, AGripperSeenEdgeOnKeepsItsOrientationWhateverItsEulerSplit) {
  auto gripper = make_gripper("plugin = \"hydrogel_six_finger\"");
  const auto& model = gripper->model();
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> split(30.0, 60.0);
  std::uniform_int_distribution<int> which(0, 1);
  const int n = 40;
  std::vector<Eigen::VectorXd> truth, written;
  for (int i = 0; i < n; ++i) {
    Eigen::VectorXd h = truth_at(0);
    h[3] = 0;
    h[4] = 89;
    h[5] = 0.5 * i;
    truth.push_back(h);
    // R = Rz(rz) Ry(89) Rx(rx): about Ry(90), a turn of rx is one of -rz.
    const double a = i % 2 ? split(rng) : -split(rng);
    Eigen::VectorXd w = h;
    w[3] += a;
    w[5] += a;
    ASSERT_LT(angle_deg(w, h), 1.2) << i;
    // As itself or turned by half a turn about its normal: both edge-on.
    written.push_back(model.symmetric_equivalent(w, 3 * which(rng)));
  }
  auto rows = rows_of(written);
  const double change = gtrack::smooth_orientations(model, rows, 1.5);
  EXPECT_LT(change, 1.0);
  for (int i = 0; i < n; ++i) {
    double e = 1e9;
    for (int k = 0; k < 6; ++k) {
      e = std::min(e, angle_deg(rows[static_cast<std::size_t>(i)].hypothesis,
                                model.symmetric_equivalent(truth[static_cast<std::size_t>(i)], k)));
    }
    EXPECT_LT(e, 1.5) << i;
  }
}

TEST(SmoothOrientations, ARowTheImageBarelySupportsCountsLittle) {
  auto gripper = make_gripper("plugin = \"hydrogel_six_finger\"");
  const auto& model = gripper->model();
  std::vector<Eigen::VectorXd> truth;
  for (int i = 0; i < 60; ++i) truth.push_back(truth_at(i));
  // Row 30 is 25 deg off in its tilt; every row overlaps the observation
  // by 4000 pixels, row 30 by `overlap_30`.
  const auto smoothed = [&](std::uint64_t overlap_30) {
    std::vector<Eigen::VectorXd> hs = truth;
    hs[30][3] += 25;
    auto rows = rows_of(hs);
    for (auto& r : rows) r.terms.overlap = 4000;
    rows[30].terms.overlap = overlap_30;
    gtrack::smooth_orientations(model, rows, 1.5);
    std::vector<double> error;
    for (int i = 0; i < 60; ++i) {
      error.push_back(angle_deg(rows[static_cast<std::size_t>(i)].hypothesis, truth[static_cast<std::size_t>(i)]));
    }
    return error;
  };
  // Seen as well as its neighbours, it keeps part of its error and passes
  // some to them.
  const auto alike = smoothed(4000);
  EXPECT_GT(alike[30], 4.0);
  EXPECT_GT(alike[29], 2.0);
  EXPECT_GT(alike[31], 2.0);
  // A sliver (2 % of the others' overlap): it takes its neighbours' line,
  // and they keep theirs.
  const auto sliver = smoothed(80);
  EXPECT_LT(sliver[30], 0.5);
  for (int i = 0; i < 60; ++i) {
    if (i != 30) EXPECT_LT(sliver[static_cast<std::size_t>(i)], 0.2) << i;
  }
}

// The two-pass table's choice between the forward (0) and backward (1)
// candidates, against paths worked out by hand.
using Costs = std::vector<std::array<std::array<double, 2>, 2>>;
constexpr double kOut = std::numeric_limits<double>::infinity();

TEST(CheapestPath, TakesTheCostOfEachCandidateAfterEachCandidateBefore) {
  // Frame 0: forward 1.0, backward 1.5. Frame 1 after forward: 1.0 / 2.0;
  // after backward: 2.0 / 0.1. Forward then forward sums 2.0, backward then
  // backward 1.6: the path is {1, 1}. Reading frame 1's costs from one row
  // only (each candidate's cost the same whatever came before) gives {0, 0}
  // with the first row and {0, 1} with the second.
  const Costs costs = {{{{1.0, 1.5}, {1.0, 1.5}}}, {{{1.0, 2.0}, {2.0, 0.1}}}};
  EXPECT_EQ(gtrack::cheapest_path(costs), (std::vector<int>{1, 1}));
  Costs row0 = costs, row1 = costs;
  row0[1][1] = row0[1][0];
  row1[1][0] = row1[1][1];
  EXPECT_EQ(gtrack::cheapest_path(row0), (std::vector<int>{0, 0}));
  EXPECT_EQ(gtrack::cheapest_path(row1), (std::vector<int>{0, 1}));
}

TEST(CheapestPath, PaysMoreAtOneFrameWhereTheFramesAfterRepayIt) {
  // The backward candidate costs more at frames 0 and 1, but staying on the
  // forward one costs 10 at frame 2 and switching costs 5 there: a frame by
  // frame choice takes {0, 0, 1}, at 1 + 1 + 5; the path {1, 1, 1} costs 3.
  const Costs costs = {
      {{{1.0, 1.2}, {1.0, 1.2}}},
      {{{1.0, 1.6}, {1.0, 1.2}}},
      {{{10.0, 5.0}, {10.0, 0.6}}},
  };
  EXPECT_EQ(gtrack::cheapest_path(costs), (std::vector<int>{1, 1, 1}));
}

TEST(CheapestPath, LeavesOutWhatIsRuledOutAndTiesGoForward) {
  // Frame 1 has no backward candidate (lost): every path goes through its
  // forward one, although the backward candidates around it cost nothing.
  const Costs costs = {
      {{{1.0, 0.0}, {1.0, 0.0}}},
      {{{0.5, kOut}, {3.0, kOut}}},
      {{{1.0, 0.0}, {kOut, kOut}}},
  };
  EXPECT_EQ(gtrack::cheapest_path(costs), (std::vector<int>{0, 0, 1}));
  const Costs tied = {{{{1.0, 1.0}, {1.0, 1.0}}}, {{{1.0, 1.0}, {1.0, 1.0}}}};
  EXPECT_EQ(gtrack::cheapest_path(tied), (std::vector<int>{0, 0}));
  EXPECT_TRUE(gtrack::cheapest_path(Costs{}).empty());
}

}  // namespace
