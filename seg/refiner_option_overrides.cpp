#include "seg/refiner_option_overrides.h"

#include "core/error.h"
#include "core/option_assignment.h"

namespace segslam::seg {

namespace {

constexpr const char* kWhat = "refiner option";

AddUnmatchedRule AddUnmatchedRuleValue(const NumericAssignment& parsed) {
  const int rule = WholeNumberValue(parsed, kWhat);
  if (rule < 0 || rule > 2) {
    throw Error(std::string(kWhat) + " " + parsed.name + ": expected 0 (never), 1 (paper's count rule) or 2 (always), got '" +
                parsed.text + "'");
  }
  return static_cast<AddUnmatchedRule>(rule);
}

#define SEGSLAM_REAL(field) {#field, [](RefinerOptions* o, const NumericAssignment& a) { o->field = a.value; }}
#define SEGSLAM_INT(field) \
  {#field, [](RefinerOptions* o, const NumericAssignment& a) { o->field = WholeNumberValue(a, kWhat); }}
#define SEGSLAM_BOOL(field) \
  {#field, [](RefinerOptions* o, const NumericAssignment& a) { o->field = ZeroOrOneValue(a, kWhat); }}

// Every overridable field; one table serves both functions.
const NamedOptionTable<RefinerOptions>& Table() {
  static const NamedOptionTable<RefinerOptions> table(kWhat, {
      SEGSLAM_REAL(w_barycenter),
      SEGSLAM_REAL(w_shape),
      SEGSLAM_REAL(max_match_cost),
      SEGSLAM_BOOL(require_same_category),
      SEGSLAM_BOOL(fill_missing_depth_with_median),
      SEGSLAM_BOOL(project_depthless_regions_at_far_limit),
      SEGSLAM_REAL(splat_footprint_scale),
      SEGSLAM_INT(hole_fill_iterations),
      SEGSLAM_REAL(depth_tolerance),
      SEGSLAM_REAL(occlusion_tolerance),
      SEGSLAM_REAL(min_depth_m),
      SEGSLAM_INT(min_projected_area_px),
      SEGSLAM_INT(min_far_projected_area_px),
      SEGSLAM_INT(min_matched_area_px),
      SEGSLAM_REAL(replace_min_ratio_gap),
      SEGSLAM_INT(boundary_tolerance_px),
      SEGSLAM_BOOL(trim_instead_of_replace),
      SEGSLAM_BOOL(trim_keeps_region_depth),
      SEGSLAM_BOOL(repair_missing_parts),
      SEGSLAM_REAL(repair_min_current_inside),
      SEGSLAM_REAL(repair_max_projected_covered),
      {"add_unmatched", [](RefinerOptions* o, const NumericAssignment& a) { o->add_unmatched = AddUnmatchedRuleValue(a); }},
      SEGSLAM_INT(min_detections_to_add),
      SEGSLAM_REAL(added_score_decay),
      SEGSLAM_REAL(min_added_score),
      SEGSLAM_REAL(matched_previous_score_weight),
      SEGSLAM_REAL(new_region_score_factor),
      SEGSLAM_REAL(min_new_region_score),
  });
  return table;
}

#undef SEGSLAM_REAL
#undef SEGSLAM_INT
#undef SEGSLAM_BOOL

}  // namespace

void SetRefinerOption(RefinerOptions* options, const std::string& assignment) { Table().Set(options, assignment); }

std::vector<std::string> RefinerOptionNames() { return Table().Names(); }

}  // namespace segslam::seg
