// Refinement options set by name ("name=value"), for tuning without rebuilding: seg-eval
// --refiner, run --refiner, and a scenario's bench.refiner (so a sweep can take one as an
// axis).
#pragma once

#include <string>
#include <vector>

#include "seg/refiner.h"

namespace segslam::seg {

// Sets the RefinerOptions field `name` (as spelled in seg/refiner.h) from "name=value".
// Booleans take 0 or 1, integers whole numbers, add_unmatched 0 (never), 1 (the paper's
// count rule) or 2 (always). Throws segslam::Error naming the field on an unknown name or
// a malformed value. Ranges are RefinerOptions::IsValid's to check, once all are set.
void SetRefinerOption(RefinerOptions* options, const std::string& assignment);

// The names SetRefinerOption accepts, sorted.
std::vector<std::string> RefinerOptionNames();

}  // namespace segslam::seg
