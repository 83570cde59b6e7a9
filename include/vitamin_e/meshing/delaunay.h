#pragma once
// 2D Delaunay triangulation (incremental Bowyer-Watson): points are inserted in
// a spatially coherent order (grid-cell snake order), each located by a
// visibility walk from the last created triangle, and the cavity of triangles
// whose circumcircle contains the point is re-triangulated as a fan. Expected
// O(n) for well-spread points (a few ms for 10^4 points).
#include <Eigen/Core>
#include <vector>

namespace vitamin_e::meshing {

// Triangles as indices into `points`, counter-clockwise in a y-up frame (i.e.
// orient2d > 0; in image coordinates with y down they appear clockwise).
// Exact duplicate points are skipped (they appear in no triangle). Fewer than 3
// points or all collinear -> no triangles.
std::vector<Eigen::Vector3i> delaunayTriangulate(const std::vector<Eigen::Vector2d>& points);

// > 0 if a, b, c turn counter-clockwise (y up), < 0 clockwise, 0 collinear.
double orient2d(const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Eigen::Vector2d& c);
// > 0 if d is strictly inside the circumcircle of the counter-clockwise triangle a, b, c.
double inCircle(const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Eigen::Vector2d& c, const Eigen::Vector2d& d);

}  // namespace vitamin_e::meshing
