// Registration of the CLI's subcommands. Each Add*Command adds its options to `app`
// and, when its subcommand is chosen, stores the work to run in `*action`.
#pragma once

#include <CLI/CLI.hpp>

#include <functional>

namespace segslam::harness {

void AddGenerateCommand(CLI::App& app, std::function<int()>* action);
void AddBenchCommand(CLI::App& app, std::function<int()>* action);
// `bench aliasing`, added under the `bench` subcommand by AddBenchCommand.
void AddBenchAliasingCommand(CLI::App& bench, std::function<int()>* action);
void AddPreviewCommand(CLI::App& app, std::function<int()>* action);
void AddSegEvalCommand(CLI::App& app, std::function<int()>* action);
void AddEvalTrajCommand(CLI::App& app, std::function<int()>* action);
void AddRunCommand(CLI::App& app, std::function<int()>* action);
void AddEvalCommand(CLI::App& app, std::function<int()>* action);
void AddScenarioCommand(CLI::App& app, std::function<int()>* action);
void AddSweepCommand(CLI::App& app, std::function<int()>* action);
void AddMasksCommand(CLI::App& app, std::function<int()>* action);
void AddOptionsCommand(CLI::App& app, std::function<int()>* action);
// `scenario suite`, added under the `scenario` subcommand by AddScenarioCommand.
void AddSuiteCommand(CLI::App& scenario, std::function<int()>* action);

}  // namespace segslam::harness
