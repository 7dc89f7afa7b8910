// `segslam options tracker | refiner`: every tunable that --tracker / --refiner (and a
// scenario's bench.tracker / bench.refiner) can set, with its default, range, unit and
// one line of help, from the one declaration of each (slam/tracker_options.h,
// seg/refiner_options.h). --json gives the same as JSON.
#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <memory>
#include <string>

#include "core/option_registry.h"
#include "harness/commands.h"
#include "seg/refiner_options.h"
#include "slam/tracker_options.h"

namespace segslam::harness {
namespace {

struct OptionsArgs {
  std::string which;
  bool json = false;
};

template <typename Options>
int PrintOptions(const OptionRegistry<Options>& registry, const std::string& flag, bool as_json) {
  const Options defaults;
  if (as_json) {
    nlohmann::json list = nlohmann::json::array();
    for (const auto& spec : registry.specs()) {
      list.push_back({{"name", spec.name},
                      {"default", OptionValueJson(spec.get(defaults), spec.kind)},
                      {"range", DescribeOptionRange(spec.range, spec.kind)},
                      {"unit", spec.unit},
                      {"help", spec.help}});
    }
    fmt::print("{}\n", list.dump(2));
    return 0;
  }
  std::size_t name_width = 4;
  for (const auto& spec : registry.specs()) name_width = std::max(name_width, spec.name.size());
  fmt::print("{} options, set with {} NAME=VALUE (repeatable)\n", registry.specs().size(), flag);
  fmt::print("{:<{}}  {:>8}  {:<16}  {}\n", "name", name_width, "default", "range", "what it does");
  for (const auto& spec : registry.specs()) {
    fmt::print("{:<{}}  {:>8}  {:<16}  {}\n", spec.name, name_width, FormatOptionValue(spec.get(defaults)),
               registry.RangeText(spec), spec.help);
  }
  return 0;
}

}  // namespace

void AddOptionsCommand(CLI::App& app, std::function<int()>* action) {
  auto args = std::make_shared<OptionsArgs>();
  CLI::App* cmd = app.add_subcommand(
      "options", "List the tunables of the tracker or the mask refinement: name, default, range, unit, help");
  cmd->add_option("which", args->which, "tracker (run --tracker, bench.tracker) or refiner (--refiner, bench.refiner)")
      ->required()
      ->check(CLI::IsMember({"tracker", "refiner"}));
  cmd->add_flag("--json", args->json, "Print the list as JSON");
  cmd->callback([args, action] {
    *action = [args] {
      if (args->which == "tracker") return PrintOptions(slam::TrackerOptionRegistry(), "--tracker", args->json);
      return PrintOptions(seg::RefinerOptionRegistry(), "--refiner", args->json);
    };
  });
}

}  // namespace segslam::harness
