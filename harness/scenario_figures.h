// The figures of a scenario report: which files it shows, with their captions, and
// drawing them (with harness/report_figures.h) from the runs of a finished report.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "harness/scenario_report.h"

namespace segslam::harness {

// A picture of the report, relative to the report directory, drawn by DrawReportFigures;
// the report shows each figure whose file exists (one that could not be drawn is
// missing, and `scenario run` says why).
struct PlannedFigure {
  std::string file;
  std::string caption;
};

// The report's figures whose files exist in `report_dir`, in the order the report shows
// them (none for an empty path).
std::vector<PlannedFigure> PresentFigures(const std::filesystem::path& report_dir);

// Draws the report's figures into report.report_dir/figures/: top views of both passes
// (as the paper's Fig. 4), and for one frame of pass 1 of the mutual run of median ATE
// the raw vs refined masks (Fig. 5) and the features kept vs dropped (Fig. 6; this runs
// that pass again with feature records, as they are not saved). A figure that cannot be
// drawn (e.g. the mutual mode did not run) is skipped; the returned lines say which and
// why.
std::vector<std::string> DrawReportFigures(const ScenarioReport& report);

}  // namespace segslam::harness
