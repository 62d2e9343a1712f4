// The loader: one error per way a plugin can be wrong, and object lifetime.
#include <gtest/gtest.h>

#include <boost/dll/shared_library.hpp>
#include <dlfcn.h>
#include <filesystem>
#include <fstream>
#include <map>
#include <optional>
#include <vector>
#include <gtrack/error.hpp>
#include <gtrack/plugin_loader.hpp>
#include <gtrack/setup.hpp>

#include "support/logged.hpp"
#include "support/plugins.hpp"
#include "support/scoped_env.hpp"

namespace fs = std::filesystem;

namespace {

const fs::path kFixtures = GTRACK_TEST_FIXTURE_DIR;

std::string plugin_error(const std::function<void()>& f) {
  try {
    f();
  } catch (const gtrack::PluginError& e) {
    return e.what();
  } catch (const gtrack::Error& e) {
    return std::string("other gtrack error: ") + e.what();
  }
  return "";
}

gtrack::ConfigTable table(const std::string& name, const std::string& section = "sensor") {
  auto root = gtrack::ConfigTable::parse("[" + section + "]\nplugin = \"" + name + "\"\n", "t.toml");
  return root.table(section);
}

TEST(PluginLoader, DiscoversTheBuiltInPlugins) {
  gtrack::PluginLoader loader;
  auto records = loader.discover();
  std::map<std::string, gtrack::PluginKind> found;
  for (const auto& r : records) found[r.name] = r.kind;
  EXPECT_EQ(found.at("pinhole_microscope"), gtrack::PluginKind::Sensor);
  EXPECT_EQ(found.at("hydrogel_six_finger"), gtrack::PluginKind::Gripper);
  EXPECT_EQ(found.at("temperature_hysteresis"), gtrack::PluginKind::Stimulus);
  for (const auto& r : records) EXPECT_TRUE(fs::exists(r.file)) << r.file;
}

// A stimulus plugin's results are checked as the tracker takes them: a NaN
// penalty had made frames "ok" with no cost, a range upside down had
// clamped the joints to nothing; each is now a PluginError naming the
// plugin, the call and what was expected.
TEST(PluginLoader, AStimulusPluginsUnusableResultsAreRefusedNamingIt) {
  gtrack::PluginLoader loader({kFixtures});
  const auto made = [&](const std::string& wrong) {
    auto root = gtrack::ConfigTable::parse(
        "[stimulus]\nplugin = \"fixture_wrong_stimulus\"\nwrong = \"" + wrong + "\"\n", "t.toml");
    return loader.make_stimulus(root.table("stimulus"));
  };
  const std::vector<double> joints{10, 20};
  // Named with its file.
  const std::string plugin = "stimulus plugin 'fixture_wrong_stimulus' (" +
                             (kFixtures / "libgtrack_fixture_wrong_stimulus.so").string() + "): ";
  EXPECT_EQ(plugin_error([&] { made("nan_penalty")->penalty(joints); }),
            plugin + "penalty() returned nan; expected a finite number, 0 or more");
  EXPECT_EQ(plugin_error([&] { made("range_upside_down")->state(); }),
            plugin + "state() returned a feasible joint range of 60 to 10 deg; expected feasible_min_deg <= "
                     "feasible_max_deg, neither nan");
  EXPECT_EQ(plugin_error([&] { made("fold_fraction")->fold_fraction(); }),
            plugin + "fold_fraction() returned 1.5; expected a number in [0, 1]");
  // Its own exception, likewise.
  EXPECT_EQ(plugin_error([&] { made("throws")->penalty(joints); }),
            plugin + "penalty() threw: calibration table not loaded");
  const auto right = made("nothing");
  EXPECT_EQ(plugin_error([&] {
              right->update(3.5, 0.1);
              EXPECT_EQ(right->state().value, 3.5);
              EXPECT_EQ(right->penalty(joints), 0.0);
              EXPECT_EQ(right->fold_fraction(), 0.5);
            }),
            "");
}

TEST(PluginLoader, NotFoundListsPathsAndAvailablePlugins) {
  gtrack::PluginLoader loader({"/nonexistent/dir"});
  std::string e = plugin_error([&] { loader.make_sensor(table("pinhole_microscop")); });
  EXPECT_NE(e.find("sensor plugin 'pinhole_microscop' not found"), std::string::npos) << e;
  EXPECT_NE(e.find("/nonexistent/dir"), std::string::npos) << e;
  EXPECT_NE(e.find("available sensor plugins: pinhole_microscope"), std::string::npos) << e;
  EXPECT_EQ(e.find("hydrogel"), std::string::npos) << "lists only plugins of the kind asked for: " << e;
  // A library of the name without gtrack's prefix (add_library instead of
  // gtrack_add_plugin) is pointed out.
  const fs::path dir = fs::temp_directory_path() / "gtrack_plugin_loader_test" / "unprefixed";
  fs::remove_all(dir);
  fs::create_directories(dir);
  fs::copy_file(kFixtures / "libgtrack_fixture_good_sensor.so", dir / "liblab_camera.so");
  gtrack::PluginLoader lab({dir});
  e = plugin_error([&] { lab.make_sensor(table("lab_camera")); });
  EXPECT_NE(e.find((dir / "liblab_camera.so").string() + " is there, but a plugin's file is named "
                   "libgtrack_lab_camera.so (gtrack_add_plugin names it so)"),
            std::string::npos)
      << e;
  fs::remove_all(dir);
}

TEST(PluginLoader, RefusesAnAbiMismatchBeforeCallingAnything) {
  gtrack::PluginLoader loader({kFixtures});
  // The fixture's factory aborts; reaching it would kill the test.
  std::string e = plugin_error([&] { loader.make_sensor(table("fixture_bad_abi")); });
  EXPECT_NE(e.find("plugin ABI version " + std::to_string(GTRACK_PLUGIN_ABI_VERSION + 41)), std::string::npos) << e;
  EXPECT_NE(e.find("this gtrack's plugin ABI version " + std::to_string(GTRACK_PLUGIN_ABI_VERSION)),
            std::string::npos)
      << e;
}

TEST(PluginLoader, RefusesAnInfoRecordOfAnotherLayout) {
  gtrack::PluginLoader loader({kFixtures});
  std::string e = plugin_error([&] { loader.make_sensor(table("fixture_bad_size")); });
  EXPECT_NE(e.find("info record has size"), std::string::npos) << e;
}

TEST(PluginLoader, NotAGtrackPlugin) {
  gtrack::PluginLoader loader({kFixtures});
  std::string e = plugin_error([&] { loader.make_sensor(table("fixture_not_a_plugin")); });
  EXPECT_NE(e.find("not a gtrack plugin"), std::string::npos) << e;
}

// Both exports are pointers held in variables; a null one is refused before
// it is dereferenced, by load and by discovery alike.
TEST(PluginLoader, RefusesANullInfoPointer) {
  gtrack::PluginLoader loader({kFixtures});
  std::string e = plugin_error([&] { loader.make_sensor(table("fixture_null_info")); });
  EXPECT_NE(e.find("its gtrack_plugin_info is a null pointer"), std::string::npos) << e;
  for (const auto& r : loader.discover()) EXPECT_NE(r.name, "fixture_null_info");
}

TEST(PluginLoader, NamesTheMissingFactory) {
  gtrack::PluginLoader loader({kFixtures});
  std::string e = plugin_error([&] { loader.make_sensor(table("fixture_no_create")); });
  EXPECT_NE(e.find("it exports no gtrack_plugin_create"), std::string::npos) << e;
}

TEST(PluginLoader, WrongKind) {
  gtrack::PluginLoader loader({kFixtures});
  std::string e = plugin_error([&] { loader.make_gripper(table("fixture_wrong_kind", "gripper")); });
  EXPECT_NE(e.find("is a sensor plugin; [gripper] needs a gripper plugin"), std::string::npos) << e;
  EXPECT_EQ(e.rfind("t.toml:2: key 'gripper.plugin': ", 0), 0u) << "starts where the config names it: " << e;
}

TEST(PluginLoader, FactoryThrowsGivesItsMessage) {
  gtrack::PluginLoader loader({kFixtures});
  std::string e = plugin_error([&] { loader.make_sensor(table("fixture_throwing_factory")); });
  EXPECT_NE(e.find("could not be created: calibration file missing"), std::string::npos) << e;
}

TEST(PluginLoader, AnErrorThrownByAPluginsMethodOutlivesItsLastInstance) {
  // The instance, the last owner of its library, goes while the stack
  // unwinds; the catch block then reads and destroys an exception whose
  // code is the plugin's.
  std::string caught;
  try {
    gtrack::PluginLoader loader({kFixtures});
    auto sensor = loader.make_sensor(table("fixture_throwing_later"));
    (void)sensor->mm_per_pixel();
  } catch (const gtrack::Error& e) {
    caught = e.what();
  }
  EXPECT_EQ(caught, "fixture_throwing_later: reading 3 is bad");
}

TEST(PluginLoader, CannotLoadIsReported) {
  const fs::path dir = fs::temp_directory_path() / "gtrack_loader_test";
  fs::create_directories(dir);
  { std::ofstream(dir / "libgtrack_garbage.so") << "not an ELF file"; }
  gtrack::PluginLoader loader({dir});
  std::string e = plugin_error([&] { loader.make_sensor(table("garbage")); });
  EXPECT_NE(e.find("cannot load library"), std::string::npos) << e;
  // Discovery skips it rather than failing.
  EXPECT_NO_THROW(loader.discover());
}

// A library whose file name is not libgtrack_<its declared name>.so can never
// be loaded by name: discovery skips it instead of listing a name that fails.
TEST(PluginLoader, DiscoverySkipsALibraryNamedOtherwise) {
  const fs::path dir = fs::temp_directory_path() / "gtrack_loader_renamed";
  fs::remove_all(dir);
  fs::create_directories(dir);
  fs::copy_file(kFixtures / "libgtrack_fixture_good_sensor.so", dir / "libgtrack_renamed.so");
  gtrack::PluginLoader loader({dir});
  for (const auto& r : loader.discover()) {
    EXPECT_NE(r.name, "fixture_good_sensor");
    EXPECT_NE(r.name, "renamed");
  }
  const std::string e = plugin_error([&] { loader.make_sensor(table("renamed")); });
  EXPECT_NE(e.find("declares the plugin name 'fixture_good_sensor', expected 'renamed'"), std::string::npos) << e;
  // The same library under its own name is listed.
  fs::copy_file(kFixtures / "libgtrack_fixture_good_sensor.so", dir / "libgtrack_fixture_good_sensor.so");
  bool listed = false;
  for (const auto& r : loader.discover()) listed = listed || r.name == "fixture_good_sensor";
  EXPECT_TRUE(listed);
  fs::remove_all(dir);
}

// A skipped library named as a built-in plugin's file stands ahead of it on
// the search path: the built-in one is listed, and said to be out of a
// run's reach, as the run fails on the skipped file.
TEST(PluginLoader, DiscoverySaysWhenASkippedLibraryHidesAListedOne) {
  const fs::path dir = fs::temp_directory_path() / "gtrack_loader_hiding";
  fs::remove_all(dir);
  fs::create_directories(dir);
  fs::copy_file(kFixtures / "libgtrack_fixture_good_sensor.so", dir / "libgtrack_hydrogel_six_finger.so");
  gtrack::PluginLoader loader({dir});
  bool listed = false;
  const std::string said = gtrack::testing::logged([&] {
    for (const auto& r : loader.discover()) listed = listed || r.name == "hydrogel_six_finger";
  });
  EXPECT_TRUE(listed);
  EXPECT_NE(said.find("gripper plugin 'hydrogel_six_finger' is listed from "), std::string::npos) << said;
  EXPECT_NE(said.find("but a run takes " + (dir / "libgtrack_hydrogel_six_finger.so").string() +
                      " ahead of it, and fails; remove or rename that file"),
            std::string::npos)
      << said;
  const std::string e = plugin_error([&] { loader.make_gripper(table("hydrogel_six_finger", "gripper")); });
  EXPECT_NE(e.find((dir / "libgtrack_hydrogel_six_finger.so").string() + ": plugin 'fixture_good_sensor' is a sensor"),
            std::string::npos)
      << e;
  // Without it, nothing is said.
  fs::remove(dir / "libgtrack_hydrogel_six_finger.so");
  const std::string quiet = gtrack::testing::logged([&] { loader.discover(); });
  EXPECT_EQ(quiet.find("is listed from"), std::string::npos) << quiet;
  fs::remove_all(dir);
}

// A sensor whose projection is not of its image's size (Projection::size
// left unset) is refused when the setup is loaded, naming both sizes.
TEST(PluginLoader, ASensorWhoseProjectionIsOfAnotherSizeIsRefused) {
  gtrack::SetupOptions o;
  o.plugin_paths = {kFixtures};
  o.with_stimulus = false;
  const std::string gripper = "[gripper]\nplugin = \"hydrogel_six_finger\"\n";
  EXPECT_NO_THROW(gtrack::load_setup(
      gtrack::ConfigTable::parse("[sensor]\nplugin = \"fixture_good_sensor\"\n" + gripper, "lab.toml"), o));
  try {
    gtrack::load_setup(gtrack::ConfigTable::parse(
                           "[sensor]\nplugin = \"fixture_good_sensor\"\nprojection_size = 0\n" + gripper, "lab.toml"),
                       o);
    ADD_FAILURE() << "a projection of another size was taken";
  } catch (const gtrack::ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("lab.toml:2: key 'sensor.plugin': the sensor's projection().size is 0x0 "
                                         "and its image_size() 64x64; expected the same positive size"),
              std::string::npos)
        << e.what();
  }
  // Numbers the engine builds its search on that are not finite: the
  // plugin is named, not a key of the search box the config lacks.
  for (const auto& [key, said] : std::vector<std::pair<std::string, std::string>>{
           {"nan = \"mm_per_pixel\"", "the sensor plugin's mm_per_pixel() is nan; expected a positive number"},
           {"mm_per_pixel = 0.0", "the sensor plugin's mm_per_pixel() is 0; expected a positive number"},
           {"nan = \"nominal_position\"", "the sensor plugin's nominal_position_mm() is not finite"},
           {"nan = \"projection\"", "the sensor plugin's projection() holds a world_to_image that is not finite"},
           // Its calls that throw, and more clip planes than a renderer takes.
           {"throws = \"projection\"", "the sensor plugin's projection() threw: projection not calibrated"},
           {"throws = \"project\"", "the sensor plugin's project() threw: no lens model yet"},
           {"clip_planes = 9", "the sensor plugin's projection() has 9 clip planes; expected at most 8"},
           // A pixel size or a project() that is not the projection's: synth
           // had drawn blank frames, and the search box was sized wrong.
           {"mm_per_pixel = 50.0",
            "the sensor plugin's mm_per_pixel() is 50 mm, but projection() images 1 to 1 mm a pixel about "
            "nominal_position_mm(); expected the projection's pixel size"},
           {"project_turned = true",
            "the sensor plugin's project() and projection() disagree: the point (6.4, 0, 0) mm images at (-0.0, "
            "6.4) by project() and (6.4, 0.0) by projection(); expected the same pixel but for lens distortion"},
           {"nan = \"projection_row\"",
            "the sensor plugin's projection() images the world about nominal_position_mm() onto a line or a point "
            "(at 1 and 0 pixels per mm in its two directions); expected a world_to_image of rank 3"}}) {
    try {
      gtrack::load_setup(gtrack::ConfigTable::parse(
                             "[sensor]\nplugin = \"fixture_good_sensor\"\n" + key + "\n" + gripper, "lab.toml"),
                         o);
      ADD_FAILURE() << key << " was taken";
    } catch (const gtrack::ConfigError& e) {
      EXPECT_NE(std::string(e.what()).find("lab.toml:2: key 'sensor.plugin': " + said), std::string::npos)
          << e.what();
    }
  }
}

