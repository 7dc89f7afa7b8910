// Fuzz target: the scenario parser (scenes/scenario.h), from YAML text. Every accepted
// scenario must survive the documented round trip: ParseScenario(Dump(ScenarioToYaml(s)))
// accepts it again and gives the same effective configuration.
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>

#include <yaml-cpp/yaml.h>

#include "scenes/scenario.h"
#include "tests/fuzz/fuzz_util.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace segslam;
  const std::string text(reinterpret_cast<const char*>(data), size);
  std::optional<scenes::Scenario> scenario;
  if (fuzz::Refused([&] { scenario = scenes::ParseScenario(text, "fuzz.yaml"); })) return 0;

  const std::string dumped = YAML::Dump(scenes::ScenarioToYaml(*scenario));
  std::optional<scenes::Scenario> again;
  try {
    again = scenes::ParseScenario(dumped, "round-trip.yaml");
  } catch (const Error& e) {
    fuzz::PropertyBroken(std::string("an accepted scenario's effective configuration is refused: ") + e.what() +
                         "\n--- effective configuration:\n" + dumped);
  }
  const std::string dumped_again = YAML::Dump(scenes::ScenarioToYaml(*again));
  if (dumped_again != dumped) {
    fuzz::PropertyBroken("the effective configuration changes when re-read:\n--- first:\n" + dumped +
                         "\n--- re-read:\n" + dumped_again);
  }
  return 0;
}
