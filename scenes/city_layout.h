// The city's street cross-section and vehicle footprints, shared by the city builder
// (city.cpp) and the scenario checks that depend on them (scenario.cpp).
//
// Each side of a street, from the curb: a parking lane as wide as the widest parked
// vehicle (trucks; buses do not park) with its curb gap, then the driving lane, whose
// centre line the widest moving vehicle (a bus) keeps 0.2 m clear of the parking lane.
// Cars drive on the right; the camera car drives on the centre line of the right lane.
#pragma once

namespace segslam::scenes::city_layout {

// Footprints, half length along the heading and half width across it, metres.
struct VehicleDims {
  double half_length, half_width;
};
constexpr VehicleDims kCarDims{2.45, 1.12}, kTruckDims{3.6, 1.2}, kBusDims{5.6, 1.3};  // cars with mirrors

constexpr double kCurbGapM = 0.15;  // a parked vehicle's side to the curb
constexpr double kParkingLaneM = kCurbGapM + 2 * kTruckDims.half_width;
constexpr double kLaneToParkingM = kBusDims.half_width + 0.2;

// The camera rides on a car of kCarDims, on its centre line, this far behind its front
// bumper.
constexpr double kCameraToBumperM = 2.0;

// Distance of the driving lane's centre line (the camera's lane) from the street's centre
// line, for a road `road_width_m` wide from curb to curb.
constexpr double DrivingLaneOffsetM(double road_width_m) {
  return road_width_m / 2 - kParkingLaneM - kLaneToParkingM;
}
// Distance of the driving lanes' outer edges (the parking lanes' lines) from the street's
// centre line.
constexpr double DrivingLanesHalfWidthM(double road_width_m) { return road_width_m / 2 - kParkingLaneM; }

// Across a sidewalk, from the curb: trees and lamp posts on one line, benches with their
// backs to the buildings. Pedestrians walk in the strip between, their bodies clear.
constexpr double kFurnitureLineM = 0.7;      // trunks' and posts' centres
constexpr double kMaxTrunkRadiusM = 0.2;
constexpr double kBenchFromFarEdgeM = 0.45;  // a bench's centre, from the sidewalk's far edge
constexpr double kBenchFrontM = 0.22;        // its seat's front, ahead of its centre
constexpr double kWalkerClearanceM = 0.3;    // a pedestrian's half-width, and a little
constexpr double kWalkStripNearM = kFurnitureLineM + kMaxTrunkRadiusM + kWalkerClearanceM;
constexpr double kWalkStripFarM = kBenchFromFarEdgeM + kBenchFrontM + kWalkerClearanceM;  // from the far edge
// The narrowest sidewalk a scenario may ask for (city.sidewalk_width_m): the strip exists.
constexpr double kMinSidewalkWidthM = 2.5;
static_assert(kWalkStripNearM <= kMinSidewalkWidthM - kWalkStripFarM, "no walking strip on the narrowest sidewalk");

}  // namespace segslam::scenes::city_layout
