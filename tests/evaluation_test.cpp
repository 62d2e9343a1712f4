// The evaluator: symmetry, geodesic angles, lost and out-of-view frames, recovery, CSV errors.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <fstream>
#include <numbers>

#include "gtrack/error.hpp"
#include "gtrack/evaluation.hpp"
#include "support/plugins.hpp"

using gtrack::testing::make_gripper;

namespace {

Eigen::VectorXd pose(double x, double y, double z, double rx, double ry, double rz, std::vector<double> q) {
  Eigen::VectorXd h(6 + q.size());
  h << x, y, z, rx, ry, rz, Eigen::Map<Eigen::VectorXd>(q.data(), q.size());
  return h;
}

gtrack::PoseRow row(int frame, const Eigen::VectorXd& h, std::string status = "ok", double in_view = 1) {
  gtrack::PoseRow r;
  r.frame = frame;
  r.h = h;
  r.status = std::move(status);
  r.extra["in_view"] = in_view;
  return r;
}

TEST(Evaluation, SymmetricEquivalentScoresZero) {
  auto g = make_gripper("plugin = \"hydrogel_six_finger\"");
  const auto& m = g->model();
  const Eigen::VectorXd truth = pose(0.3, -0.2, 100, 25, -30, 40, {5, 12, 20, 28, 35, 41});
  for (int k = 1; k < 6; ++k) {
    // Turned by k * 60 degrees about the palm normal, fingers renumbered.
    const Eigen::VectorXd est = m.symmetric_equivalent(truth, k);
    ASSERT_GT((est - truth).norm(), 1.0) << "the equivalent must differ as numbers";
    const auto e = gtrack::compare_to_truth(m, truth, est);
    EXPECT_NEAR(e.endpoint_um, 0, 1e-6) << k;
    EXPECT_NEAR(e.orientation_deg, 0, 1e-6) << k;
    EXPECT_NEAR(e.joint_deg, 0, 1e-9) << k;
    EXPECT_NEAR(e.position_um, 0, 1e-9) << k;
    for (int a = 0; a < 3; ++a) EXPECT_NEAR(e.axis_deg[a], 0, 1e-6) << k;
  }
}

TEST(Evaluation, ErrorsAboutEachAxisStaySmallAtNinetyDegreesOfTilt) {
  auto g = make_gripper("plugin = \"hydrogel_six_finger\"");
  const auto& m = g->model();
  // At ry = 90 deg, rx and rz trade off: Euler differences of these two
  // near-equal poses would be 30 deg about x and z.
  const Eigen::VectorXd truth = pose(0, 0, 100, 30, 90, 10, {10, 10, 10, 10, 10, 10});
  Eigen::VectorXd est = truth;
  est[4] = 89.9;
  const auto e = gtrack::compare_to_truth(m, truth, est);
  EXPECT_NEAR(e.orientation_deg, 0.1, 1e-6);
  for (int a = 0; a < 3; ++a) EXPECT_LE(e.axis_deg[a], 0.1 + 1e-6) << a;
  EXPECT_NEAR(e.axis_deg.norm(), e.orientation_deg, 1e-9);
  // A turn about the world's x axis alone is an error about x alone.
  const Eigen::VectorXd flat = pose(0, 0, 100, 0, 0, 0, {10, 10, 10, 10, 10, 10});
  Eigen::VectorXd turned = flat;
  turned.segment<3>(3) = gtrack::euler_deg_from_rotation(
      Eigen::AngleAxisd(5 * std::numbers::pi / 180, Eigen::Vector3d::UnitX()).toRotationMatrix());
  const auto x = gtrack::compare_to_truth(m, flat, turned);
  EXPECT_NEAR(x.axis_deg[0], 5, 1e-6);
  EXPECT_NEAR(x.axis_deg[1], 0, 1e-6);
  EXPECT_NEAR(x.axis_deg[2], 0, 1e-6);
}

TEST(Evaluation, PooledStatisticsAreThoseOfAllTheFrames) {
  // {1, 2, 3} and {10, 20} taken as {1, 2, 3, 10, 20}.
  gtrack::ErrorStats a, b, none;
  a.mean = 2, a.std = std::sqrt(2.0 / 3), a.max = 3, a.count = 3;
  b.mean = 15, b.std = 5, b.max = 20, b.count = 2;
  const gtrack::ErrorStats all = gtrack::pooled({a, none, b});
  EXPECT_EQ(all.count, 5);
  EXPECT_NEAR(all.mean, 7.2, 1e-12);
  EXPECT_NEAR(all.std, std::sqrt(102.8 - 7.2 * 7.2), 1e-12);
  EXPECT_EQ(all.max, 20);
  EXPECT_TRUE(std::isnan(all.median));
}

TEST(Evaluation, ErrorsAreInMicrometresAndDegrees) {
  auto g = make_gripper("plugin = \"hydrogel_six_finger\"");
  const auto& m = g->model();
  const Eigen::VectorXd truth = pose(0, 0, 100, 0, 0, 0, {10, 10, 10, 10, 10, 10});
  Eigen::VectorXd est = truth;
  est[0] += 0.003;   // 3 um in x
  est[1] -= 0.004;   // 4 um in y
  est[2] += 0.012;   // 12 um in depth
  est[6] += 6;       // one finger off by 6 deg
  const auto e = gtrack::compare_to_truth(m, truth, est);
  EXPECT_NEAR(e.inplane_um, 5, 1e-6);
  EXPECT_NEAR(e.depth_um, 12, 1e-6);
  EXPECT_NEAR(e.position_um, 13, 1e-6);
  EXPECT_NEAR(e.joint_deg, 1, 1e-9);
  EXPECT_EQ(e.symmetry_k, 0);
  EXPECT_NEAR(e.orientation_deg, 0, 1e-9);
}

TEST(Evaluation, GeodesicAngle) {
  EXPECT_NEAR(gtrack::geodesic_angle_deg({0, 0, 0}, {10, 0, 0}), 10, 1e-9);
  EXPECT_NEAR(gtrack::geodesic_angle_deg({0, 0, 170}, {0, 0, -170}), 20, 1e-9);
  // Two rotations about different axes: the angle of R_a^T R_b, not the sum of Euler differences.
  const Eigen::Matrix3d r = gtrack::rotation_from_euler_deg(30, 0, 0).transpose() *
                            gtrack::rotation_from_euler_deg(0, 40, 0);
  const double expected = Eigen::AngleAxisd(r).angle() * 180 / M_PI;
  EXPECT_NEAR(gtrack::geodesic_angle_deg({30, 0, 0}, {0, 40, 0}), expected, 1e-9);
  EXPECT_LT(expected, 70);
  // The same rotation written on the other Euler branch.
  EXPECT_NEAR(gtrack::geodesic_angle_deg({20, 30, 40}, {20 + 180, 180 - 30, 40 + 180}), 0, 1e-9);
}

TEST(Evaluation, FlagsTheTiltMirrorOfAFlatGripperAndTheOtherTiltBranch) {
  auto g = make_gripper("plugin = \"hydrogel_six_finger\"");
  const auto& m = g->model();
  const std::vector<double> flat(6, 0.0), folded(6, 30.0);
  // Flat and tilted by 20 deg about x: the estimate tilted the other way is
  // the mirror, 40 deg off; one tilted the same way with a small error is not.
  const Eigen::VectorXd truth = pose(0, 0, 100, 20, 0, 15, flat);
  const auto mirrored = gtrack::compare_to_truth(m, truth, pose(0, 0, 100, -20, 0, 15, flat));
  EXPECT_TRUE(mirrored.tilt_mirror);
  EXPECT_TRUE(mirrored.tilt_branch);
  EXPECT_NEAR(mirrored.orientation_deg, 40, 1e-6);
  // The mirror is judged on the palm normal, whatever the turn about the
  // optical axis.
  EXPECT_TRUE(gtrack::compare_to_truth(m, truth, pose(0, 0, 100, -18, 3, 70, flat)).tilt_mirror);
  const auto same_branch = gtrack::compare_to_truth(m, truth, pose(0, 0, 100, 17, -2, 15, flat));
  EXPECT_FALSE(same_branch.tilt_mirror);
  EXPECT_FALSE(same_branch.tilt_branch);
  // A folded truth's outline tells the tilts apart: never the flat mirror,
  // but the estimate is on the other branch of the tilt's sign.
  const Eigen::VectorXd folded_truth = pose(0, 0, 100, 20, 0, 15, folded);
  const Eigen::VectorXd folded_other = pose(0, 0, 100, -20, 0, 15, folded);
  const auto folded_pair = gtrack::compare_to_truth(m, folded_truth, folded_other);
  EXPECT_FALSE(folded_pair.tilt_mirror);
  EXPECT_TRUE(folded_pair.tilt_branch);
  // Upside down is neither.
  const auto upside_down = gtrack::compare_to_truth(m, truth, pose(0, 0, 100, 20 + 180, 0, 15, flat));
  EXPECT_FALSE(upside_down.tilt_mirror);
  EXPECT_FALSE(upside_down.tilt_branch);
  // Nearly untilted: the two are the same configuration.
  const auto untilted =
      gtrack::compare_to_truth(m, pose(0, 0, 100, 2, 0, 0, flat), pose(0, 0, 100, -2, 0, 0, flat));
  EXPECT_FALSE(untilted.tilt_mirror);
  EXPECT_FALSE(untilted.tilt_branch);

  // Judged about the line of sight: seen along x, the same pair is no mirror,
  // and the mirror about x is.
  EXPECT_FALSE(gtrack::compare_to_truth(m, truth, pose(0, 0, 100, -20, 0, 15, flat), Eigen::Vector3d::UnitX())
                   .tilt_mirror);
  const Eigen::Vector3d n = gtrack::rotation_from_euler_deg(20, 0, 15).col(2);
  const Eigen::Vector3d about_x(n.x(), -n.y(), -n.z());  // n turned by 180 deg about x
  const Eigen::Vector3d turned = gtrack::euler_deg_from_rotation(
      Eigen::Quaterniond::FromTwoVectors(n, about_x).toRotationMatrix() * gtrack::rotation_from_euler_deg(20, 0, 15));
  EXPECT_TRUE(gtrack::compare_to_truth(m, truth, pose(0, 0, 100, turned.x(), turned.y(), turned.z(), flat), Eigen::Vector3d::UnitX())
                  .tilt_mirror);

  // A pinhole's line of sight runs from its centre through the point; a
  // slice's (an affine projection) is the plane's normal everywhere.
  gtrack::Projection pinhole;
  pinhole.world_to_image << 1000, 0, 500, 0, 0, 1000, 500, 0, 0, 0, 1, 0;
  EXPECT_LT((gtrack::line_of_sight(pinhole, {1, 2, 100}) - Eigen::Vector3d(1, 2, 100).normalized()).norm(), 1e-9);
  gtrack::Projection slice;
  slice.world_to_image << 10, 0, 0, 5, 0, 0, 10, 7, 0, 0, 0, 1;  // images x and z: the plane y = const
  const Eigen::Vector3d d = gtrack::line_of_sight(slice, {3, 4, 5});
  EXPECT_NEAR(std::abs(d.y()), 1, 1e-12);

  // Over a sequence: the count, the share of the summed orientation error,
  // and the other frames' error. Frames 0-1 mirrored (40 deg each), 2 off
  // by 10 deg, 3 exact, 4 lost (not counted), 5 folded and on the other
  // branch (40 deg): two flat mirrors, three on the other branch.
  gtrack::PoseTable t, e;
  t.fingers = e.fingers = 6;
  for (int f = 0; f < 5; ++f) t.rows.push_back(row(f, truth));
  t.rows.push_back(row(5, folded_truth));
  e.rows = {row(0, pose(0, 0, 100, -20, 0, 15, flat)), row(1, pose(0, 0, 100, -20, 0, 15, flat)),
            row(2, pose(0, 0, 100, 30, 0, 15, flat)), row(3, truth), row(4, truth, "lost"), row(5, folded_other)};
  const auto ev = gtrack::evaluate(m, t, e);
  EXPECT_EQ(ev.tilt_mirror_frames, 2);
  EXPECT_NEAR(ev.tilt_mirror_orientation_share, 80.0 / 130.0, 1e-6);
  EXPECT_EQ(ev.orientation_without_tilt_mirror_deg.count, 3);
  EXPECT_NEAR(ev.orientation_without_tilt_mirror_deg.mean, 50.0 / 3, 1e-6);
  EXPECT_EQ(ev.tilt_branch_frames, 3);
  EXPECT_NEAR(ev.tilt_branch_orientation_share, 120.0 / 130.0, 1e-6);
  EXPECT_NEAR(ev.in_view.orientation_deg.mean, 26, 1e-6) << "the headline error is unchanged";
  const std::string json = gtrack::evaluation_json(ev);
  EXPECT_NE(json.find("\"tilt_mirror\": {\"frames\": 2"), std::string::npos);
  EXPECT_NE(json.find("\"tilt_branch\": {\"frames\": 3"), std::string::npos);
}

// Depth is along the sensor's viewing axis and in-plane across it, whatever
// the sensor's orientation: a camera looking down world z splits a position
// error into z and x-y; an ultrasound slice turned to image world x and z
// has its depth (across the slice) along world y.
TEST(Evaluation, DepthIsAlongTheSensorsViewingAxis) {
  gtrack::Projection pinhole;
  pinhole.world_to_image << 1000, 0, 500, 0, 0, 1000, 500, 0, 0, 0, 1, 0;
  EXPECT_LT((gtrack::viewing_axis(pinhole) - Eigen::Vector3d::UnitZ()).norm(), 1e-12);
  gtrack::Projection slice;
  slice.world_to_image << 10, 0, 0, 5, 0, 0, 10, 7, 0, 0, 0, 1;  // images x and z: the plane y = const
  const Eigen::Vector3d axis = gtrack::viewing_axis(slice);
  EXPECT_NEAR(std::abs(axis.y()), 1, 1e-12);

  auto g = make_gripper("plugin = \"hydrogel_six_finger\"");
  const auto& m = g->model();
  Eigen::VectorXd truth = Eigen::VectorXd::Zero(m.dims());
  truth[2] = 30;
  Eigen::VectorXd across = truth, within = truth;
  across[1] += 0.2;   // 200 um across the slice
  within[2] += 0.2;   // 200 um down the image
  const auto a = gtrack::compare_to_truth(m, truth, across, axis, axis);
  EXPECT_NEAR(a.depth_um, 200, 1e-6);
  EXPECT_NEAR(a.inplane_um, 0, 1e-6);
  const auto w = gtrack::compare_to_truth(m, truth, within, axis, axis);
  EXPECT_NEAR(w.depth_um, 0, 1e-6);
  EXPECT_NEAR(w.inplane_um, 200, 1e-6);
  // The camera's split, the default.
  const auto z = gtrack::compare_to_truth(m, truth, within);
  EXPECT_NEAR(z.depth_um, 200, 1e-6);
  EXPECT_NEAR(z.inplane_um, 0, 1e-6);
  // The endpoints, likewise: a shift across the slice moves each by 200 um
  // in 3D and not at all within the imaging plane.
  EXPECT_NEAR(a.endpoint_um, 200, 1e-6);
  EXPECT_NEAR(a.endpoint_inplane_um, 0, 1e-6);
  EXPECT_NEAR(w.endpoint_inplane_um, 200, 1e-6);
}

// An estimate 500 um across an ultrasound slice from the truth, which the
// slice's image does not show, is off track in 3D and on track within the
// imaging plane, as EvalOptions::off_track_in_plane judges it.
TEST(Evaluation, OffTrackWithinTheImagingPlaneLeavesOutTheAcrossPlaneOffset) {
  auto g = make_gripper("plugin = \"hydrogel_six_finger\"");
  const auto& m = g->model();
  const Eigen::VectorXd h = pose(0, 0, 100, 0, 0, 0, {0, 0, 0, 0, 0, 0});
  Eigen::VectorXd deeper = h;
  deeper[2] += 0.5;  // along the camera's axis, standing in for the slice's normal
  gtrack::PoseTable truth, est;
  truth.fingers = est.fingers = 6;
  for (int f = 0; f < 3; ++f) truth.rows.push_back(row(f, h));
  est.rows = {row(0, h), row(1, deeper), row(2, deeper)};
  gtrack::EvalOptions in_3d, in_plane;
  in_plane.off_track_in_plane = true;
  EXPECT_EQ(gtrack::evaluate(m, truth, est, in_3d).off_track_frames, 2);
  EXPECT_EQ(gtrack::evaluate(m, truth, est, in_plane).off_track_frames, 0);
}

TEST(Evaluation, LostMissingAndOutOfViewFramesAreCountedNotDropped) {
  auto g = make_gripper("plugin = \"hydrogel_six_finger\"");
  const auto& m = g->model();
  const Eigen::VectorXd h = pose(0, 0, 100, 0, 0, 0, {0, 0, 0, 0, 0, 0});
  Eigen::VectorXd far = h;
  far[0] += 1.5;  // well off the gripper
  gtrack::PoseTable truth, est;
  truth.fingers = est.fingers = 6;
  // Frames 0-1 tracked, 2 lost, 3 missing, 4-5 out of view, 6-7 back in view
  // but off track, 8 on track again.
  for (int f = 0; f < 9; ++f) truth.rows.push_back(row(f, h, "", (f == 4 || f == 5) ? 0.0 : 1.0));
  Eigen::VectorXd near10 = h, near20 = h;
  near10[0] += 0.010;  // 10 um off
  near20[1] += 0.020;  // 20 um off
  est.rows = {row(0, h), row(1, near10), row(2, h, "lost"), row(4, h, "lost"), row(5, h, "lost"),
              row(6, far), row(7, h, "lost"), row(8, near20)};
  const auto ev = gtrack::evaluate(m, truth, est);
  EXPECT_EQ(ev.frames, 9);
  EXPECT_EQ(ev.out_of_view_frames, 2);
  EXPECT_EQ(ev.in_view_frames, 7);
  EXPECT_EQ(ev.missing_frames, 1);
  EXPECT_EQ(ev.lost_frames, 5);           // 2, 3 (missing), 4, 5, 7
  EXPECT_EQ(ev.lost_in_view_frames, 3);   // 2, 3, 7
  EXPECT_EQ(ev.evaluated_frames, 4);      // 0, 1, 6, 8
  EXPECT_EQ(ev.off_track_frames, 1);      // 6
  ASSERT_EQ(ev.recovery.size(), 1u);
  EXPECT_EQ(ev.recovery[0].returned_at, 6);
  EXPECT_EQ(ev.recovery[0].frames_to_recover, 2);
  EXPECT_TRUE(ev.recovery[0].recovered);
  EXPECT_EQ(ev.frames_lost_after_return, 2);
  // The same rows in another order (a table put together by hand): the
  // same return and recovery, the frames in order.
  gtrack::PoseTable shuffled_truth = truth, shuffled_est = est;
  std::reverse(shuffled_truth.rows.begin(), shuffled_truth.rows.end());
  std::rotate(shuffled_est.rows.begin(), shuffled_est.rows.begin() + 3, shuffled_est.rows.end());
  const auto again = gtrack::evaluate(m, shuffled_truth, shuffled_est);
  ASSERT_EQ(again.recovery.size(), 1u);
  EXPECT_EQ(again.recovery[0].returned_at, 6);
  EXPECT_EQ(again.recovery[0].frames_to_recover, 2);
  EXPECT_EQ(again.per_frame.front().frame, 0);
  EXPECT_EQ(again.per_frame.back().frame, 8);
  // In-plane errors of the evaluated frames 0, 1, 6, 8: 0, 10, 1500, 20 um.
  EXPECT_NEAR(ev.in_view.position_inplane_um.mean, 382.5, 1e-6);
  EXPECT_NEAR(ev.in_view.position_inplane_um.median, 15, 1e-6);
  EXPECT_NEAR(ev.in_view.position_inplane_um.max, 1500, 1e-6);
  const std::string json = gtrack::evaluation_json(ev);
  EXPECT_NE(json.find("\"median\": "), std::string::npos);
  for (const char* key : {"\"position_um\"", "\"position_inplane_um\"", "\"depth_um\"", "\"orientation_deg\"",
                          "\"joint_deg\"", "\"endpoint_um\"", "\"lost_frames\": 5", "\"recovery\""}) {
    EXPECT_NE(json.find(key), std::string::npos) << key;
  }
}

// An estimate far enough away that its errors overflow is scored as far
// away, never as the default of a perfect match.
TEST(Evaluation, AnOverflowingErrorIsNotReportedAsZero) {
  auto g = make_gripper("plugin = \"hydrogel_six_finger\"");
  const auto& m = g->model();
  const Eigen::VectorXd truth = pose(0, 0, 100, 0, 0, 0, {10, 10, 10, 10, 10, 10});
  Eigen::VectorXd est = truth;
  est[0] = 1e200;
  const auto e = gtrack::compare_to_truth(m, truth, est);
  EXPECT_FALSE(e.position_um < 1e9) << e.position_um;
  EXPECT_FALSE(e.endpoint_um < 1e9) << e.endpoint_um;
}

// The message with which a table of `text` is refused ("" if it is read).
std::string refusal(const std::filesystem::path& file, const std::string& text, bool truth = false) {
  std::ofstream(file) << text;
  try {
    truth ? gtrack::read_truth_table(file) : gtrack::read_pose_table(file);
  } catch (const gtrack::InputError& e) {
    return e.what();
  }
  return "";
}

TEST(PoseTable, ReadsByHeaderAndReportsBadRows) {
  const auto dir = std::filesystem::temp_directory_path() / "gtrack_eval_test";
  std::filesystem::create_directories(dir);
  {
    std::ofstream f(dir / "ok.csv");
    f << "frame,x_mm,y_mm,z_mm,rx_deg,ry_deg,rz_deg,q1_deg,q2_deg,cost,status,ms\n"
         "0,1,2,3,4,5,6,7,8,0.1,ok,3\n"
         "1,1,2,3,4,5,6,7,8,0.9,lost,3\n";
  }
  const auto t = gtrack::read_pose_table(dir / "ok.csv");
  EXPECT_EQ(t.fingers, 2);
  ASSERT_EQ(t.rows.size(), 2u);
  EXPECT_EQ(t.rows[1].status, "lost");
  EXPECT_DOUBLE_EQ(t.rows[0].h[7], 8);
  EXPECT_DOUBLE_EQ(t.rows[0].extra.at("cost"), 0.1);
  const std::string header = "frame,x_mm,y_mm,z_mm,rx_deg,ry_deg,rz_deg,q1_deg";
  const std::string bad = refusal(dir / "bad.csv", header + "\n0,1,2,3,4,5,6,7\n1,1,two,3,4,5,6,7\n");
  EXPECT_NE(bad.find("bad.csv:3"), std::string::npos) << bad;
  EXPECT_NE(bad.find("y_mm"), std::string::npos) << bad;
  // An estimate may be lost (null); a ground truth may not, or every mean
  // over it would come out NaN.
  const std::string truth_text = header + "\n0,1,2,3,4,5,6,7\n1,1,2,3,4,5,6,7\n2,1,2,3,4,5,6,nan\n";
  EXPECT_EQ(refusal(dir / "truth.csv", truth_text), "");
  EXPECT_EQ(gtrack::read_pose_table(dir / "truth.csv").rows.size(), 3u);
  EXPECT_NE(refusal(dir / "truth.csv", truth_text, true).find("truth.csv:4: expected a finite number for 'q1_deg'"),
            std::string::npos);
  // A byte-order mark before the header is skipped; a row that says it is
  // tracked but has no configuration is refused (only a lost one may).
  EXPECT_EQ(refusal(dir / "bom.csv", "\xEF\xBB\xBF" + header + ",status\n0,1,2,3,4,5,6,7,ok\n1,nan,nan,nan,nan,nan,nan,nan,lost\n"),
            "");
  EXPECT_EQ(gtrack::read_pose_table(dir / "bom.csv").rows.size(), 2u);
  // gtrack's own writers put "null" for a value that is no number: read back as nan.
  EXPECT_EQ(refusal(dir / "null.csv", header + ",status,cost\n0,1,2,3,4,5,6,7,ok,null\n1,null,null,null,null,null,"
                                               "null,null,lost,0.5\n"),
            "");
  const auto nulls = gtrack::read_pose_table(dir / "null.csv");
  ASSERT_EQ(nulls.rows.size(), 2u);
  EXPECT_TRUE(std::isnan(nulls.rows[0].extra.at("cost")));
  EXPECT_TRUE(std::isnan(nulls.rows[1].h[0]));
  const std::string nan_ok = refusal(dir / "nan_ok.csv", header + ",status\n0,1,2,3,4,5,6,7,ok\n1,1,2,nan,4,5,6,7,ok\n");
  EXPECT_NE(nan_ok.find("nan_ok.csv:3: expected a finite number for 'z_mm' in a row whose status is ok"),
            std::string::npos)
      << nan_ok;
  // A value no micro-gripper pose can have is refused by name and line.
  const std::string far = refusal(dir / "far.csv", header + "\n0,1,2,3,4,5,6,7\n1,1e200,2,3,4,5,6,7\n");
  EXPECT_NE(far.find("far.csv:3: 'x_mm' = 1e200 is not a plausible pose value"), std::string::npos) << far;
  std::filesystem::remove_all(dir);
}

}  // namespace
