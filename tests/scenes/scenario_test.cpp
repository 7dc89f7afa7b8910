#include "scenes/scenario.h"

#include "core/error.h"
#include "scenes/world.h"
#include "test_util.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

namespace segslam::scenes {
namespace {

using testing::ScenarioPath;

// The error message of parsing `text`, or "" if it parsed.
std::string ParseError(const std::string& text) {
  try {
    ParseScenario(text, "my.yaml");
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

TEST(ScenarioTest, LoadsEveryScenarioFile) {
  int count = 0;
  for (const std::string dir : {"", "test"}) {
    for (const auto& entry : std::filesystem::directory_iterator(ScenarioPath(dir))) {
      if (entry.path().extension() != ".yaml") continue;
      SCOPED_TRACE(entry.path().string());
      const Scenario s = LoadScenario(entry.path());
      EXPECT_FALSE(s.name.empty());
      EXPECT_EQ(s.text.rfind("#", 0), 0u) << "scenario files start with a comment";
      ++count;
    }
  }
  EXPECT_GE(count, 10);
}

TEST(ScenarioTest, DefaultCityFileHasTheDocumentedValues) {
  const Scenario s = LoadScenario(ScenarioPath("city_street_grid.yaml"));
  EXPECT_EQ(s.kind, "city");
  EXPECT_DOUBLE_EQ(s.city.route_length_m, 200);
  EXPECT_EQ(s.city.parked_cars, 20);
  EXPECT_EQ(s.city.moving_cars, 6);
  EXPECT_EQ(s.city.pedestrians, 10);
  EXPECT_DOUBLE_EQ(s.pass2.camera_offset_m.y(), 0.5);
  EXPECT_DOUBLE_EQ(s.camera.depth_factor, 1000);
  EXPECT_NEAR(s.camera.fovy_deg, 73.74, 0.01);
}

TEST(ScenarioTest, TextIsTheFileBytes) {
  const std::string path = ScenarioPath("test/office_small.yaml");
  std::ifstream in(path, std::ios::binary);
  const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_EQ(LoadScenario(path).text, bytes);
}

TEST(ScenarioTest, KindChoosesCameraDefaults) {
  const Scenario office = ParseScenario("kind: office\n", "o.yaml");
  EXPECT_DOUBLE_EQ(office.camera.depth_factor, 5000);
  EXPECT_DOUBLE_EQ(office.camera.far_m, 20);
  EXPECT_NEAR(office.camera.fovy_deg, 49.13, 0.01);
  EXPECT_DOUBLE_EQ(office.camera.fps, 30);
  const Scenario city = ParseScenario("kind: city\ncamera: {far_m: 300}\n", "c.yaml");
  EXPECT_DOUBLE_EQ(city.camera.far_m, 300);
  EXPECT_DOUBLE_EQ(city.camera.depth_factor, 1000);
  EXPECT_EQ(city.name, "c");
}

// yaml-cpp keeps both of a repeated key and a lookup takes the first: the second seed
// below was ignored, unseen.
TEST(ScenarioTest, RepeatedKeyIsRefusedNamingBothLines) {
  EXPECT_EQ(ParseError("kind: office\nseed: 5\noffice:\n  frames: 40\nseed: 9\n"),
            "my.yaml: line 5: key 'seed' appears twice in one mapping (first on line 2)");
  EXPECT_EQ(ParseError("kind: office\noffice:\n  frames: 40\n  people_walking: 1\n  frames: 3\n"),
            "my.yaml: line 5: key 'frames' appears twice in one mapping (first on line 3)");
}

// A key read from the file is quoted with its control bytes escaped, not echoed to the
// terminal.
TEST(ScenarioTest, UnknownKeyIsQuotedPrintably) {
  EXPECT_EQ(ParseError("kind: office\n\x1b[31mevil: 1\n"), "my.yaml: unknown key '\\x1b[31mevil'");
}

TEST(ScenarioTest, UnknownKeyNamesKeyAndFile) {
  EXPECT_EQ(ParseError("city:\n  movng_cars: 3\n"), "my.yaml: unknown key 'city.movng_cars'");
  EXPECT_EQ(ParseError("colour: red\n"), "my.yaml: unknown key 'colour'");
}

TEST(ScenarioTest, OutOfRangeNamesKeyAndValue) {
  EXPECT_EQ(ParseError("city:\n  moving_cars: -3\n"), "my.yaml: city.moving_cars: must be in [0, 100] (got -3)");
  EXPECT_EQ(ParseError("camera:\n  fps: 0\n"), "my.yaml: camera.fps: must be in (0, 240] (got 0)");
  EXPECT_EQ(ParseError("camera: {width: 8}\n"), "my.yaml: camera.width: must be in [16, 4096] (got 8)");
  EXPECT_EQ(ParseError("pass2: {relocated_share: 1.5}\n"),
            "my.yaml: pass2.relocated_share: must be in [0, 1] (got 1.5)");
  EXPECT_EQ(ParseError("pass2: {relocated_shift_m: 3}\n"),
            "my.yaml: pass2.relocated_shift_m: must be in [0, 2.5] (got 3)");
  EXPECT_EQ(ParseError("kind: office\npass2: {relocated_shift_m: 1}\n"),
            "my.yaml: pass2.relocated_shift_m: applies to city scenarios only (this one is 'office'); leave it 0");
  EXPECT_EQ(ParseError("city: {route_length_m: 5}\n"), "my.yaml: city.route_length_m: must be in [20, 2000] (got 5)");
  EXPECT_EQ(ParseError("city: {road_width_m: 10}\n"), "my.yaml: city.road_width_m: must be in [11, 30] (got 10)");
  EXPECT_EQ(ParseError("kind: office\noffice: {room_size_m: [4.5, 6, 2.8]}\n"),
            "my.yaml: office.room_size_m: floor must be at least 5 m (x) by 4 m (y)");
  EXPECT_EQ(ParseError("city: {red_lights: -1}\n"), "my.yaml: city.red_lights: must be in [0, 50] (got -1)");
  EXPECT_EQ(ParseError("city: {red_light_s: 0.5}\n"), "my.yaml: city.red_light_s: must be in [1, 120] (got 0.5)");
  EXPECT_EQ(ParseError("kind: forest\n"), "my.yaml: kind: must be one of city, office (got 'forest')");
  EXPECT_EQ(ParseError("city: {red_light_lead: tram}\n"),
            "my.yaml: city.red_light_lead: must be one of random, car, truck, bus (got 'tram')");
  EXPECT_EQ(ParseError("office: {camera_motion: spin}\n"),
            "my.yaml: office.camera_motion: must be one of xyz, static, rpy, halfsphere (got 'spin')");
  EXPECT_NE(ParseError("seed: -1\n").find("seed: must be >= 0"), std::string::npos);
  EXPECT_NE(ParseError("camera: {near_m: 1, far_m: 0.5}\n").find("camera.far_m"), std::string::npos);
  EXPECT_EQ(ParseError("sensor: {min_depth_m: 10, max_depth_m: 1}\n"),
            "my.yaml: sensor.max_depth_m: must be > sensor.min_depth_m (got 1 <= 10): no pixel would have depth");
  EXPECT_EQ(ParseScenario("sensor: {min_depth_m: 10, max_depth_m: 0}\n", "ok.yaml").sensor.min_depth_m, 10);
}

// Crossing cars and people are timed by their speed to cross when the camera is near: at
// 0 m/s they would stand where they cross, in the camera's way.
TEST(ScenarioTest, CityMoversMustMove) {
  EXPECT_EQ(ParseError("city: {moving_car_speed_mps: 0}\n"),
            "my.yaml: city.moving_car_speed_mps: must be in (0, 30] (got 0)");
  EXPECT_EQ(ParseError("city: {pedestrian_speed_mps: 0}\n"),
            "my.yaml: city.pedestrian_speed_mps: must be in (0, 3] (got 0)");
  EXPECT_EQ(ParseError("city: {moving_car_speed_mps: 0.5, pedestrian_speed_mps: 0.2}\n"), "");
}

// A city's pass-2 camera rides on the camera car as pass 1's does: the offset keeps it
// above the road and that car within the driving lanes (default road: its lane's centre
// 1.95 m right of the centre line, the driving lanes 3.45 m either side of it, the car
// 2.24 m wide), and not so far along the route that it runs into the vehicle it waits
// behind at a red light.
TEST(ScenarioTest, CityCameraOffsetKeepsTheCameraCarOnTheRoad) {
  EXPECT_EQ(ParseError("pass2: {camera_offset_m: [0, 0, -2]}\n"),
            "my.yaml: pass2.camera_offset_m: puts the pass-2 camera -0.5 m above the road (city.camera_height_m "
            "1.5 + z -2); it must be at least 0.3 m");
  EXPECT_EQ(ParseError("pass2: {camera_offset_m: [0, -1.7, 0]}\n"),
            "my.yaml: pass2.camera_offset_m: y (to the left) must be in [-0.38, 4.28] for city.road_width_m 12 (got "
            "-1.7): further, the camera car (2.24 m wide) leaves the driving lanes for a lane of parked cars");
  EXPECT_NE(ParseError("pass2: {camera_offset_m: [0, 4.5, 0]}\n").find("y (to the left) must be in"),
            std::string::npos);
  EXPECT_EQ(ParseError("pass2: {camera_offset_m: [4, 0, 0]}\n"),
            "my.yaml: pass2.camera_offset_m: x (along the route) must be in [-0.8, 0.8] (got 4): the camera car "
            "stands 2 m behind the vehicle it waits behind at a red light, and movers keep 1 m from it");
  EXPECT_NE(ParseError("pass2: {camera_offset_m: [-1.5, 0, 0]}\n").find("x (along the route)"), std::string::npos);
  // Within the bounds; a wider road has room for more.
  EXPECT_EQ(ParseError("pass2: {camera_offset_m: [0.8, -0.35, -1.2]}\n"), "");
  EXPECT_EQ(ParseError("pass2: {camera_offset_m: [-0.8, 4.2, 0]}\n"), "");
  EXPECT_EQ(ParseError("city: {road_width_m: 20}\npass2: {camera_offset_m: [0, 5, 0]}\n"), "");
  EXPECT_EQ(ParseError("city: {camera_height_m: 0.5}\npass2: {camera_offset_m: [0, 0, -0.2]}\n"), "");
  // Offices have no lanes.
  EXPECT_EQ(ParseError("kind: office\npass2: {camera_offset_m: [0, -1.7, -1]}\n"), "");
  // An override is checked the same way, naming the scenario file.
  Scenario s = LoadScenario(ScenarioPath("city_street_grid.yaml"));
  try {
    ApplyOverride(s, "pass2.camera_offset_m", "[0, -1.7, 0]");
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("city_street_grid.yaml: pass2.camera_offset_m: y (to the left)"),
              std::string::npos)
        << e.what();
  }
}

TEST(ScenarioTest, WrongTypesAreRefused) {
  EXPECT_EQ(ParseError("camera:\n  fps: fast\n"), "my.yaml: camera.fps: expected a number (got 'fast')");
  EXPECT_EQ(ParseError("city: {parked_cars: 2.5}\n"), "my.yaml: city.parked_cars: expected an integer (got '2.5')");
  EXPECT_EQ(ParseError("sensor: {enabled: maybe}\n"), "my.yaml: sensor.enabled: expected true or false (got maybe)");
  EXPECT_EQ(ParseError("pass2: {camera_offset_m: [1, 2]}\n"),
            "my.yaml: pass2.camera_offset_m: expected a list of 3 numbers");
  EXPECT_EQ(ParseError("city: 3\n"), "my.yaml: city: expected a mapping");
  EXPECT_EQ(ParseError("camera: {fps: [1]}\n"), "my.yaml: camera.fps: expected a number (got a list)");
}

// The name names folders (dataset cache, reports) and goes into JUnit XML.
TEST(ScenarioTest, NamesThatCannotNameAFolderAreRefused) {
  EXPECT_EQ(ParseError("name: ../up\n"),
            "my.yaml: name: '../up' must be 1 to 100 letters, digits, '.', '_' or '-', not starting with '.' (it "
            "names folders)");
  EXPECT_NE(ParseError("name: \"ofc\\x01<&>\"\n").find("must be 1 to 100 letters"), std::string::npos);
  EXPECT_NE(ParseError("name: a b\n").find("'a b' must be"), std::string::npos);
  EXPECT_NE(ParseError("name: " + std::string(101, 'a') + "\n").find("must be 1 to 100"), std::string::npos);
  EXPECT_EQ(ParseScenario("name: city-2.v_1\n", "my.yaml").name, "city-2.v_1");
  try {
    ParseScenario("kind: office\n", "my scenario.yaml");
    ADD_FAILURE() << "a file name with a space named the scenario";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("'my scenario' (the file's name)"), std::string::npos) << e.what();
  }
}

TEST(ScenarioTest, MalformedYamlNamesLine) {
  const std::string error = ParseError("kind: city\ncity:\n  parked_cars: [1, 2\n  moving_cars: 3\n");
  EXPECT_EQ(error.rfind("my.yaml: line ", 0), 0u) << error;
  EXPECT_NE(ParseError("- a\n- b\n").find("expected a mapping"), std::string::npos);
}

TEST(ScenarioTest, MissingFileNamesFile) {
  try {
    LoadScenario("/nonexistent/x.yaml");
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/x.yaml"), std::string::npos);
  }
}

TEST(ScenarioTest, ExpectIsKeptVerbatim) {
  const Scenario s = ParseScenario("expect:\n  ate_m: {max: 0.1}\n  anything: [1, 2]\n", "e.yaml");
  ASSERT_TRUE(s.expect.IsMap());
  EXPECT_DOUBLE_EQ(s.expect["ate_m"]["max"].as<double>(), 0.1);
}

// `bench:` belongs to `segslam scenario run`; the world must not depend on it.
TEST(ScenarioTest, BenchIsKeptVerbatimAndLeavesTheWorldAlone) {
  const Scenario plain = ParseScenario("kind: office\nseed: 3\n", "b.yaml");
  const Scenario with_bench =
      ParseScenario("kind: office\nseed: 3\nbench: {modes: [plain, mutual], repeats: 4}\n", "b.yaml");
  ASSERT_TRUE(with_bench.bench.IsMap());
  EXPECT_EQ(with_bench.bench["repeats"].as<int>(), 4);
  EXPECT_TRUE(ScenarioToYaml(with_bench)["bench"].IsMap());
  EXPECT_EQ(BuildWorld(plain).objects.size(), BuildWorld(with_bench).objects.size());
}

TEST(ScenarioTest, ApplyOverrideSetsValuesWithTheSameChecks) {
  Scenario s = LoadScenario(ScenarioPath("city_street_grid.yaml"));
  ApplyOverride(s, "city.moving_cars", "8");
  EXPECT_EQ(s.city.moving_cars, 8);
  EXPECT_EQ(s.city.parked_cars, 20);  // the rest is kept
  ApplyOverride(s, "pass2.camera_offset_m", "[0, 1, 0.2]");
  EXPECT_DOUBLE_EQ(s.pass2.camera_offset_m.z(), 0.2);
  EXPECT_EQ(s.city.moving_cars, 8);  // earlier overrides survive
  ApplyOverride(s, "seed", "99");
  EXPECT_EQ(s.seed, 99u);
  EXPECT_NE(s.source_file.string().find("city_street_grid.yaml"), std::string::npos);

  try {
    ApplyOverride(s, "city.movng_cars", "8");
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("unknown key 'city.movng_cars'"), std::string::npos);
  }
  EXPECT_THROW(ApplyOverride(s, "city.moving_cars", "-1"), Error);
  EXPECT_EQ(s.city.moving_cars, 8);  // unchanged after a refused override

