#pragma once
// Four floats operated on together (for example a mesh vertex's (inverse depth, gradient x,
// gradient y, 0) in the NLTGV iteration). With SSE2 (every x86-64 CPU) each operation is one
// instruction; elsewhere the same operations run lane by lane (PortableLanes, also what the
// unit test checks the SSE2 type against).
#include <algorithm>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace vitamin_e::common {

struct PortableLanes {
  float v[4];
  static PortableLanes of(float a, float b, float c, float d) { return {{a, b, c, d}}; }
  static PortableLanes all(float a) { return {{a, a, a, a}}; }
  PortableLanes operator+(PortableLanes o) const {
    return {{v[0] + o.v[0], v[1] + o.v[1], v[2] + o.v[2], v[3] + o.v[3]}};
  }
  PortableLanes operator-(PortableLanes o) const {
    return {{v[0] - o.v[0], v[1] - o.v[1], v[2] - o.v[2], v[3] - o.v[3]}};
  }
  PortableLanes operator*(PortableLanes o) const {
    return {{v[0] * o.v[0], v[1] * o.v[1], v[2] * o.v[2], v[3] * o.v[3]}};
  }
  PortableLanes& operator+=(PortableLanes o) { return *this = *this + o; }
  PortableLanes& operator-=(PortableLanes o) { return *this = *this - o; }
  // Each lane into [-bound, bound] (bound >= 0).
  PortableLanes clamp(PortableLanes bound) const {
    PortableLanes r;
    for (int k = 0; k < 4; ++k) r.v[k] = std::max(0.0f - bound.v[k], std::min(bound.v[k], v[k]));
    return r;
  }
  // Lane 0 from `o`, the others from this.
  PortableLanes withFirst(PortableLanes o) const { return {{o.v[0], v[1], v[2], v[3]}}; }
  PortableLanes broadcastFirst() const { return all(v[0]); }
  // The sum of the four lanes, in every lane.
  PortableLanes sumInAll() const { return all((v[0] + v[1]) + (v[2] + v[3])); }
  float operator[](int k) const { return v[k]; }
};

#if defined(__SSE2__)
struct Sse2Lanes {
  __m128 v;
  static Sse2Lanes of(float a, float b, float c, float d) { return {_mm_setr_ps(a, b, c, d)}; }
  static Sse2Lanes all(float a) { return {_mm_set1_ps(a)}; }
  Sse2Lanes operator+(Sse2Lanes o) const { return {_mm_add_ps(v, o.v)}; }
  Sse2Lanes operator-(Sse2Lanes o) const { return {_mm_sub_ps(v, o.v)}; }
  Sse2Lanes operator*(Sse2Lanes o) const { return {_mm_mul_ps(v, o.v)}; }
  Sse2Lanes& operator+=(Sse2Lanes o) { return v = _mm_add_ps(v, o.v), *this; }
  Sse2Lanes& operator-=(Sse2Lanes o) { return v = _mm_sub_ps(v, o.v), *this; }
  Sse2Lanes clamp(Sse2Lanes bound) const {
    return {_mm_max_ps(_mm_sub_ps(_mm_setzero_ps(), bound.v), _mm_min_ps(bound.v, v))};
  }
  Sse2Lanes withFirst(Sse2Lanes o) const { return {_mm_move_ss(v, o.v)}; }
  Sse2Lanes broadcastFirst() const { return {_mm_shuffle_ps(v, v, 0)}; }
  Sse2Lanes sumInAll() const {
    // (v0 + v1, v1 + v0, v2 + v3, v3 + v2), then each pair's sum added to the other's.
    const __m128 t = _mm_add_ps(v, _mm_shuffle_ps(v, v, _MM_SHUFFLE(2, 3, 0, 1)));
    return {_mm_add_ps(t, _mm_shuffle_ps(t, t, _MM_SHUFFLE(1, 0, 3, 2)))};
  }
  float operator[](int k) const {
    alignas(16) float f[4];
    _mm_store_ps(f, v);
    return f[k];
  }
};
using Lanes = Sse2Lanes;
#else
using Lanes = PortableLanes;
#endif

}  // namespace vitamin_e::common
