// The command line's answers to bad input: one line on stderr, a non-zero exit code,
// and nothing left at the output path.
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <regex>
#include <string>
#include <csignal>
#include <sys/wait.h>
#include <unistd.h>

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
  EXPECT_NE(out_of_range.stderr_text.find("--strength: Value 12 not in range"), std::string::npos)
      << out_of_range.stderr_text;
}

// --refiner tunes the mutual loop's refinement: where no loop runs it would do nothing.
TEST_F(CliRunBadInputTest, RefinerOptionsOutsideTheLoopOrOutOfRangeAreRefused) {
  const fs::path sequence = GenerateTinySequence();
  ExpectRunFails(sequence.string() + " --mode plain --refiner depth_tolerance=0.1", "--refiner applies to the mutual loop");
  ExpectRunFails(sequence.string() + " --mode mutual --refiner depth_tolerance=0.1", "--refiner applies to the mutual loop");
  ExpectRunFails(sequence.string() + " --mode mutual --segmenter fcis-like --refiner depth_tolerance=2",
                 "depth_tolerance must lie in [0, 1)");
  ExpectRunFails(sequence.string() + " --mode mutual --segmenter fcis-like --refiner depth_tol=0.1",
                 "unknown field 'depth_tol'");
}