// A gripper plugin whose model() holds nothing (a default-constructed
// model) is refused when the setup is loaded, naming the plugin's key; it
// had drawn empty frames and failed later in the renderer.
TEST(PluginLoader, AGripperWithAnEmptyModelIsRefused) {
  gtrack::SetupOptions o;
  o.plugin_paths = {kFixtures};
  o.with_stimulus = false;
  try {
    gtrack::load_setup(gtrack::ConfigTable::parse("[sensor]\nplugin = \"fixture_good_sensor\"\n[gripper]\n"
                                                  "plugin = \"fixture_empty_gripper\"\n",
                                                  "lab.toml"),
                       o);
    ADD_FAILURE() << "an empty model was taken";
  } catch (const gtrack::ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("lab.toml:4: key 'gripper.plugin': the gripper plugin's model() has no "
                                         "fingers or no size"),
              std::string::npos)
        << e.what();
  }
}

TEST(PluginLoader, UnknownKeyInThePluginTable) {
  gtrack::PluginLoader loader({kFixtures});
  auto root = gtrack::ConfigTable::parse("[sensor]\nplugin = \"fixture_good_sensor\"\nsise = 3\n", "k.toml");
  try {
    loader.make_sensor(root.table("sensor"));
    FAIL() << "unknown key accepted";
  } catch (const gtrack::ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("k.toml:3: key 'sensor.sise'"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("did you mean 'size'"), std::string::npos) << e.what();
  }
}

