#pragma once
// The building blocks of the procedural textures (texture.cpp), shared with the
// street textures (street_textures.cpp). Internal to the synth module.
#include <opencv2/core.hpp>

#include "vitamin_e/synth/texture.h"

namespace vitamin_e::synth::detail {

// One octave of value noise with the given wavelength [texels], added into dst
// (CV_32FC1) with the given amplitude.
void addValueNoise(cv::Mat* dst, double wavelength_px, double amplitude, Rng* rng);
// Hard-edged discs, rotated rectangles and strokes of size in [min_m, max_m]
// (log-uniform), per_m2 of them, values in [-amplitude, amplitude], added into dst.
void addShapes(cv::Mat* dst, double texel_m, double min_m, double max_m, double per_m2, double amplitude, Rng* rng);

}  // namespace vitamin_e::synth::detail
