#pragma once
// Rounding to the nearest integer with ties away from zero, as std::lround, but inline: the libm
// call was a tenth of the TSDF's voxel loop and of the tracker's hill climb (callgrind).
// For |x| < 2^31 only (pixel coordinates): the truncation and x - i are then exact, so the result
// is lround's to the bit.

namespace vitamin_e::common {

inline int roundHalfAway(double x) {
  const int i = static_cast<int>(x);
  const double f = x - static_cast<double>(i);
  return i + (f >= 0.5 ? 1 : 0) - (f <= -0.5 ? 1 : 0);
}

inline int roundHalfAway(float x) {
  const int i = static_cast<int>(x);
  const float f = x - static_cast<float>(i);
  return i + (f >= 0.5f ? 1 : 0) - (f <= -0.5f ? 1 : 0);
}

}  // namespace vitamin_e::common
