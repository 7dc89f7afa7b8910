// The maps of the paper (section III.C): keyframes and 3-D points.
//
// One Map holds the points the tracker matches against. Each point remembers which
// feature set it came from (background `A`, or a static instance of `B_s`), so the
// long-term map can be taken as the background points only (DESIGN.md, core step 5).
// Points loaded from a long-term map file are `fixed`: they are matched like any other
// point but never moved by bundle adjustment, never culled, and never written back, so
// a localization run (the paper's second pass) cannot pollute the map it runs on.
//
// Ownership: the Map owns points and keyframes; everything else refers to them by
// pointer. Points are marked `bad` instead of being freed while frames may still point at
// them; PurgeBadPoints() frees them at a moment the tracker chooses.
#pragma once

#include <cstdint>
#include <map>
#include <memory>
#include <unordered_map>
#include <vector>

#include <Eigen/Geometry>

#include "core/camera.h"
#include "slam/map_file.h"
#include "slam/orb_descriptor.h"
#include "slam/orb_extractor.h"

namespace segslam::slam {

struct Keyframe;

// Orders keyframes by id, so iterating a point's observations (and what is computed
// from them) does not depend on where the keyframes happen to lie in memory.
struct KeyframeIdLess {
  bool operator()(const Keyframe* a, const Keyframe* b) const;
};

struct MapPoint {
  std::uint64_t id = 0;
  Eigen::Vector3d position_w = Eigen::Vector3d::Zero();
  OrbDescriptor descriptor{};               // the most central of its observations
  Eigen::Vector3d viewing_direction_w = Eigen::Vector3d::UnitZ();  // mean unit ray
  float min_distance_m = 0;                 // range where its descriptor's scale applies
  float max_distance_m = 0;
  std::uint16_t instance_id = 0;            // 0: background (set A)
  // For a background point made within the margin of an instance not judged yet, where
  // no margin kept such features out (a run's first frames: see TrackerOptions::
  // instance_margin_around_unjudged_at_start), that instance, whose outline it may be:
  // the point waits for the verdict out of the fine pose, the map's keyframes and the
  // culling, and goes with the instance if it is judged moving. 0: none, or released.
  std::uint16_t bordered_unjudged_instance = 0;
  bool fixed = false;                       // from a loaded long-term map
  bool bad = false;
  std::array<std::uint8_t, 3> color_rgb{};
  std::uint64_t first_keyframe_id = 0;
  double first_stamp_s = 0;                 // when it was made (not stored in map files)
  int visible_count = 1;                    // frames whose frustum it was in
  int found_count = 1;                      // frames that matched it
  int num_loaded_observations = 0;          // observations recorded in the map file
  // Frames with instance masks that matched it (its own first included), and how many
  // of them saw it on an instance. A point made where a mask missed an object is labelled
  // background for good; the later frames that see it on the object keep it out of the
  // long-term map (SeenMostlyOnInstances).
  int labelled_sightings = 0;
  int instance_sightings = 0;
  // The same for instances of a moveable class (core/coco.h): made on one, and sightings.
  bool made_on_moveable = false;
  int moveable_sightings = 0;
  std::map<Keyframe*, int, KeyframeIdLess> observations;  // keyframe -> keypoint index
  // Bookkeeping of the tracker, so one frame does not match or count a point twice.
  int last_matched_frame = -1;
  int last_visible_frame = -1;

  int NumObservations() const {
    return static_cast<int>(observations.size()) + num_loaded_observations;
  }
  double FoundRatio() const { return double(found_count) / std::max(1, visible_count); }
  // At least half of its labelled sightings were on an instance: not known to stay put.
  bool SeenMostlyOnInstances() const {
    return instance_sightings > 0 && 2 * instance_sightings >= labelled_sightings;
  }
  bool SeenMostlyOnMoveableInstances() const {
    return moveable_sightings > 0 && 2 * moveable_sightings >= labelled_sightings;
  }
  // Pyramid level at which a point at `distance_m` should be detected (ORB-SLAM's
  // scale prediction), clamped to the pyramid.
  int PredictLevel(double distance_m, const OrbExtractor& extractor) const;
};

struct Keyframe {
  std::uint64_t id = 0;
  int frame_index = 0;
  double stamp_s = 0;
  Eigen::Isometry3d T_cw = Eigen::Isometry3d::Identity();
  FrameFeatures features;
  std::vector<MapPoint*> points;  // per keypoint; nullptr = none
  // Per keypoint: the instance it lay on (0: background; empty without masks), and its
  // colour, for points made later on what this keyframe kept out (map_instances_on_verdict).
  std::vector<std::uint16_t> instance;
  std::vector<std::array<std::uint8_t, 3>> color_rgb;
  bool bad = false;

  Eigen::Isometry3d T_wc() const { return T_cw.inverse(); }
  Eigen::Vector3d Center() const { return T_cw.inverse().translation(); }
};

class Map {
 public:
  Map() = default;
  Map(const Map&) = delete;
  Map& operator=(const Map&) = delete;

  Keyframe* AddKeyframe(std::unique_ptr<Keyframe> keyframe);
  MapPoint* AddPoint(std::unique_ptr<MapPoint> point);

  // Records that keypoint `index` of `keyframe` observes `point`.
  static void AddObservation(MapPoint* point, Keyframe* keyframe, int index);
  // Removes every observation of the point and marks it bad.
  static void MarkBad(MapPoint* point);
  // Recomputes descriptor (the one with the least median distance to the others, as
  // ORB-SLAM) and viewing direction / distance range from the observations.
  static void UpdatePointStatistics(MapPoint* point, const OrbExtractor& extractor);

  // Frees bad points. Pointers to them held outside the map must be gone by then.
  void PurgeBadPoints();

  // Adds the points of a long-term map file as fixed points.
  void LoadFixedPoints(const LongTermMapData& data);
  // Background points with at least `min_observations` observations (fixed ones
  // included) as a long-term map, leaving out those seen mostly on instances;
  // `keep_fixed_instances` leaves out only those made or seen mostly on instances of a
  // moveable class; `include_instances` keeps every point instead (the `plain`
  // baseline, which knows no instances).
  LongTermMapData ToLongTermMap(const PinholeCamera& camera, bool include_instances, int min_observations,
                                bool keep_fixed_instances = false) const;

  const std::vector<std::unique_ptr<Keyframe>>& keyframes() const { return keyframes_; }
  const std::vector<std::unique_ptr<MapPoint>>& points() const { return points_; }
  size_t NumGoodPoints() const;
  std::uint64_t NextPointId() { return next_point_id_++; }
  // The id the next point will get (ids only grow: a point made later has a larger one).
  std::uint64_t UpcomingPointId() const { return next_point_id_; }
  std::uint64_t NextKeyframeId() { return next_keyframe_id_++; }

 private:
  std::vector<std::unique_ptr<Keyframe>> keyframes_;
  std::vector<std::unique_ptr<MapPoint>> points_;
  std::uint64_t next_point_id_ = 1;
  std::uint64_t next_keyframe_id_ = 1;
};

}  // namespace segslam::slam
