#pragma once
// An indexed triangle mesh in the world frame (output of the TSDF) and its PLY writer.
#include <Eigen/Core>
#include <string>
#include <vector>

namespace vitamin_e::fusion {

struct TriangleMesh {
  std::vector<Eigen::Vector3f> vertices;  // world frame
  std::vector<Eigen::Vector3f> normals;   // unit, per vertex, pointing to free space (empty: none)
  std::vector<Eigen::Vector3i> faces;     // counter-clockwise seen from free space
};

// Writes a PLY file (binary little endian by default, ascii on request) with
// vertex positions, normals (when present) and faces. Returns false (and fills
// *error) when the file cannot be written.
bool saveMeshPly(const TriangleMesh& mesh, const std::string& path, std::string* error = nullptr, bool binary = true);

}  // namespace vitamin_e::fusion
