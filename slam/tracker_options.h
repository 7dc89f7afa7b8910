// The tracker's tunables (slam/tracker.h, TrackerOptions, with its ORB extractor, pose
// optimiser and local bundle adjustment options) declared once: name, kind, range, unit
// and one line of help (core/option_registry.h). They are set by name for tuning and for
// sweeps without rebuilding (segslam run --tracker, a scenario's bench.tracker);
// `segslam options tracker` lists them.
#pragma once

#include <string>
#include <vector>

#include "core/option_registry.h"
#include "slam/tracker.h"

namespace segslam::slam {

const OptionRegistry<TrackerOptions>& TrackerOptionRegistry();

// Sets the TrackerOptions field `name` (as spelled in slam/tracker.h; nested fields as
// "orb.max_features", "pose_optimizer.rounds") from "name=value". Switches take 0 or 1,
// whole numbers whole numbers. Throws segslam::Error naming the field on an unknown name,
// a malformed value or one outside its range.
void SetTrackerOption(TrackerOptions* options, const std::string& assignment);

// The names SetTrackerOption accepts, sorted.
std::vector<std::string> TrackerOptionNames();

}  // namespace segslam::slam
