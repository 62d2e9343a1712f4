// The articulated model against hand-computed geometry (hydrogel gripper).
#include <gtest/gtest.h>

#include <cmath>

#include "support/plugins.hpp"

using gtrack::testing::make_gripper;

namespace {

Eigen::VectorXd hyp(std::initializer_list<double> pose, double q) {
  Eigen::VectorXd h(12);
  int i = 0;
  for (double v : pose) h[i++] = v;
  for (; i < 12; ++i) h[i] = q;
  return h;
}

TEST(HydrogelModel, HasThePapersShape) {
  auto g = make_gripper("plugin = \"hydrogel_six_finger\"");
  const auto& m = g->model();
  EXPECT_EQ(m.triangles(), 46);
  EXPECT_EQ(m.dims(), 12);
  EXPECT_EQ(m.fingers(), 6);
  EXPECT_EQ(m.geometry().symmetry_order, 6);
  // 4 mm tip to tip when open.
  auto tips = m.fingertips(hyp({0, 0, 0, 0, 0, 0}, 0));
  EXPECT_NEAR((tips[0] - tips[3]).norm(), 4.0, 1e-9);
  EXPECT_NEAR(m.radius_mm(), 2.0, 1e-9);
}

TEST(HydrogelModel, FingertipsMatchHandComputedValues) {
  auto g = make_gripper("plugin = \"hydrogel_six_finger\"");
  const auto& m = g->model();
  // Open: tips on a 2 mm circle every 60 degrees.
  auto tips = m.fingertips(hyp({0, 0, 0, 0, 0, 0}, 0));
  for (int f = 0; f < 6; ++f) {
    const double a = f * M_PI / 3;
    EXPECT_NEAR(tips[f].x(), 2.0 * std::cos(a), 1e-9);
    EXPECT_NEAR(tips[f].y(), 2.0 * std::sin(a), 1e-9);
    EXPECT_NEAR(tips[f].z(), 0.0, 1e-12);
  }
  // q = 90: links at 90, 180, 270, 360 deg: the tip ends 0.05 mm inside the
  // palm edge (0.65 - 0.35 + 0.30), back in the palm plane.
  tips = m.fingertips(hyp({0, 0, 0, 0, 0, 0}, 90));
  EXPECT_NEAR(tips[0].x(), 0.60, 1e-9);
  EXPECT_NEAR(tips[0].z(), 0.0, 1e-9);
  // q = 30 with a pose: r = 0.35(cos30+cos60+cos90) + 0.30 cos120,
  // z = 0.35(sin30+sin60+sin90) + 0.30 sin120; rotated by rz = 90, moved by (1, 2, 50).
  tips = m.fingertips(hyp({1, 2, 50, 0, 0, 90}, 30));
  const double r = 0.65 + 0.35 * (std::sqrt(3) / 2 + 0.5 + 0) + 0.30 * -0.5;
  const double z = 0.35 * (0.5 + std::sqrt(3) / 2 + 1) + 0.30 * std::sqrt(3) / 2;
  EXPECT_NEAR(tips[0].x(), 1.0, 1e-9);
  EXPECT_NEAR(tips[0].y(), 2.0 + r, 1e-9);
  EXPECT_NEAR(tips[0].z(), 50.0 + z, 1e-9);
  // Fingers fold towards +Z of the model: with rx = 180 they fold towards -Z.
  tips = m.fingertips(hyp({0, 0, 10, 180, 0, 0}, 30));
  EXPECT_NEAR(tips[0].z(), 10.0 - z, 1e-9);
}

TEST(HydrogelModel, PoseMatchesEndpointsAndEuler) {
  auto g = make_gripper("plugin = \"hydrogel_six_finger\"");
  const auto& m = g->model();
  Eigen::VectorXd h = hyp({0.3, -0.2, 40, 20, -35, 110}, 25);
  std::vector<Eigen::Vector3d> verts;
  m.pose(h, verts);
  ASSERT_EQ(verts.size(), 46u * 3);
  // Every vertex is at the same distance from the palm centre as in the model frame.
  std::vector<Eigen::Vector3d> local;
  m.pose_model(std::span<const double>(h.data() + 6, 6), local);
  for (size_t i = 0; i < verts.size(); ++i) {
    EXPECT_NEAR((verts[i] - h.head<3>()).norm(), local[i].norm(), 1e-9);
  }
  // Euler round trip.
  Eigen::Matrix3d R = gtrack::rotation_from_euler_deg(20, -35, 110);
  Eigen::Vector3d e = gtrack::euler_deg_from_rotation(R);
  EXPECT_NEAR(e.x(), 20, 1e-9);
  EXPECT_NEAR(e.y(), -35, 1e-9);
  EXPECT_NEAR(e.z(), 110, 1e-9);
}

TEST(HydrogelModel, SymmetricEquivalentDescribesTheSameShape) {
  auto g = make_gripper("plugin = \"hydrogel_six_finger\"");
  const auto& m = g->model();
  Eigen::VectorXd h(12);
  h << 0.1, 0.2, 30, 15, -20, 40, 5, 10, 20, 30, 40, 50;
  for (int k = 1; k < 6; ++k) {
    Eigen::VectorXd e = m.symmetric_equivalent(h, k);
    EXPECT_GT((e - h).norm(), 1.0);
    // Same set of fingertips.
    auto a = m.fingertips(h), b = m.fingertips(e);
    for (const auto& p : a) {
      double best = 1e9;
      for (const auto& q : b) best = std::min(best, (p - q).norm());
      EXPECT_LT(best, 1e-9) << "k=" << k;
    }
    // Every phalanx endpoint too (the finger carrying the same joint value lands there).
    auto ea = m.link_endpoints(h), eb = m.link_endpoints(e);
    for (const auto& p : ea) {
      double best = 1e9;
      for (const auto& q : eb) best = std::min(best, (p - q).norm());
      EXPECT_LT(best, 1e-9) << "k=" << k;
    }
  }
}

TEST(HydrogelModel, KinematicPenaltyFollowsTheRules) {
  auto g = make_gripper("plugin = \"hydrogel_six_finger\"\nmax_adjacent_difference_deg = 40");
  std::vector<double> ok{10, 20, 30, 40, 50, 60};  // neighbours differ by 10, but fingers 6 and 1 by 50
  std::vector<double> fine{30, 30, 30, 30, 30, 30};
  EXPECT_EQ(g->kinematic_penalty(fine), 0.0);
  EXPECT_GT(g->kinematic_penalty(ok), 0.0);  // fingers 6 and 1 differ by 50 > 40
  std::vector<double> beyond{85, 85, 85, 85, 85, 85};  // above joint_max 80, over the range [0, 80]
  EXPECT_NEAR(g->kinematic_penalty(beyond), 6 * 5.0 / 80.0, 1e-12);
  std::vector<double> backwards{-4, 0, 0, 0, 0, 0};  // below joint_min 0: a finger folded the wrong way
  EXPECT_NEAR(g->kinematic_penalty(backwards), 4.0 / 80.0, 1e-12);
}

TEST(HydrogelModel, ConfigOverridesAreValidated) {
  EXPECT_THROW(make_gripper("plugin = \"hydrogel_six_finger\"\nlink_widths_mm = [1, 2]"), gtrack::ConfigError);
  EXPECT_THROW(make_gripper("plugin = \"hydrogel_six_finger\"\njoint_min_deg = 50\njoint_max_deg = 40"),
               gtrack::ConfigError);
  // Another number of links needs its widths: the built-in ones are for four.
  try {
    make_gripper("plugin = \"hydrogel_six_finger\"\nlink_lengths_mm = [0.5, 0.5]");
    ADD_FAILURE() << "two links without their widths were accepted";
  } catch (const gtrack::ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("key 'link_widths_mm': missing; link_lengths_mm gives 2 links"),
              std::string::npos)
        << e.what();
  }
  // A link 0 wide at both ends is named by the widths' key, not the plugin.
  try {
    make_gripper("plugin = \"hydrogel_six_finger\"\nlink_widths_mm = [0.3, 0, 0, 0, 0]");
    ADD_FAILURE() << "links without width were accepted";
  } catch (const gtrack::ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("key 'link_widths_mm': link 2 is 0 wide at both ends"), std::string::npos)
        << e.what();
  }
  auto g = make_gripper("plugin = \"hydrogel_six_finger\"\nlink_lengths_mm = [0.5, 0.5]\nlink_widths_mm = [0.5, 0.4, 0]");
  EXPECT_EQ(g->model().triangles(), 4 + 6 * 3);
  // Limits that leave out the built-in open and folded joints (0 and 60):
  // those are brought within them, as the tracker and synth start there.
  for (const char* metal : {"hydrogel_six_finger", "metallic_six_finger", "metallic_two_finger"}) {
    SCOPED_TRACE(metal);
    const auto limited = make_gripper(std::string("plugin = \"") + metal + "\"\njoint_min_deg = 20\njoint_max_deg = 50");
    EXPECT_EQ(limited->model().geometry().unfolded_deg, 20);
    EXPECT_EQ(limited->model().geometry().folded_deg, 50);
  }
}

}  // namespace