  // A scenario built in code has no text: the effective configuration is edited.
  Scenario code;
  code.kind = "office";
  code.office.frames = 77;
  ApplyOverride(code, "office.people_walking", "3");
  EXPECT_EQ(code.office.people_walking, 3);
  EXPECT_EQ(code.office.frames, 77);
}

TEST(ScenarioTest, ApplyOverridesSplitsKeyAndValueAtTheFirstEquals) {
  Scenario s = LoadScenario(ScenarioPath("city_street_grid.yaml"));
  ApplyOverrides(s, {"city.moving_cars=12", "pass2.camera_offset_m=[0, 2, 0]", "seed=5", "name=a-b"});
  EXPECT_EQ(s.name, "a-b");
  // The value is what follows the first '=': here a name that is refused whole.
  try {
    Scenario other = LoadScenario(ScenarioPath("city_street_grid.yaml"));
    ApplyOverrides(other, {"name=a=b"});
    ADD_FAILURE() << "name a=b was taken";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("name: 'a=b' must be"), std::string::npos) << e.what();
  }
  EXPECT_EQ(s.city.moving_cars, 12);
  EXPECT_DOUBLE_EQ(s.pass2.camera_offset_m.y(), 2.0);
  EXPECT_EQ(s.seed, 5u);

  for (const std::string bad : {"city.moving_cars", "=8"}) {
    try {
      ApplyOverrides(s, {"seed=6", bad});
      FAIL() << bad;
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find("'" + bad + "': expected KEY=VALUE"), std::string::npos) << e.what();
    }
    EXPECT_EQ(s.seed, 5u) << "a failed list leaves the scenario as it was";
  }
}

