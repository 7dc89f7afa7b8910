// Tracker options set by name from the command line ("name=value"), for tuning and for
// sweeps over the tracker's thresholds without rebuilding (segslam run --tracker).
#pragma once

#include <string>
#include <vector>

#include "slam/tracker.h"

namespace segslam::slam {

// Sets the TrackerOptions field `name` (as spelled in slam/tracker.h; ORB extractor
// fields as "orb.max_features") from "name=value". Booleans take 0 or 1, integers whole
// numbers. Throws segslam::Error naming the field on an unknown name or a malformed value.
void SetTrackerOption(TrackerOptions* options, const std::string& assignment);

// The names SetTrackerOption accepts, sorted.
std::vector<std::string> TrackerOptionNames();

}  // namespace segslam::slam
