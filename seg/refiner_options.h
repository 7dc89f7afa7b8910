// The refinement's tunables (seg/refiner.h, RefinerOptions) declared once: name, kind,
// range, unit and one line of help (core/option_registry.h). They are set by name for
// tuning without rebuilding: seg-eval --refiner, run --refiner, and a scenario's
// bench.refiner (so a sweep can take one as an axis); `segslam options refiner` lists them.
#pragma once

#include <string>
#include <vector>

#include "core/option_registry.h"
#include "seg/refiner.h"

namespace segslam::seg {

const OptionRegistry<RefinerOptions>& RefinerOptionRegistry();

// Sets the RefinerOptions field `name` (as spelled in seg/refiner.h) from "name=value".
// Switches take 0 or 1, whole numbers whole numbers, add_unmatched 0 (never), 1 (the
// paper's count rule) or 2 (always). Throws segslam::Error naming the field on an unknown
// name, a malformed value or one outside its range.
void SetRefinerOption(RefinerOptions* options, const std::string& assignment);

// The names SetRefinerOption accepts, sorted.
std::vector<std::string> RefinerOptionNames();

}  // namespace segslam::seg