// relocated_share + removed_share <= 1 is checked on the result, not after each key:
// from the file's 0.3 + 0.1, raising one share first and lowering the other second is
// as valid as the other order.
TEST(ScenarioTest, ApplyOverridesValidatesOnceAllAreSet) {
  for (const std::vector<std::string>& order :
       {std::vector<std::string>{"pass2.relocated_share=0.95", "pass2.removed_share=0"},
        std::vector<std::string>{"pass2.removed_share=0", "pass2.relocated_share=0.95"}}) {
    Scenario s = LoadScenario(ScenarioPath("city_street_grid.yaml"));
    ApplyOverrides(s, order);
    EXPECT_DOUBLE_EQ(s.pass2.relocated_share, 0.95);
    EXPECT_DOUBLE_EQ(s.pass2.removed_share, 0.0);
  }
  Scenario s = LoadScenario(ScenarioPath("city_street_grid.yaml"));
  try {
    ApplyOverrides(s, {"pass2.relocated_share=0.95", "pass2.removed_share=0.2"});
    FAIL() << "1.15 accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("relocated_share + removed_share must be <= 1"), std::string::npos)
        << e.what();
  }
  // A key set twice: the later value wins.
  ApplyOverrides(s, {"city.moving_cars=3", "city.moving_cars=9"});
  EXPECT_EQ(s.city.moving_cars, 9);
}

