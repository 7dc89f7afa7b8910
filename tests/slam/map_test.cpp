// The long-term map taken from a tracking map: background only (DESIGN.md, core step 5),
// or, keeping fixed instances, everything but what lies on moveable ones.
#include "slam/map.h"

#include <gtest/gtest.h>

#include <memory>

namespace segslam::slam {
namespace {

// A map of two keyframes and one point per case, seen by both.
class MapExportTest : public ::testing::Test {
 protected:
  MapPoint* AddPoint(std::uint16_t instance_id, int labelled_sightings, int instance_sightings) {
    auto point = std::make_unique<MapPoint>();
    point->id = map_.NextPointId();
    point->position_w = Eigen::Vector3d(static_cast<double>(point->id), 0, 5);
    point->instance_id = instance_id;
    point->labelled_sightings = labelled_sightings;
    point->instance_sightings = instance_sightings;
    MapPoint* added = map_.AddPoint(std::move(point));
    for (Keyframe* keyframe : keyframes_) {
      keyframe->points.push_back(nullptr);
      Map::AddObservation(added, keyframe, static_cast<int>(keyframe->points.size()) - 1);
    }
    return added;
  }
  // A point on an instance of a moveable class, `moveable_sightings` of its sightings
  // on such instances.
  MapPoint* AddMoveablePoint(std::uint16_t instance_id, int labelled_sightings, int moveable_sightings) {
    MapPoint* point = AddPoint(instance_id, labelled_sightings, moveable_sightings);
    point->made_on_moveable = instance_id != 0;
    point->moveable_sightings = moveable_sightings;
    return point;
  }
  bool Exported(const MapPoint* point, bool include_instances, bool keep_fixed_instances = false) const {
    const LongTermMapData data = map_.ToLongTermMap(camera_, include_instances, 2, keep_fixed_instances);
    for (const StoredMapPoint& stored : data.points) {
      if (stored.id == point->id) return true;
    }
    return false;
  }
  void SetUp() override {
    for (int k = 0; k < 2; ++k) {
      auto keyframe = std::make_unique<Keyframe>();
      keyframe->id = map_.NextKeyframeId();
      keyframes_.push_back(map_.AddKeyframe(std::move(keyframe)));
    }
  }

  PinholeCamera camera_ = PinholeCamera::FromVerticalFov(640, 480, 50);
  Map map_;
  std::vector<Keyframe*> keyframes_;
};

TEST_F(MapExportTest, BackgroundPointsAreKeptInstancePointsOnlyWithInstances) {
  const MapPoint* background = AddPoint(0, 6, 0);
  const MapPoint* static_car = AddPoint(3, 6, 6);
  EXPECT_TRUE(Exported(background, false));
  EXPECT_FALSE(Exported(static_car, false));
  EXPECT_TRUE(Exported(static_car, true));
}

// A point made on a frame whose mask missed a walker is labelled background; the frames
// that see it on the walker afterwards keep it out, while a background point a passer-by
// hid once stays.
TEST_F(MapExportTest, BackgroundPointSeenMostlyOnInstancesIsLeftOut) {
  const MapPoint* missed_walker = AddPoint(0, 5, 4);
  const MapPoint* half_and_half = AddPoint(0, 4, 2);
  const MapPoint* hidden_once = AddPoint(0, 9, 1);
  const MapPoint* never_labelled = AddPoint(0, 0, 0);  // plain mode: no masks
  EXPECT_FALSE(Exported(missed_walker, false));
  EXPECT_FALSE(Exported(half_and_half, false));
  EXPECT_TRUE(Exported(hidden_once, false));
  EXPECT_TRUE(Exported(never_labelled, false));
  EXPECT_TRUE(Exported(missed_walker, true));
}

// Keeping fixed instances: a desk's points stay, a chair's go, and so does a point made
// on the desk that a person sitting at it covered in most later sightings.
TEST_F(MapExportTest, KeepingFixedInstancesLeavesOutOnlyWhatLiesOnMoveableOnes) {
  const MapPoint* background = AddPoint(0, 6, 0);
  const MapPoint* desk = AddPoint(2, 6, 6);
  const MapPoint* chair = AddMoveablePoint(7, 6, 6);
  MapPoint* desk_under_a_sitter = AddPoint(2, 6, 6);
  desk_under_a_sitter->moveable_sightings = 4;
  MapPoint* desk_passed_once = AddPoint(2, 6, 6);
  desk_passed_once->moveable_sightings = 1;
  const MapPoint* missed_walker = AddMoveablePoint(0, 5, 4);  // made as background
  EXPECT_TRUE(Exported(background, false, true));
  EXPECT_TRUE(Exported(desk, false, true));
  EXPECT_FALSE(Exported(chair, false, true));
  EXPECT_FALSE(Exported(desk_under_a_sitter, false, true));
  EXPECT_TRUE(Exported(desk_passed_once, false, true));
  EXPECT_FALSE(Exported(missed_walker, false, true));
  // Without keeping fixed instances the desk goes too.
  EXPECT_FALSE(Exported(desk, false, false));
  EXPECT_TRUE(Exported(chair, true, true));
}

}  // namespace
}  // namespace segslam::slam
