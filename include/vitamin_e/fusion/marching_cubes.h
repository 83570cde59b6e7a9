#pragma once
// Table-driven marching cubes. The 256-entry case table is not typed in: it is
// derived once from a rule on the cube faces. On every face the crossing edges
// (corners of different sign) are joined by segments; a face with four
// crossings (diagonal corners of equal sign) isolates its inside corners, so
// the choice depends on that face's four signs only and the two cubes sharing a
// face always agree: the surface is closed wherever all corners are observed.
// Segments are oriented with the outside on their left seen from outside the
// cube, chained into loops around the cube and each loop is fanned into
// triangles, whose normals then point to the outside (value >= 0).
// Corner c of a cube sits at offset (c & 1, (c >> 1) & 1, (c >> 2) & 1);
// "inside" means value < 0.
#include <cstdint>
#include <vector>

#include "vitamin_e/fusion/triangle_mesh.h"

namespace vitamin_e::fusion::mc {

// Edge e (0..11) runs along axis e / 4 from corner edgeLowerCorner(e) to
// edgeLowerCorner(e) + (1 << axis).
int edgeAxis(int e);
int edgeLowerCorner(int e);

constexpr int kMaxCentroids = 3;

// Triangles of the case whose inside corners are the set bits of inside_mask,
// as triples of vertex indices, terminated by -1 (at most 12 triangles): 0..11
// the vertex on that edge, 12 + j the centroid of the edge vertices in
// centroidEdges(inside_mask, j) (bit e: edge e). Loops are fanned from a vertex
// whose diagonals all cross the cube's interior; a loop without such a vertex
// is fanned around its centroid (a vertex of this cube only).
const std::int8_t* caseTriangles(int inside_mask);
std::uint16_t centroidEdges(int inside_mask, int j);

// Marching cubes over a dense grid of values (x fastest: x + nx * (y + ny * z))
// at `spacing`, grid point (0, 0, 0) at the origin; vertices shared between
// cubes, no normals.
TriangleMesh marchingCubesGrid(const std::vector<float>& values, int nx, int ny, int nz, float spacing);

}  // namespace vitamin_e::fusion::mc
