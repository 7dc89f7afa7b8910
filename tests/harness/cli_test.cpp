// The command line's answers to bad input: one line on stderr, a non-zero exit code,
// and nothing left at the output path.
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <regex>
#include <string>
#include <utility>
#include <vector>
#include <csignal>
#include <sys/wait.h>
#include <unistd.h>

#include "core/atomic_file.h"

namespace {

namespace fs = std::filesystem;

struct CommandResult {
  int exit_code = -1;
  std::string stderr_text;
};

// Runs the segslam binary with `arguments` (shell-quoted by the caller), capturing stderr.
CommandResult RunSegslam(const std::string& arguments, const std::string& env = "") {
  const fs::path stderr_file = fs::temp_directory_path() /
                               ("segslam_cli_test_" + std::to_string(::getpid()) + ".err");
  const std::string command = env + " " + SEGSLAM_BINARY + " " + arguments + " >/dev/null 2>" +
                              stderr_file.string();
  const int status = std::system(command.c_str());
  CommandResult result;
  result.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  std::ifstream in(stderr_file);
  result.stderr_text.assign(std::istreambuf_iterator<char>(in), {});
  fs::remove(stderr_file);
  return result;
}

int LineCount(const std::string& text) {
  int lines = 0;
  for (char c : text) lines += c == '\n';
  return lines;
}

std::string ReadText(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

// True when `text` holds no byte a terminal would take for a control (C0 or DEL) other
// than line ends.
bool HoldsNoControlBytes(const std::string& text) {
  for (const char c : text) {
    const auto byte = static_cast<unsigned char>(c);
    if ((byte < 0x20 && byte != '\n') || byte == 0x7f) return false;
  }
  return true;
}

class CliBadInputTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("segslam_cli_" + std::to_string(::getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  fs::path WriteScenario(const std::string& name, const std::string& text) {
    const fs::path file = dir_ / name;
    std::ofstream(file) << text;
    return file;
  }

  // Expects a failed `generate` of `scenario` with a one-line error containing every
  // fragment, and no output directory left behind.
  void ExpectGenerateFails(const fs::path& scenario, const std::vector<std::string>& fragments,
                           const std::string& extra_args = "", const std::string& env = "") {
    const fs::path out = dir_ / "out";
    const CommandResult result =
        RunSegslam("generate " + scenario.string() + " --out " + out.string() + " --frames 2 -q " +
                       extra_args,
                   env);
    EXPECT_NE(result.exit_code, 0);
    EXPECT_EQ(LineCount(result.stderr_text), 1) << result.stderr_text;
    for (const auto& fragment : fragments) {
      EXPECT_NE(result.stderr_text.find(fragment), std::string::npos)
          << "missing '" << fragment << "' in: " << result.stderr_text;
    }
    EXPECT_FALSE(fs::exists(out));
    // No hidden partial directory either.
    for (const auto& entry : fs::directory_iterator(dir_)) {
      EXPECT_EQ(entry.path().filename().string().find(".out.partial"), std::string::npos);
    }
  }

  fs::path dir_;
};

const char* kSmallOffice = SEGSLAM_SOURCE_DIR "/scenarios/test/office_small.yaml";

TEST_F(CliBadInputTest, MalformedYamlNamesFileAndLine) {
  const fs::path file = WriteScenario("broken.yaml", "name: broken\nkind: [office\nseed: 3\n");
  ExpectGenerateFails(file, {"broken.yaml", "line"});
}

TEST_F(CliBadInputTest, UnknownKeyIsNamed) {
  const fs::path file =
      WriteScenario("typo.yaml", "name: typo\nkind: city\ncity:\n  movng_cars: 3\n");
  ExpectGenerateFails(file, {"typo.yaml", "movng_cars"});
}

TEST_F(CliBadInputTest, OutOfRangeValueIsNamed) {
  const fs::path file =
      WriteScenario("range.yaml", "name: range\nkind: city\ncity:\n  moving_cars: -3\n");
  ExpectGenerateFails(file, {"range.yaml", "moving_cars"});
}

TEST_F(CliBadInputTest, MissingScenarioFile) {
  ExpectGenerateFails(dir_ / "nowhere.yaml", {"nowhere.yaml"});
}

// A number out of range names its option and the allowed range in words (CLI11's own
// check printed a 309-digit maximum), and exits 1 as every other error does.
TEST_F(CliBadInputTest, NumberOutOfRangeSaysTheRangeInWordsAndExitsOne) {
  const std::string out = " --out " + (dir_ / "out").string();
  const std::pair<std::string, std::string> cases[] = {
      {std::string("generate ") + kSmallOffice + out + " --frames -3",
       "--frames: must be a whole number from 0 to 1000000 (0 = all), got -3"},
      {std::string("run ") + dir_.string() + out + " --frames 99999999999999",
       "--frames: must be a whole number from 0 to 1000000 (0 = all), got 99999999999999"},
      {std::string("scenario run ") + kSmallOffice + out + " --repeats 0",
       "--repeats: must be a whole number from 1 to 1000, got 0"},
      {std::string("scenario run ") + kSmallOffice + out + " --jobs 0",
       "--jobs: must be a whole number from 1 to 1024, got 0"},
      {std::string("eval-traj a.txt b.txt --rpe-delta 0"), "--rpe-delta: must be a number above 0 and at most 1e+06, got 0"},
  };
  for (const auto& [arguments, message] : cases) {
    SCOPED_TRACE(arguments);
    const CommandResult result = RunSegslam(arguments);
    EXPECT_EQ(result.exit_code, 1);
    EXPECT_EQ(LineCount(result.stderr_text), 1) << result.stderr_text;
    EXPECT_NE(result.stderr_text.find("segslam: error: " + message), std::string::npos) << result.stderr_text;
  }
  EXPECT_FALSE(fs::exists(dir_ / "out"));
}

// Every exit code is listed in the help of segslam and of each subcommand.
TEST_F(CliBadInputTest, HelpListsTheExitCodes) {
  for (const std::string command : {"", "run ", "scenario run "}) {
    const fs::path help = dir_ / "help.txt";
    ASSERT_EQ(std::system((std::string(SEGSLAM_BINARY) + " " + command + "--help >" + help.string()).c_str()), 0);
    std::ifstream in(help);
    const std::string text((std::istreambuf_iterator<char>(in)), {});
    for (const char* code : {"Exit codes: 0 done; 1 an error", "2 an expectation failed", "3 an internal error",
                             "130 interrupted"}) {
      EXPECT_NE(text.find(code), std::string::npos) << command << "--help lacks '" << code << "':\n" << text;
    }
  }
}

// `segslam options` lists every tunable with its default, range, unit and help, as the
// registries declare them; --json gives the same list.
TEST_F(CliBadInputTest, OptionsListsEveryTunableWithDefaultRangeAndHelp) {
  const fs::path listing = dir_ / "options.txt";
  auto list = [&](const std::string& arguments) {
    const int status = std::system((std::string(SEGSLAM_BINARY) + " options " + arguments + " >" + listing.string() +
                                    " 2>/dev/null").c_str());
    return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  };
  ASSERT_EQ(list("tracker"), 0);
  const std::string tracker = ReadText(listing);
  EXPECT_NE(tracker.find("orb.max_features"), std::string::npos);
  EXPECT_NE(tracker.find(">= 4"), std::string::npos) << "min_rival_consensus's range";
  EXPECT_NE(tracker.find("pose_optimizer.chi2_stereo"), std::string::npos);
  ASSERT_EQ(list("refiner --json"), 0);
  const nlohmann::json options = nlohmann::json::parse(ReadText(listing));
  ASSERT_TRUE(options.is_array());
  bool found = false;
  for (const nlohmann::json& option : options) {
    EXPECT_FALSE(option.at("help").get<std::string>().empty()) << option.dump();
    if (option.at("name") == "depth_tolerance") {
      found = true;
      EXPECT_DOUBLE_EQ(option.at("default").get<double>(), 0.05);
      EXPECT_EQ(option.at("range"), "[0, 1)");
    }
  }
  EXPECT_TRUE(found);
  EXPECT_EQ(list("segmenter"), 1);
}

// A folder given where a file is expected is named, with exit code 1 (it was an internal
// error, exit 3, without the path).
TEST_F(CliBadInputTest, FolderWhereAFileIsExpectedIsNamed) {
  const fs::path folder = dir_ / "folder";
  fs::create_directories(folder);
  const CommandResult result = RunSegslam("eval-traj " + folder.string() + " " + folder.string());
  EXPECT_EQ(result.exit_code, 1);
  EXPECT_NE(result.stderr_text.find(folder.string() + ": is a directory, expected a file"), std::string::npos)
      << result.stderr_text;
  const CommandResult scenario = RunSegslam("generate " + folder.string() + " --out " + (dir_ / "out").string());
  EXPECT_EQ(scenario.exit_code, 1);
  EXPECT_NE(scenario.stderr_text.find(folder.string() + ": is a directory, expected a file"), std::string::npos)
      << scenario.stderr_text;
}

// Translations near 1e200 m printed inf and -nan with exit code 0.
TEST_F(CliBadInputTest, EvalTrajRefusesPositionsBeyondEarth) {
  const fs::path ground_truth = dir_ / "groundtruth.txt", estimate = dir_ / "estimate.txt";
  std::ofstream(ground_truth) << "1.0 0 0 0 0 0 0 1\n1.5 1 0 0 0 0 0 1\n2.0 2 0 0 0 0 0 1\n2.5 3 1 0 0 0 0 1\n";
  std::ofstream(estimate) << "1.0 1e200 0 0 0 0 0 1\n1.5 1 0 0 0 0 0 1\n2.0 2 0 0 0 0 0 1\n2.5 3 1 0 0 0 0 1\n";
  const CommandResult result = RunSegslam("eval-traj " + ground_truth.string() + " " + estimate.string());
  EXPECT_EQ(result.exit_code, 1);
  EXPECT_NE(result.stderr_text.find("estimate pose 0 (stamp 1.000000) lies 1e+200 m from the origin"),
            std::string::npos)
      << result.stderr_text;
}

TEST_F(CliBadInputTest, UnwritableOutputPath) {
  // A regular file where the output's parent directory should be.
  const fs::path blocker = dir_ / "blocker";
  std::ofstream(blocker) << "not a directory";
  const CommandResult result = RunSegslam(std::string("generate ") + kSmallOffice + " --out " +
                                          (blocker / "out").string() + " --frames 2 -q");
  EXPECT_NE(result.exit_code, 0);
  EXPECT_EQ(LineCount(result.stderr_text), 1) << result.stderr_text;
  EXPECT_NE(result.stderr_text.find("blocker"), std::string::npos) << result.stderr_text;
}

TEST_F(CliBadInputTest, ExistingOutputIsKeptWithoutForce) {
  const fs::path out = dir_ / "out";
  fs::create_directories(out);
  std::ofstream(out / "keep.txt") << "precious";
  const CommandResult result = RunSegslam(std::string("generate ") + kSmallOffice + " --out " +
                                          out.string() + " --frames 2 -q");
  EXPECT_NE(result.exit_code, 0);
  EXPECT_NE(result.stderr_text.find("already exists"), std::string::npos) << result.stderr_text;
  EXPECT_TRUE(fs::exists(out / "keep.txt"));
}

// generate --force replaces only a dataset that segslam wrote (its manifest.json lists
// every file): it deleted a folder of other files, or a plain file, whatever it held.
TEST_F(CliBadInputTest, ForceReplacesOnlyADatasetThatSegslamWrote) {
  const std::string generate = std::string("generate ") + kSmallOffice + " --frames 2 -q --force --out ";
  const fs::path folder = dir_ / "x";
  fs::create_directories(folder / "sub");
  std::ofstream(folder / "sub" / "t.tex") << "precious";
  const CommandResult refused = RunSegslam(generate + folder.string());
  EXPECT_EQ(refused.exit_code, 1);
  EXPECT_EQ(LineCount(refused.stderr_text), 1) << refused.stderr_text;
  EXPECT_NE(refused.stderr_text.find(folder.string() + ": holds what segslam did not write (no segslam manifest.json)"),
            std::string::npos)
      << refused.stderr_text;
  EXPECT_EQ(ReadText(folder / "sub" / "t.tex"), "precious");

  const fs::path file = dir_ / "file";
  std::ofstream(file) << "a plain file";
  const CommandResult plain = RunSegslam(generate + file.string());
  EXPECT_EQ(plain.exit_code, 1);
  EXPECT_NE(plain.stderr_text.find(file.string() + ": is a file, not a folder"), std::string::npos) << plain.stderr_text;
  EXPECT_EQ(ReadText(file), "a plain file");

  // What generate wrote, it replaces.
  const fs::path dataset = dir_ / "dataset";
  ASSERT_EQ(RunSegslam(generate + dataset.string()).exit_code, 0);
  const CommandResult again = RunSegslam(generate + dataset.string());
  EXPECT_EQ(again.exit_code, 0) << again.stderr_text;
  EXPECT_TRUE(fs::exists(dataset / "manifest.json"));
  for (const auto& entry : fs::directory_iterator(dir_)) {
    EXPECT_EQ(entry.path().filename().string().find(".partial"), std::string::npos) << entry.path();
  }
}

// A crowd denser than the streets hold is not refused: generate leaves out the movers
// that find no path clear of the others, says how many, and records it in the manifest.
TEST_F(CliBadInputTest, CrowdDenserThanTheStreetsIsThinnedAndSaid) {
  const fs::path out = dir_ / "rush", printed = dir_ / "stdout.txt";
  const std::string command = std::string(SEGSLAM_BINARY) + " generate " + SEGSLAM_SOURCE_DIR +
                              "/scenarios/city_rush_hour.yaml --out " + out.string() +
                              " --frames 1 -q --set camera.width=160 --set camera.height=120 >" + printed.string() +
                              " 2>&1";
  const int status = std::system(command.c_str());
  ASSERT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << command;
  std::ifstream in(printed);
  const std::string text((std::istreambuf_iterator<char>(in)), {});
  std::smatch note;
  ASSERT_TRUE(std::regex_search(text, note, std::regex("note: ([0-9]+) of the scenario's moving cars and pedestrians")))
      << text;
  const int left_out = std::stoi(note[1]);
  EXPECT_GT(left_out, 0);
  EXPECT_LT(left_out, 140 / 2) << "most of rush hour's 140 movers find room";
  std::ifstream manifest(out / "manifest.json");
  EXPECT_EQ(nlohmann::json::parse(manifest).at("extra").at("movers_left_out").get<int>(), left_out);
}

TEST_F(CliBadInputTest, UnknownGlBackend) {
  ExpectGenerateFails(kSmallOffice, {"unknown GL back-end", "vulkan"}, "--gl vulkan");
}

TEST_F(CliBadInputTest, UnavailableEglBackend) {
  // Point GLVND at no EGL vendor at all: EGL cannot start, and generate must say so.
  ExpectGenerateFails(kSmallOffice, {"EGL"}, "--gl egl",
                      "__EGL_VENDOR_LIBRARY_FILENAMES=/nonexistent/vendor.json");
}

}  // namespace

namespace {

// Ctrl-C in the middle of a generation: exit code 130, nothing at the output path, and
// no hidden partial directory left beside it.
TEST_F(CliBadInputTest, InterruptLeavesNothingBehind) {
  const fs::path out = dir_ / "out";
  const std::string scenario = SEGSLAM_SOURCE_DIR "/scenarios/city_street_grid.yaml";
  const pid_t pid = ::fork();
  ASSERT_GE(pid, 0);
  if (pid == 0) {
    ::freopen("/dev/null", "w", stderr);
    // --frames bounds the work should the child ever outlive the test.
    ::execl(SEGSLAM_BINARY, SEGSLAM_BINARY, "generate", scenario.c_str(), "--out", out.c_str(), "--frames",
            "400", "--quiet", static_cast<char*>(nullptr));
    ::_exit(127);
  }
  // On every way out of this test (a failed ASSERT included) the child is stopped and
  // reaped, so it never writes into dir_ after TearDown removed it.
  bool reaped = false;
  int status = 0;
  struct ChildGuard {
    pid_t pid;
    bool& reaped;
    ~ChildGuard() {
      if (reaped) return;
      ::kill(pid, SIGKILL);
      ::waitpid(pid, nullptr, 0);
    }
  } guard{pid, reaped};
  // Wait until frames are being written (the staging directory has a pass1/rgb folder).
  auto staging_has_frames = [&] {
    for (const auto& entry : fs::directory_iterator(dir_)) {
      const fs::path rgb = entry.path() / "pass1" / "rgb";
      if (fs::exists(rgb) && !fs::is_empty(rgb)) return true;
    }
    return false;
  };
  for (int waited_ms = 0; waited_ms < 60000 && !staging_has_frames(); waited_ms += 50) {
    ::usleep(50 * 1000);
  }
  ASSERT_TRUE(staging_has_frames()) << "generation never started writing frames";
  ::kill(pid, SIGINT);
  ASSERT_EQ(::waitpid(pid, &status, 0), pid);
  reaped = true;
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 130);
  EXPECT_FALSE(fs::exists(out));
  EXPECT_TRUE(fs::is_empty(dir_)) << "something was left in " << dir_;
}

}  // namespace

// `segslam run` on a tiny generated sequence with a broken map or missing masks.
class CliRunBadInputTest : public CliBadInputTest {
 protected:
  fs::path GenerateTinySequence() {
    const fs::path dataset = dir_ / "dataset";
    const CommandResult generated =
        RunSegslam(std::string("generate ") + kSmallOffice + " --out " + dataset.string() + " --frames 3 -q");
    EXPECT_EQ(generated.exit_code, 0) << generated.stderr_text;
    return dataset / "pass1";
  }

