#pragma once
// Checks on triangle meshes shared by the fusion tests.
#include <map>
#include <utility>

#include "vitamin_e/fusion/triangle_mesh.h"

namespace vitamin_e::test {

// Directed edges of a mesh that are not matched by exactly one edge in the
// opposite direction (0: closed and consistently oriented).
inline int openEdges(const fusion::TriangleMesh& mesh) {
  std::map<std::pair<int, int>, int> directed;
  for (const auto& f : mesh.faces)
    for (int k = 0; k < 3; ++k) ++directed[{f[k], f[(k + 1) % 3]}];
  int bad = 0;
  for (const auto& [e, c] : directed) {
    const auto it = directed.find({e.second, e.first});
    if (c != 1 || it == directed.end() || it->second != 1) ++bad;
  }
  return bad;
}

}  // namespace vitamin_e::test
