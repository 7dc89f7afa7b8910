#include "seg/refiner_options.h"

namespace segslam::seg {

#define REAL(FIELD, RANGE, UNIT, HELP) SEGSLAM_OPTION_REAL(RefinerOptions, FIELD, RANGE, UNIT, HELP)
#define WHOLE(FIELD, RANGE, UNIT, HELP) SEGSLAM_OPTION_WHOLE(RefinerOptions, FIELD, RANGE, UNIT, HELP)
#define SWITCH(FIELD, HELP) SEGSLAM_OPTION_SWITCH(RefinerOptions, FIELD, HELP)

const OptionRegistry<RefinerOptions>& RefinerOptionRegistry() {
  static const OptionRegistry<RefinerOptions> registry("refiner option", {
      REAL(w_barycenter, AtLeast(0), "", "weight of the barycentre distance (per image diagonal) in the match cost"),
      REAL(w_shape, AtLeast(0), "", "weight of the shape disagreement in the match cost"),
      REAL(max_match_cost, Above(0), "", "a previous and a current region match only below this cost"),
      SWITCH(require_same_category, "match only regions of the same COCO category"),
      SWITCH(fill_missing_depth_with_median, "pixels without depth project at their region's median depth"),
      SWITCH(project_depthless_regions_at_far_limit, "a region without depth projects at the farthest depth measured"),
      REAL(splat_footprint_scale, Closed(0.5, 3), "", "size of each projected point's footprint, times its warped pixel"),
      SWITCH(splat_interior_in_blocks, "a region's inside is splatted 2x2 pixels at a time, its outline pixel by pixel"),
      WHOLE(hole_fill_iterations, Closed(0, 8), "", "passes of depth-aware hole filling after the projection"),
      REAL(depth_tolerance, ClosedOpen(0, 1), "", "relative depth tolerance of the hole filling (and of trims that keep depth)"),
      REAL(occlusion_tolerance, ClosedOpen(0, 1), "", "relative margin by which current depth must lie in front to hide a projected pixel"),
      REAL(min_depth_m, Above(0), "m", "projected points nearer than this are dropped"),
      WHOLE(min_projected_area_px, AtLeast(0), "px", "smaller projected regions are not added back"),
      WHOLE(min_far_projected_area_px, AtLeast(0), "px", "the same for regions projected at the far limit"),
      WHOLE(min_matched_area_px, AtLeast(0), "px", "smaller projected regions are not matched"),
      REAL(replace_min_ratio_gap, ClosedOpen(0, 1), "", "replace (or trim) a region only when the overlap ratios differ by more"),
      WHOLE(boundary_tolerance_px, Closed(0, 16), "px", "pixels this close to the other region count as inside it"),
      SWITCH(trim_instead_of_replace, "a replacement keeps the current pixels near the projection (a trim)"),
      SWITCH(trim_keeps_region_depth, "a trim keeps cut-off pixels at the region's depth"),
      SWITCH(repair_missing_parts, "replace a current region that lost a part of the projected one"),
      REAL(repair_min_current_inside, OpenClosed(0, 1), "", "share of the current region inside the projection for a repair"),
      REAL(repair_max_projected_covered, OpenClosed(0, 1), "", "a repair needs the current region to cover less of the projection"),
      WHOLE(add_unmatched, Closed(0, 2), "", "add unmatched projected regions: 0 never, 1 the paper's count rule, 2 always"),
      WHOLE(min_detections_to_add, AtLeast(1), "", "frames a track must have been detected in before it is added back"),
      REAL(added_score_decay, OpenClosed(0, 1), "", "an added region's score is its previous one times this"),
      REAL(min_added_score, Closed(0, 1), "", "a region scoring below this is no longer added back"),
      REAL(matched_previous_score_weight, Closed(0, 1), "", "a matched region scores at least this times its previous score"),
      REAL(new_region_score_factor, OpenClosed(0, 1), "", "a current region without a match scores its score times this"),
      REAL(min_new_region_score, Closed(0, 1), "", "a new region scoring below this (after the factor) is dropped"),
  });
  return registry;
}

#undef REAL
#undef WHOLE
#undef SWITCH

void SetRefinerOption(RefinerOptions* options, const std::string& assignment) {
  RefinerOptionRegistry().Set(options, assignment);
}

std::vector<std::string> RefinerOptionNames() { return RefinerOptionRegistry().Names(); }

}  // namespace segslam::seg
