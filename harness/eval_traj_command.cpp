// `segslam eval-traj GT EST`: ATE and RPE of an estimated TUM trajectory against ground
// truth, computed as the TUM RGB-D benchmark's scripts do (harness/trajectory_metrics.h),
// printed as a table and optionally written as JSON.
#include "core/atomic_file.h"
#include "harness/cli_numbers.h"
#include "harness/commands.h"
#include "harness/trajectory_metrics.h"

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <map>
#include <memory>
#include <optional>
#include <string>

namespace segslam::harness {
namespace {

constexpr double kDegreesPerRadian = 180.0 / 3.14159265358979323846;

struct EvalTrajArgs {
  std::string ground_truth;
  std::string estimate;
  double max_difference_s = 0.02;
  bool no_align = false;
  double rpe_delta = 1;
  std::string rpe_unit = "s";
  std::string json_file;
};

std::string TableRow(const std::string& metric, const ErrorStatistics& s) {
  return fmt::format("{:<22} {:>6} {:>9.6f} {:>9.6f} {:>9.6f} {:>9.6f} {:>9.6f} {:>9.6f}\n",
                     metric, s.count, s.rmse, s.mean, s.median, s.std, s.min, s.max);
}

nlohmann::json StatisticsJson(const ErrorStatistics& s) {
  return {{"count", s.count}, {"rmse", s.rmse}, {"mean", s.mean}, {"median", s.median},
          {"std", s.std},     {"min", s.min},   {"max", s.max}};
}

int RunEvalTraj(const EvalTrajArgs& args) {
  AteOptions ate_options;
  ate_options.max_difference_s = args.max_difference_s;
  ate_options.align = !args.no_align;
  RpeOptions rpe_options;
  rpe_options.delta = args.rpe_delta;
  rpe_options.unit = args.rpe_unit == "f" ? RpeDeltaUnit::kFrames : RpeDeltaUnit::kSeconds;
  const TrajectoryEvaluation evaluation =
      EvaluateTrajectoryFiles(args.ground_truth, args.estimate, ate_options, rpe_options);

  const std::string delta_text =
      fmt::format("{:g} {}", args.rpe_delta, args.rpe_unit == "f" ? "frame(s)" : "s");
  const std::optional<ErrorStatistics> rotation_deg =
      evaluation.rpe ? std::optional(Scaled(evaluation.rpe->rotation_rad, kDegreesPerRadian)) : std::nullopt;
  fmt::print("estimate     {}\nground truth {}\n", args.estimate, args.ground_truth);
  fmt::print("ATE: poses associated within {:g} s, {}\n", args.max_difference_s,
             ate_options.align ? "aligned by Horn's method (rotation and translation, no scale)"
                               : "not aligned (compared in the given frames)");
  fmt::print("RPE: fixed delta {}\n", delta_text);
  fmt::print("{:<22} {:>6} {:>9} {:>9} {:>9} {:>9} {:>9} {:>9}\n", "metric", "pairs", "rmse",
             "mean", "median", "std", "min", "max");
  fmt::print("{}", TableRow("ATE translation [m]", evaluation.ate.translation_m));
  if (evaluation.rpe.has_value()) {
    fmt::print("{}", TableRow("RPE translation [m]", evaluation.rpe->translation_m));
    fmt::print("{}", TableRow("RPE rotation [deg]", *rotation_deg));
  } else {
    fmt::print("RPE: not computed: {}\n", evaluation.rpe_missing_reason);
  }

  if (!args.json_file.empty()) {
    nlohmann::json T_gt_est = nlohmann::json::array();
    for (int row = 0; row < 4; ++row) {
      nlohmann::json values = nlohmann::json::array();
      for (int col = 0; col < 4; ++col) values.push_back(evaluation.ate.T_gt_est.matrix()(row, col));
      T_gt_est.push_back(values);
    }
    const nlohmann::json json = {
        {"ground_truth", args.ground_truth},
        {"estimate", args.estimate},
        {"ate",
         {{"max_difference_s", args.max_difference_s},
          {"aligned", ate_options.align},
          {"T_gt_est", T_gt_est},
          {"translation_m", StatisticsJson(evaluation.ate.translation_m)}}},
        {"rpe", evaluation.rpe.has_value()
                    ? nlohmann::json{{"delta", args.rpe_delta},
                                     {"delta_unit", args.rpe_unit},
                                     {"translation_m", StatisticsJson(evaluation.rpe->translation_m)},
                                     {"rotation_deg", StatisticsJson(*rotation_deg)}}
                    : nlohmann::json{{"delta", args.rpe_delta},
                                     {"delta_unit", args.rpe_unit},
                                     {"missing_reason", evaluation.rpe_missing_reason}}}};
    WriteFileAtomically(args.json_file, json.dump(2) + "\n");
  }
  return 0;
}

}  // namespace

void AddEvalTrajCommand(CLI::App& app, std::function<int()>* action) {
  auto args = std::make_shared<EvalTrajArgs>();
  CLI::App* command = app.add_subcommand(
      "eval-traj",
      "ATE and RPE of an estimated TUM trajectory against ground truth, as TUM's "
      "evaluate_ate.py and evaluate_rpe.py --fixed_delta compute them");
  command->add_option("ground_truth", args->ground_truth, "Ground-truth TUM trajectory file")
      ->required();
  command->add_option("estimate", args->estimate, "Estimated TUM trajectory file")->required();
  command->add_option("--max-difference", args->max_difference_s,
                      "ATE: largest stamp difference of an associated pose pair, seconds")
      ->check(NumberIn(0, 1e6, /*min_excluded=*/true))
      ->capture_default_str();
  command->add_flag("--no-align", args->no_align,
                    "ATE: compare in the given frames, without Horn alignment (e.g. an "
                    "estimate relocalized in a map in the ground truth's frame)");
  command->add_option("--rpe-delta", args->rpe_delta, "RPE: distance of the compared poses")
      ->check(NumberIn(0, 1e6, /*min_excluded=*/true))
      ->capture_default_str();
  command->add_option("--rpe-unit", args->rpe_unit, "RPE: unit of --rpe-delta, s or f (frames)")
      ->check(CLI::IsMember({"s", "f"}))
      ->capture_default_str();
  command->add_option("--json", args->json_file, "Also write the results to this JSON file");
  command->callback([args, action] { *action = [args] { return RunEvalTraj(*args); }; });
}

}  // namespace segslam::harness