  // A copy of the tiny sequence's dataset (both passes) whose pass 2 cannot be read to its
  // end: its last depth image is no PNG. Returns the dataset and sets `*broken_file`.
  fs::path DatasetBrokenInPassTwo(fs::path* broken_file) {
    if (!fs::exists(dir_ / "dataset")) GenerateTinySequence();
    const fs::path broken = dir_ / "broken";
    fs::copy(dir_ / "dataset", broken, fs::copy_options::recursive);
    fs::path last_depth;
    for (const auto& entry : fs::directory_iterator(broken / "pass2" / "depth")) {
      last_depth = std::max(last_depth, entry.path());
    }
    std::ofstream(last_depth) << "not a PNG";
    *broken_file = last_depth;
    return broken;
  }

  void ExpectRunFails(const std::string& arguments, const std::string& fragment) {
    const CommandResult result = RunSegslam("run " + arguments + " -q --out " + (dir_ / "run").string());
    EXPECT_NE(result.exit_code, 0);
    EXPECT_EQ(LineCount(result.stderr_text), 1) << result.stderr_text;
    EXPECT_NE(result.stderr_text.find(fragment), std::string::npos) << result.stderr_text;
    EXPECT_FALSE(fs::exists(dir_ / "run" / "trajectory.txt"));
  }
};

TEST_F(CliRunBadInputTest, CorruptMapFileIsNamed) {
  const fs::path sequence = GenerateTinySequence();
  const fs::path map = dir_ / "broken.segslam";
  std::ofstream(map, std::ios::binary) << std::string("SEGSLAM-MAP\0", 12) << "not a real payload";
  ExpectRunFails(sequence.string() + " --mode plain --map-in " + map.string(), "broken.segslam");
}

TEST_F(CliRunBadInputTest, MissingInstanceTableIsNamed) {
  const fs::path sequence = GenerateTinySequence();
  fs::remove(sequence / "instances.json");
  ExpectRunFails(sequence.string() + " --mode mutual", "instances.json");
}

TEST_F(CliRunBadInputTest, UnknownModeIsRefused) {
  const fs::path sequence = GenerateTinySequence();
  ExpectRunFails(sequence.string() + " --mode dynaslam", "dynaslam");
}

// --strength scales the simulated segmenter's errors: alone it would silently do nothing.
TEST_F(CliRunBadInputTest, StrengthWithoutASimulatedSegmenterIsRefused) {
  const fs::path sequence = GenerateTinySequence();
  ExpectRunFails(sequence.string() + " --mode mutual --strength 2", "give --segmenter too");
  const CommandResult out_of_range =
      RunSegslam("run " + sequence.string() + " --mode mutual --segmenter fcis-like --strength 12 -q");
  EXPECT_NE(out_of_range.exit_code, 0);
  EXPECT_NE(out_of_range.stderr_text.find("--strength: must be a number from 0 to 10, got 12"), std::string::npos)
      << out_of_range.stderr_text;
}

// run --camera gets the check generate's camera gets: a focal length of 1e-9 px ran to
// "100 % localized" and an ATE of 4e8 m, a principal point far outside the image and a
// lens that folds the image were taken.
TEST_F(CliRunBadInputTest, CameraGenerateWouldRefuseIsRefused) {
  const fs::path sequence = GenerateTinySequence();
  const std::string intrinsics = "width: 320\nheight: 240\nfy: 250\ncy: 119.5\ndepth_factor: 5000\n";
  const std::pair<std::string, std::string> cameras[] = {
      {"fx: 1e-9\ncx: 159.5\n", "fx 1e-09 px gives a horizontal field of view of 180 deg"},
      {"fx: 250\ncx: 99999\n", "principal point cx 99999 lies outside the image"},
      {"fx: 250\ncx: 159.5\nk1: 50\nk2: -90\n", "the lens (k1 50, k2 -90, k3 0) folds the image"},
  };
  for (const auto& [camera, fragment] : cameras) {
    SCOPED_TRACE(camera);
    std::ofstream(dir_ / "camera.yaml") << intrinsics << camera;
    ExpectRunFails(sequence.string() + " --mode plain --camera " + (dir_ / "camera.yaml").string(),
                   (dir_ / "camera.yaml").string() + ": invalid camera: " + fragment);
  }
  ExpectRunFails(sequence.string() + " --mode plain --camera " + dir_.string(),
                 dir_.string() + ": is a directory, expected a file");
}

// The README promises that an empty results list is an error leaving no folder; it wrote
// a folder of empty masks.
TEST_F(CliRunBadInputTest, MasksImportOfAnEmptyListFailsAndLeavesNoFolder) {
  const fs::path sequence = GenerateTinySequence();
  std::ofstream(dir_ / "empty.json") << "[]\n";
  const fs::path out = dir_ / "masks";
  const CommandResult result =
      RunSegslam("masks import " + sequence.string() + " " + (dir_ / "empty.json").string() + " -q --out " + out.string());
  EXPECT_EQ(result.exit_code, 1);
  EXPECT_NE(result.stderr_text.find("empty.json: an empty results list"), std::string::npos) << result.stderr_text;
  EXPECT_FALSE(fs::exists(out));
  // A folder for the detections or the image list is named too.
  const CommandResult folder =
      RunSegslam("masks import " + sequence.string() + " " + dir_.string() + " -q --out " + out.string());
  EXPECT_NE(folder.stderr_text.find(dir_.string() + ": is a directory, expected a file"), std::string::npos)
      << folder.stderr_text;
  std::ofstream(dir_ / "one.json") << "[{\"image_id\": 1}]\n";
  const CommandResult images = RunSegslam("masks import " + sequence.string() + " " + (dir_ / "one.json").string() +
                                          " --images " + dir_.string() + " -q --out " + out.string());
  EXPECT_NE(images.stderr_text.find(dir_.string() + ": is a directory, expected a file"), std::string::npos)
      << images.stderr_text;
  EXPECT_FALSE(fs::exists(out));
}

// eval checks frames.jsonl against the trajectory written with it: cut to one line of
// three, it reported 1 frame, 100 % localized.
TEST_F(CliRunBadInputTest, EvalRefusesAFrameLogCutShort) {
  const fs::path sequence = GenerateTinySequence();
  const fs::path run = dir_ / "run";
  ASSERT_EQ(RunSegslam("run " + sequence.string() + " --mode plain -q --out " + run.string()).exit_code, 0);
  std::ifstream in(run / "frames.jsonl");
  std::string first_line;
  std::getline(in, first_line);
  in.close();
  std::ofstream(run / "frames.jsonl") << first_line << "\n";
  const CommandResult result = RunSegslam("eval " + run.string() + " --dataset " + sequence.string());
  EXPECT_EQ(result.exit_code, 1);
  EXPECT_EQ(LineCount(result.stderr_text), 1) << result.stderr_text;
  EXPECT_NE(result.stderr_text.find((run / "frames.jsonl").string() + ": 1 frame(s), but " +
                                    (run / "trajectory.txt").string() + " says the run read 3"),
            std::string::npos)
      << result.stderr_text;
}

// run --out naming a file is refused by name and the file kept (it said "cannot remove:
// Not a directory [FILE/seg.json]").
TEST_F(CliRunBadInputTest, OutThatIsAFileIsRefusedAndKept) {
  const fs::path sequence = GenerateTinySequence();
  const fs::path file = dir_ / "file";
  std::ofstream(file) << "a plain file";
  const CommandResult result = RunSegslam("run " + sequence.string() + " -q --out " + file.string());
  EXPECT_EQ(result.exit_code, 1);
  EXPECT_EQ(LineCount(result.stderr_text), 1) << result.stderr_text;
  EXPECT_NE(result.stderr_text.find(file.string() + ": is a file, not a folder (a run output is a folder)"),
            std::string::npos)
      << result.stderr_text;
  EXPECT_EQ(ReadText(file), "a plain file");
}

// A run's outputs are one unit: a re-run into the same --out that fails in pass 2 leaves
// the previous output whole (it left the new pass1/ beside the old pass2/, of another
// mode, and eval scored the mix).
TEST_F(CliRunBadInputTest, RunFailingInPassTwoLeavesThePreviousOutputWhole) {
  fs::path last_depth;
  const fs::path broken = DatasetBrokenInPassTwo(&last_depth);  // pass 1 runs to its end first
  const fs::path dataset = dir_ / "dataset", run = dir_ / "run";
  ASSERT_EQ(RunSegslam("run " + dataset.string() + " --mode plain -q --out " + run.string()).exit_code, 0);
  const std::string pass1 = ReadText(run / "pass1" / "trajectory.txt");
  const std::string pass2 = ReadText(run / "pass2" / "trajectory.txt");
  ASSERT_NE(pass1.find("mode plain"), std::string::npos) << pass1;

  const CommandResult failed = RunSegslam("run " + broken.string() + " --mode mask-moveable -q --out " + run.string());
  EXPECT_EQ(failed.exit_code, 1);
  EXPECT_NE(failed.stderr_text.find(last_depth.filename().string()), std::string::npos) << failed.stderr_text;
  EXPECT_EQ(ReadText(run / "pass1" / "trajectory.txt"), pass1);
  EXPECT_EQ(ReadText(run / "pass2" / "trajectory.txt"), pass2);
  for (const auto& entry : fs::directory_iterator(dir_)) {
    EXPECT_EQ(entry.path().filename().string().find(".partial"), std::string::npos) << entry.path();
  }
  const CommandResult eval = RunSegslam("eval " + run.string() + " --dataset " + dataset.string());
  EXPECT_EQ(eval.exit_code, 0) << eval.stderr_text;
}

// --map-out is part of the run's output: a folder there is refused before any frame (the
// run failed at its end and left a trajectory.txt and frames.jsonl that looked complete),
// and a map that cannot be written at the end leaves neither map nor run output.
TEST_F(CliRunBadInputTest, MapOutThatCannotBeWrittenLeavesNoRunOutput) {
  const fs::path sequence = GenerateTinySequence();
  const fs::path folder = dir_ / "maps";
  fs::create_directories(folder);
  ExpectRunFails(sequence.string() + " --mode plain --map-out " + folder.string(),
                 folder.string() + ": is a folder; --map-out takes the path of the map file to write");
  EXPECT_FALSE(fs::exists(dir_ / "run"));

  // Pass 1's map is written, then pass 2 fails: neither the map nor the run is left.
  fs::path last_depth;
  const fs::path broken = DatasetBrokenInPassTwo(&last_depth);
  const fs::path map = dir_ / "map.segslam";
  const CommandResult late = RunSegslam("run " + broken.string() + " --mode plain -q --out " +
                                        (dir_ / "run").string() + " --map-out " + map.string());
  EXPECT_EQ(late.exit_code, 1);
  EXPECT_EQ(LineCount(late.stderr_text), 1) << late.stderr_text;
  EXPECT_NE(late.stderr_text.find(last_depth.filename().string()), std::string::npos) << late.stderr_text;
  EXPECT_FALSE(fs::exists(dir_ / "run"));
  EXPECT_FALSE(fs::exists(map));
  EXPECT_FALSE(fs::exists(dir_ / "map.ply"));
  for (const auto& entry : fs::directory_iterator(dir_)) {
    EXPECT_EQ(entry.path().filename().string().find(".partial"), std::string::npos) << entry.path();
  }
}

// A run killed while its map waited beside --map-out (all of pass 2, for a dataset's two
// passes) left hidden files there that nothing removed; the next run to that map clears
// what ended processes of this host left, and keeps another host's.
TEST_F(CliRunBadInputTest, MapOutLeftoversOfAKilledRunAreCleared) {
  const fs::path sequence = GenerateTinySequence();
  const fs::path maps = dir_ / "maps";
  fs::create_directories(maps);
  // The map and its .ply wait in a hidden folder named after the map, as a staging folder.
  const std::string dead = ".m.segslam.partial-2147483000@";  // above any pid_max: no process has it
  const std::string host = segslam::StagingHostName();
  for (const fs::path& folder : {maps / (dead + host), maps / (dead + "not-" + host)}) {
    fs::create_directories(folder);
    std::ofstream(folder / "m.segslam") << "a killed run's";
    std::ofstream(folder / "m.ply") << "a killed run's";
  }
  const fs::path other_host = maps / (dead + "not-" + host);
  const CommandResult result = RunSegslam("run " + sequence.string() + " --mode plain -q --out " +
                                          (dir_ / "run").string() + " --map-out " + (maps / "m.segslam").string());
  ASSERT_EQ(result.exit_code, 0) << result.stderr_text;
  std::vector<std::string> names;
  for (const auto& entry : fs::directory_iterator(maps)) names.push_back(entry.path().filename().string());
  std::sort(names.begin(), names.end());
  EXPECT_EQ(names, (std::vector<std::string>{other_host.filename().string(), "m.ply", "m.segslam"}));
}

// File text that reaches a message unquoted (a mode a scenario names, an image path that
// associations.txt lists) comes out with its control bytes escaped, so that a file's
// bytes cannot clear the terminal; a folder's UTF-8 name stays as it is.
TEST_F(CliRunBadInputTest, FileTextInAMessageCannotControlTheTerminal) {
  const fs::path scenario =
      WriteScenario("modes.yaml", ReadText(kSmallOffice) + "bench: {modes: [\"\\e[2Jplain\"]}\n");
  const CommandResult mode = RunSegslam("scenario run " + scenario.string() + " -q --cache " +
                                        (dir_ / "cache").string() + " --out " + (dir_ / "report").string());
  EXPECT_EQ(mode.exit_code, 1);
  EXPECT_NE(mode.stderr_text.find("unknown mode '\\x1b[2Jplain'"), std::string::npos) << mode.stderr_text;
  EXPECT_TRUE(HoldsNoControlBytes(mode.stderr_text)) << mode.stderr_text;

  const fs::path sequence = dir_ / "s\u00e9quence";
  fs::copy(GenerateTinySequence(), sequence, fs::copy_options::recursive);
  std::ofstream(sequence / "associations.txt") << "0.000000 rgb/\x1b[2J\xff.png 0.000000 depth/0.000000.png\n";
  const CommandResult listed = RunSegslam("run " + sequence.string() + " --mode plain -q --out " + (dir_ / "run").string());
  EXPECT_EQ(listed.exit_code, 1);
  EXPECT_NE(listed.stderr_text.find(sequence.string() + "/rgb/\\x1b[2J\\xff.png: image file listed in the sequence"),
            std::string::npos)
      << listed.stderr_text;
  EXPECT_TRUE(HoldsNoControlBytes(listed.stderr_text)) << listed.stderr_text;
}

// --refiner tunes the mutual loop's refinement: where no loop runs it would do nothing.
TEST_F(CliRunBadInputTest, RefinerOptionsOutsideTheLoopOrOutOfRangeAreRefused) {
  const fs::path sequence = GenerateTinySequence();
  ExpectRunFails(sequence.string() + " --mode plain --refiner depth_tolerance=0.1", "--refiner applies to the mutual loop");
  ExpectRunFails(sequence.string() + " --mode mutual --refiner depth_tolerance=0.1", "--refiner applies to the mutual loop");
  ExpectRunFails(sequence.string() + " --mode mutual --segmenter fcis-like --refiner depth_tolerance=2",
                 "depth_tolerance: 2 is outside its range [0, 1)");
  ExpectRunFails(sequence.string() + " --mode mutual --segmenter fcis-like --refiner depth_tol=0.1",
                 "unknown field 'depth_tol'");
}
