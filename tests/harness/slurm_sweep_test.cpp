// A sweep as a Slurm job array and its merge job (`segslam sweep --emit-sbatch`), on a
// private single-node Slurm that scripts/slurm/local_cluster.sh brings up from Debian's
// packages: the merged report equals the one the same sweep gives in one process, and the
// tasks that share a dataset generate it once. Skipped, saying why, where Slurm cannot
// start (not installed, not root).
#include <cstdio>
#include <cstdlib>
#include <regex>
#include <thread>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "cli_runner.h"

namespace segslam::harness {
namespace {

namespace fs = std::filesystem;
using segslam::testing::CommandOutput;
using segslam::testing::ReadText;
using namespace std::chrono_literals;

struct ShellResult {
  int exit_code = -1;
  std::string output;  // stdout and stderr
};

ShellResult Shell(const std::string& command) {
  ShellResult result;
  FILE* pipe = ::popen((command + " 2>&1").c_str(), "r");
  if (pipe == nullptr) return result;
  char buffer[4096];
  for (std::size_t n; (n = std::fread(buffer, 1, sizeof(buffer), pipe)) > 0;) result.output.append(buffer, n);
  const int status = ::pclose(pipe);
  result.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return result;
}

const std::string kClusterScript = (fs::path(SEGSLAM_SOURCE_DIR) / "scripts" / "slurm" / "local_cluster.sh").string();
const std::string kSmallOffice = (fs::path(SEGSLAM_SOURCE_DIR) / "scenarios" / "test" / "office_small.yaml").string();

class SlurmSweepTest : public segslam::testing::CliScratchTest {
 protected:
  SlurmSweepTest() : CliScratchTest("segslam_slurm_") {}

  void SetUp() override {
    CliScratchTest::SetUp();
    cluster_ = dir_ / "slurm";
    const ShellResult started = Shell("bash " + kClusterScript + " start " + cluster_.string());
    if (started.exit_code == 2) GTEST_SKIP() << started.output;
    ASSERT_EQ(started.exit_code, 0) << started.output;
    std::smatch conf;
    ASSERT_TRUE(std::regex_search(started.output, conf, std::regex("export SLURM_CONF=(\\S+)"))) << started.output;
    ::setenv("SLURM_CONF", conf[1].str().c_str(), 1);
    running_ = true;
  }

  void TearDown() override {
    if (running_) Shell("bash " + kClusterScript + " stop " + cluster_.string());
    ::unsetenv("SLURM_CONF");
    CliScratchTest::TearDown();
  }

  // JobState of every record of `job` (an array job has one per task), once none is
  // pending or running; empty after `limit`.
  static std::vector<std::string> FinalStates(const std::string& job, std::chrono::seconds limit) {
    const auto deadline = std::chrono::steady_clock::now() + limit;
    while (std::chrono::steady_clock::now() < deadline) {
      const ShellResult shown = Shell("scontrol -o show job " + job);
      std::vector<std::string> states;
      const std::regex state("JobState=(\\S+)");
      for (auto it = std::sregex_iterator(shown.output.begin(), shown.output.end(), state);
           it != std::sregex_iterator(); ++it) {
        states.push_back((*it)[1].str());
      }
      const bool finished = !states.empty() && std::none_of(states.begin(), states.end(), [](const std::string& s) {
        return s == "PENDING" || s == "RUNNING" || s == "CONFIGURING" || s == "COMPLETING";
      });
      if (finished) return states;
      std::this_thread::sleep_for(500ms);
    }
    return {};
  }

  fs::path cluster_;
  bool running_ = false;
};

TEST_F(SlurmSweepTest, ArrayAndMergeJobGiveTheOneProcessReport) {
  // Three points that differ only in the segmenter's error strength share one dataset:
  // the array's tasks generate it once in their cache.
  const std::string sweep = "sweep " + kSmallOffice +
                            " --set bench.segmenter_strength=0.5,1,2 --frames 12 --repeats 1 --modes plain,mutual "
                            "--segmenter fcis-like -q";
  const CommandOutput one = Run(sweep + " --cache " + (dir_ / "cache_one").string() + " --out " + (dir_ / "one").string());
  ASSERT_EQ(one.exit_code, 0) << one.stderr_text;

  const fs::path emit = dir_ / "emit";
  const CommandOutput emitted = Run(sweep + " --cache " + (dir_ / "cache_array").string() + " --out " +
                                    (dir_ / "array").string() + " --emit-sbatch " + emit.string() +
                                    " --sbatch=--time=20");
  ASSERT_EQ(emitted.exit_code, 0) << emitted.stderr_text;
  EXPECT_NE(emitted.stdout_text.find("3 points as a Slurm array of 3 task(s)"), std::string::npos)
      << emitted.stdout_text;
  EXPECT_NE(ReadText(emit / "sweep_array.sbatch").find("#SBATCH --array=1-3"), std::string::npos);
  EXPECT_NE(ReadText(emit / "sweep_array.sbatch").find("#SBATCH --time=20"), std::string::npos);

  const ShellResult submitted = Shell("bash " + (emit / "submit.sh").string());
  ASSERT_EQ(submitted.exit_code, 0) << submitted.output;
  std::smatch jobs;
  ASSERT_TRUE(std::regex_search(submitted.output, jobs, std::regex("array job (\\d+), merge job (\\d+)")))
      << submitted.output;
  const std::vector<std::string> merge_states = FinalStates(jobs[2].str(), std::chrono::seconds(600));
  const std::vector<std::string> array_states = FinalStates(jobs[1].str(), std::chrono::seconds(10));
  std::string logs;
  for (const auto& entry : fs::directory_iterator(emit / "logs")) {
    logs += "== " + entry.path().filename().string() + "\n" + ReadText(entry.path());
  }
  ASSERT_EQ(merge_states, std::vector<std::string>{"COMPLETED"}) << logs;
  EXPECT_EQ(array_states, std::vector<std::string>(3, "COMPLETED")) << logs;

  // The merged report is the one-process report.
  const nlohmann::json merged = nlohmann::json::parse(ReadText(dir_ / "array" / "sweep_results.json"));
  const nlohmann::json whole = nlohmann::json::parse(ReadText(dir_ / "one" / "sweep_results.json"));
  EXPECT_EQ(merged["points"], whole["points"]);
  EXPECT_EQ(ReadText(dir_ / "array" / "report.md"), ReadText(dir_ / "one" / "report.md"));
  ASSERT_EQ(merged["points"].size(), 3u);

  // One task generated the dataset; the others waited for it or found it made.
  int generated = 0, reused = 0;
  const std::regex generation("generated 24 frames"), reuse("reused|\\(cached; ");
  for (const auto& entry : fs::directory_iterator(emit / "logs")) {
    if (entry.path().filename().string().rfind("array_", 0) != 0) continue;
    const std::string log = ReadText(entry.path());
    generated += std::regex_search(log, generation) ? 1 : 0;
    reused += std::regex_search(log, reuse) ? 1 : 0;
  }
  EXPECT_EQ(generated, 1) << logs;
  EXPECT_EQ(reused, 2) << logs;
}

}  // namespace
}  // namespace segslam::harness