TEST(PluginLoader, InstanceKeepsItsLibraryLoaded) {
  std::shared_ptr<gtrack::Sensor> sensor;
  {
    gtrack::PluginLoader loader({kFixtures});
    sensor = loader.make_sensor(table("fixture_good_sensor"));
  }
  // The loader is gone; the instance's code must still be mapped.
  EXPECT_EQ(sensor->image_size().width, 64);
  const fs::path lib = kFixtures / "libgtrack_fixture_good_sensor.so";
  EXPECT_TRUE(boost::dll::shared_library(lib, static_cast<boost::dll::load_mode::type>(RTLD_NOLOAD)).is_loaded());
  sensor.reset();
}

TEST(PluginLoader, SearchOrderPutsUserPathsFirst) {
  std::optional<gtrack::PluginLoader> loader;
  {
    const gtrack::testing::ScopedEnv env("GTRACK_PLUGIN_PATH", "/env/a:/env/b");
    loader.emplace(std::vector<fs::path>{"/user/1"});
  }
  loader->add_path("/config/2");
  const auto& p = loader->search_paths();
  ASSERT_EQ(p.size(), 5u);
  EXPECT_EQ(p[0], "/user/1");
  EXPECT_EQ(p[1], "/config/2");
  EXPECT_EQ(p[2], "/env/a");
  EXPECT_EQ(p[3], "/env/b");
  EXPECT_EQ(p[4], gtrack::default_plugin_dir());
  // A folder named again (the built-in one in GTRACK_PLUGIN_PATH, another
  // spelling of a user's) is searched once, at its first place.
  const fs::path here = fs::temp_directory_path() / "gtrack_search_once";
  fs::create_directories(here);
  {
    const gtrack::testing::ScopedEnv env("GTRACK_PLUGIN_PATH",
                                         (here / ".").string() + ":" + gtrack::default_plugin_dir().string());
    loader.emplace(std::vector<fs::path>{here, "/user/1", "/user/1"});
  }
  const auto& once = loader->search_paths();
  ASSERT_EQ(once.size(), 3u);
  EXPECT_EQ(once[0], here);
  EXPECT_EQ(once[1], "/user/1");
  EXPECT_EQ(once[2], gtrack::default_plugin_dir());
  fs::remove_all(here);
}