// A lens: five coefficients, and one that keeps bending outwards over the whole image
// (the generator bends every render through it and a run takes the bend out again).
TEST(ScenarioTest, LensDistortionIsFiveCoefficientsThatCoverTheImage) {
  const Scenario kinect = ParseScenario("kind: office\ncamera: {distortion: [0.2624, -0.9531, -0.0054, 0.0026, 1.1633]}\n",
                                        "ok.yaml");
  EXPECT_EQ(kinect.camera.distortion.k2, -0.9531);
  EXPECT_EQ(kinect.camera.distortion.p1, -0.0054);
  EXPECT_TRUE(ParseScenario("kind: office\n", "ok.yaml").camera.distortion.IsZero());
  EXPECT_EQ(ParseError("camera: {distortion: [0.1, 0.2]}\n"),
            "my.yaml: camera.distortion: expected a list of 5 numbers [k1, k2, p1, p2, k3]");
  EXPECT_EQ(ParseError("camera: {distortion: [0, 0, 0, 0, 12]}\n"),
            "my.yaml: camera.distortion: each value must be in [-10, 10] (got 12)");
  // The office image's corners lie at normalised radius 0.76; with k3 = -1 the radius
  // stops growing at 0.72: the lens would fold the corners back onto the image.
  const std::string fold = ParseError("kind: office\ncamera: {distortion: [0, 0, 0, 0, -1]}\n");
  EXPECT_NE(fold.find("my.yaml: camera.distortion: the lens (k1 0, k2 0, k3 -1) folds the image: its radial "
                      "distortion stops growing at normalised radius 0.72"),
            std::string::npos)
      << fold;
  // The same lens on a narrower view is fine.
  EXPECT_EQ(ParseScenario("kind: office\ncamera: {fovy_deg: 40, distortion: [0, 0, 0, 0, -1]}\n", "ok.yaml")
                .camera.distortion.k3,
            -1);
}