// A link whose length or widths are not positive finite numbers is refused
// naming the finger and the link; a NaN width had passed every comparison.
TEST(Model, ALinkThatIsNoNumberIsRefusedNamingIt) {
  const auto geometry = [](double length, double width) {
    gtrack::GripperGeometry g;
    g.name = "lab";
    g.palm_mm = {{-1, -1}, {1, -1}, {1, 1}, {-1, 1}};
    gtrack::FingerShape f;
    f.base_mm = {1, 0};
    f.links = {{0.5, 0.2, 0.2}, {length, width, 0.1}};
    g.fingers = {f, f};
    g.fingers[1].base_mm = {-1, 0};
    g.fingers[1].direction_deg = 180;
    return g;
  };
  EXPECT_NO_THROW(gtrack::ArticulatedModel(geometry(0.5, 0.2)));
  const auto error = [](const gtrack::GripperGeometry& g) {
    try {
      gtrack::ArticulatedModel m(g);
    } catch (const gtrack::Error& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  EXPECT_EQ(error(geometry(std::nan(""), 0.2)),
            "gripper 'lab': finger 1, link 2: length nan mm; expected a positive finite number");
  EXPECT_EQ(error(geometry(0.5, std::nan(""))),
            "gripper 'lab': finger 1, link 2: widths nan and 0.1 mm; expected finite numbers, neither negative nor "
            "both 0");
  EXPECT_NE(error(geometry(0.5, -0.1)).find("link 2: widths -0.1 and 0.1 mm"), std::string::npos);
  // A compiled gripper is held to what a model file is: a finger floating
  // off the palm, a reference fold past the joints' limits and an adjacent
  // pair of no finger are refused, naming what is wrong.
  gtrack::GripperGeometry floating = geometry(0.5, 0.2);
  floating.fingers[0].base_mm = {1.8, 0};
  EXPECT_EQ(error(floating), "gripper 'lab': finger 1's base [1.8, 0] is 0.8 mm off the palm's outline; expected its "
                             "first hinge on it");
  gtrack::GripperGeometry bent = geometry(0.5, 0.2);
  bent.joint_max_deg = 90;
  bent.folded_deg = 200;
  EXPECT_EQ(error(bent), "gripper 'lab': folded_deg is 200, outside the joint limits [0, 90]; expected a fold the "
                         "joints can take");
  gtrack::GripperGeometry paired = geometry(0.5, 0.2);
  paired.collision.adjacent = {{0, 5}};
  EXPECT_EQ(error(paired), "gripper 'lab': the adjacent pair (0, 5) names a finger that does not exist; expected "
                           "finger indices 0 to 1 (CollisionRule::adjacent counts from 0)");
}
