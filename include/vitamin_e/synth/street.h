#pragma once
// A synthetic town laid out around a drive path (drive_path.h): every straight
// leg of the path runs along the right lane of a street, side streets cross at
// random spacing, and the blocks between the streets are filled with buildings
// of varied width and height whose street faces carry facade textures
// (windows, shop fronts, plaster). Streets have a textured road (asphalt,
// lane markings), raised sidewalks (paving, kerbs) and cars parked along the
// kerbs (about 4.2 x 1.8 x 1.5 m). The whole town is closed by a ring of
// buildings, so that every ray either hits a surface or goes up into the
// flat, untextured sky. All boxes are axis-aligned: the path's straights must
// run along x or y. World frame: z up, road surface at z = 0, metres.
#include <cstdint>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "vitamin_e/synth/drive_path.h"
#include "vitamin_e/synth/scene.h"

namespace vitamin_e::synth {

struct StreetConfig {
  double road_width_m = 10.0;  // kerb to kerb
  double sidewalk_width_m = 3.0;
  double kerb_height_m = 0.15;
  double lane_offset_m = 1.5;  // the path runs this far right of a street's centre line
  double block_min_m = 35.0;   // spacing of side streets [min, max]
  double block_max_m = 80.0;
  double building_width_min_m = 8.0;
  double building_width_max_m = 24.0;
  double building_height_min_m = 7.0;
  double building_height_max_m = 20.0;
  double parking_probability = 0.6;  // chance that a parking slot holds a car
  double margin_m = 70.0;            // town extent beyond the path's bounding box
  double ring_depth_m = 15.0;        // depth of the closing ring of buildings at the border
  double car_clearance_m = 1.3;      // parked cars stay this far (horizontally) from the camera path
  double texel_m = 0.02;             // finest texel, on the faces nearest to the path
  double texel_per_m = 0.0012;       // texel growth with a face's distance from the path
  double max_texel_m = 0.2;
  double sky_intensity = 0.86;
  std::uint64_t seed = 0;
  void validate() const;  // throws std::invalid_argument naming the key
};

// One street: its centre line runs along `axis` (0: x, 1: y) at the other
// coordinate `offset`, over [from, to] along axis.
struct Street {
  int axis = 0;
  double offset = 0.0;
  double from = 0.0, to = 0.0;
  bool on_path = false;  // a street the path drives along (not a side street)
};

// The streets of a town around the path (the path's own streets and side
// streets), and the town's extent. Throws std::invalid_argument if a straight
// leg is not axis-aligned or two of the path's parallel streets are too close.
struct StreetLayout {
  std::vector<Street> streets;
  Eigen::Vector2d min = Eigen::Vector2d::Zero(), max = Eigen::Vector2d::Zero();  // town extent
};
StreetLayout makeStreetLayout(const StreetConfig& config, const DrivePath& path);

// The town as a Scene (boxes of kind "building", "car", "road", "sidewalk").
// Throws std::invalid_argument if the path leaves the road (the car's centre
// must stay 0.9 m inside the roads and intersections).
Scene makeStreetScene(const StreetConfig& config, const DrivePath& path);

}  // namespace vitamin_e::synth