TEST(ScenarioTest, ToYamlRoundTrips) {
  Scenario s = LoadScenario(ScenarioPath("office_walking_rpy.yaml"));
  ApplyOverride(s, "camera.distortion", "[-0.28, 0.07, 0.0002, 0.00002, 0]");
  YAML::Emitter out;
  out << ScenarioToYaml(s);
  const Scenario back = ParseScenario(out.c_str(), "round.yaml");
  EXPECT_EQ(back.office.camera_motion, "rpy");
  EXPECT_EQ(back.office.frames, s.office.frames);
  EXPECT_DOUBLE_EQ(back.camera.fovy_deg, s.camera.fovy_deg);
  EXPECT_DOUBLE_EQ(back.office.room_size_m[2], s.office.room_size_m[2]);
  EXPECT_EQ(back.camera.distortion.k1, -0.28);
  EXPECT_EQ(back.camera.distortion.p2, 0.00002);
  EXPECT_EQ(back.seed, s.seed);
}

}  // namespace
}  // namespace segslam::scenes

namespace segslam::scenes {
namespace {

bool Moves(const Object& object) { return object.placement[0].moving || object.placement[1].moving; }

// The static twin is the same world with what moves taken away: every object of the twin
// stands where an object of the same class stands in the world, in both passes, and the
// objects the twin lacks are exactly the world's movers; the camera routes are the same.
TEST(StaticTwinTest, IsTheSameWorldWithItsMoversTakenAway) {
  for (const char* file : {"test/city_small.yaml", "test/office_small.yaml"}) {
    SCOPED_TRACE(file);
    const Scenario scenario = LoadScenario(testing::ScenarioPath(file));
    const Scenario twin_scenario = StaticTwin(scenario);
    EXPECT_EQ(twin_scenario.name, scenario.name + "_static_twin");
    const World world = BuildWorld(scenario);
    const World twin = BuildWorld(twin_scenario);
    std::vector<const Object*> still;
    int movers = 0;
    for (const Object& object : world.objects) {
      if (Moves(object)) {
        ++movers;
      } else {
        still.push_back(&object);
      }
    }
    ASSERT_GT(movers, 0) << "the scenario must have movers to take away";
    ASSERT_EQ(twin.objects.size(), still.size());
    for (std::size_t k = 0; k < still.size(); ++k) {
      const Object& a = *still[k];
      const Object& b = twin.objects[k];
      EXPECT_FALSE(Moves(b));
      EXPECT_EQ(a.category_name, b.category_name) << "object " << k;
      for (int pass = 0; pass < 2; ++pass) {
        EXPECT_EQ(a.placement[pass].present, b.placement[pass].present) << "object " << k;
        EXPECT_TRUE(a.placement[pass].T_world_object.isApprox(b.placement[pass].T_world_object, 1e-12))
            << "object " << k << " (" << a.category_name << "), pass " << pass + 1;
      }
    }
    for (int pass = 0; pass < 2; ++pass) {
      const CameraRoute& route = world.camera_route[pass];
      const CameraRoute& twin_route = twin.camera_route[pass];
      ASSERT_EQ(route.keys.size(), twin_route.keys.size());
      for (std::size_t k = 0; k < route.keys.size(); ++k) {
        EXPECT_EQ(route.keys[k].stamp_s, twin_route.keys[k].stamp_s);
        EXPECT_TRUE(route.keys[k].T_wc.isApprox(twin_route.keys[k].T_wc, 1e-12)) << "pass " << pass + 1 << " key " << k;
      }
    }
  }
}

}  // namespace
}  // namespace segslam::scenes
