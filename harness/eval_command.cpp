// `segslam eval RUN_DIR --dataset DATASET [--json FILE]`: scores a run output of
// `segslam run` against the dataset's ground truth (harness/run_evaluation.h) and prints
// one table; --json writes every figure (atomically).
#include <memory>
#include <string>

#include <fmt/core.h>

#include "core/atomic_file.h"
#include "harness/commands.h"
#include "harness/run_evaluation.h"

namespace segslam::harness {
namespace {

struct EvalArgs {
  std::string run_dir;
  std::string dataset;
  std::string json_file;
};

int RunEval(const EvalArgs& args) {
  const RunEvaluation evaluation = EvaluateRun(args.run_dir, args.dataset);
  fmt::print("run     {}\ndataset {}\n", args.run_dir, args.dataset);
  fmt::print("ATE as evaluate_ate.py (pass 2: in pass 1's aligned map frame); RPE as evaluate_rpe.py "
             "--fixed_delta, delta 1 s\n\n");
  fmt::print("{}", evaluation.Table());
  if (!args.json_file.empty()) {
    WriteFileAtomically(args.json_file, evaluation.ToJson().dump(2) + "\n");
    fmt::print("\nwrote {}\n", args.json_file);
  }
  return 0;
}

}  // namespace

void AddEvalCommand(CLI::App& app, std::function<int()>* action) {
  auto args = std::make_shared<EvalArgs>();
  CLI::App* command = app.add_subcommand(
      "eval", "Score a run output of `segslam run` against its dataset: ATE, RPE, localization, raw vs refined "
              "masks, moving-object detection");
  command->add_option("run_dir", args->run_dir, "Output folder of segslam run (with pass1/ and pass2/, or one sequence)")
      ->required();
  command->add_option("--dataset", args->dataset, "The dataset the run read (generated two-pass, or a TUM sequence)")
      ->required();
  command->add_option("--json", args->json_file, "Also write the results to this JSON file");
  command->callback([args, action] { *action = [args] { return RunEval(*args); }; });
}

}  // namespace segslam::harness
