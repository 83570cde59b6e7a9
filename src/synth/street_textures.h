#pragma once
// Procedural textures of the street scene (street.cpp): facades, cars, road,
// sidewalk, kerbs. Each returns a CV_32FC1 image in [0, 1] in a "canonical"
// layout given per function (rows = one direction in metres / texel, cols =
// the other, row 0 and col 0 at the face's min corner); street.cpp transposes
// it to the face's (u, v) layout. Internal to the synth module.
#include <opencv2/core.hpp>

#include "vitamin_e/synth/texture.h"

namespace vitamin_e::synth::detail {

// Texture size in texels for an extent in metres (at least 2).
int texels(double extent_m, double texel_m);

// A building face with windows, floors, cornices and (street level) shop
// fronts, signs and doors. rows: height from the ground (row 0 at z = 0),
// cols: along the facade.
cv::Mat facadeTexture(double width_m, double height_m, double texel_m, Rng* rng);
// A windowless wall (fire wall, back of a building): plaster and stains.
cv::Mat plainWallTexture(double width_m, double height_m, double texel_m, Rng* rng);

// A car of body intensity `body`. Side: rows = height, cols = along the car
// (wheels, doors, windows). End: rows = height, cols = across (lights, plate,
// window; front or rear). Top: rows = across, cols = along (roof, windows).
cv::Mat carSideTexture(double length_m, double height_m, double texel_m, double body, Rng* rng);
cv::Mat carEndTexture(double width_m, double height_m, double texel_m, double body, bool front, Rng* rng);
cv::Mat carTopTexture(double length_m, double width_m, double texel_m, double body, Rng* rng);

// Asphalt of a road: rows = across (width_m), cols = along (length_m). With
// markings: a dashed centre line, manholes, and zebra crossings within the
// last metres of each end flagged (the ends that meet an intersection).
cv::Mat roadTexture(double length_m, double width_m, double texel_m, bool markings, bool zebra_at_start,
                    bool zebra_at_end, Rng* rng);
// Paving slabs: rows = across, cols = along.
cv::Mat sidewalkTexture(double length_m, double width_m, double texel_m, Rng* rng);
// Kerb stones: rows = height (row 0 at the slab bottom), cols = along.
cv::Mat kerbTexture(double length_m, double height_m, double texel_m, Rng* rng);

// A flat 2 x 2 texture (faces never seen).
cv::Mat flatTexture(float value);

}  // namespace vitamin_e::synth::detail