// A plugin found in an earlier folder is taken over one of the same name in
// a later one (a built-in), which is said once, and listed once.
TEST(PluginLoader, APluginThatSetsAnotherAsideIsSaidOnce) {
  const fs::path dir = fs::temp_directory_path() / "gtrack_shadowing_plugins";
  fs::remove_all(dir);
  fs::create_directories(dir);
  fs::copy_file(kFixtures / "libgtrack_fixture_good_sensor.so", dir / "libgtrack_fixture_good_sensor.so");
  gtrack::PluginLoader loader({dir, kFixtures});
  const std::string log = gtrack::testing::logged([&] {
    loader.make_sensor(table("fixture_good_sensor"));
    loader.make_sensor(table("fixture_good_sensor"));
  });
  int listed = 0;
  for (const auto& r : loader.discover()) listed += r.name == "fixture_good_sensor";
  const std::string said = "sensor plugin 'fixture_good_sensor' taken from " +
                           (dir / "libgtrack_fixture_good_sensor.so").string() + ", ahead of the one in " +
                           kFixtures.string();
  EXPECT_NE(log.find(said), std::string::npos) << log;
  EXPECT_EQ(log.find(said), log.rfind(said)) << "said once: " << log;
  EXPECT_EQ(listed, 1);
  // The same folder twice is no other plugin.
  const std::string again = gtrack::testing::logged(
      [&] { gtrack::PluginLoader({kFixtures, kFixtures}).make_sensor(table("fixture_good_sensor")); });
  EXPECT_EQ(again.find("ahead of"), std::string::npos) << again;
  fs::remove_all(dir);
}

}  // namespace

// A setup names each plugin it made with its file, as a run's errors do;
// one its loader did not make is named by its kind only.
TEST(PluginLoader, ASetupNamesItsPluginsWithTheirFiles) {
  const gtrack::Setup setup = gtrack::testing::small_microscope_setup();
  const std::string gripper = gtrack::plugin_label(setup, gtrack::PluginKind::Gripper);
  EXPECT_EQ(gripper.rfind("gripper plugin 'hydrogel_six_finger' (", 0), 0u) << gripper;
  EXPECT_NE(gripper.find("libgtrack_hydrogel_six_finger.so)"), std::string::npos) << gripper;
  gtrack::Setup by_hand;
  by_hand.gripper = setup.gripper;
  EXPECT_EQ(gtrack::plugin_label(by_hand, gtrack::PluginKind::Gripper), "gripper plugin");
}
