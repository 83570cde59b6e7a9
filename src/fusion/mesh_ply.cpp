#include <cstdint>
#include <cstring>
#include <fstream>

#include "vitamin_e/fusion/triangle_mesh.h"

namespace vitamin_e::fusion {

namespace {
bool fail(std::string* error, const std::string& msg) {
  if (error) *error = msg;
  return false;
}
template <typename T>
void put(std::ofstream& out, T v) {
  char buf[sizeof(T)];
  std::memcpy(buf, &v, sizeof(T));  // little-endian hosts only (x86, arm64)
  out.write(buf, sizeof(T));
}
}  // namespace

bool saveMeshPly(const TriangleMesh& mesh, const std::string& path, std::string* error, bool binary) {
  const bool normals = !mesh.normals.empty();
  if (normals && mesh.normals.size() != mesh.vertices.size())
    return fail(error, "saveMeshPly: normals.size() != vertices.size()");
  for (const auto& f : mesh.faces)
    for (int k = 0; k < 3; ++k)
      if (f[k] < 0 || f[k] >= static_cast<int>(mesh.vertices.size()))
        return fail(error, "saveMeshPly: face index out of range");
  std::ofstream out(path, std::ios::binary);
  if (!out) return fail(error, "cannot open '" + path + "' for writing");
  out << "ply\nformat " << (binary ? "binary_little_endian" : "ascii") << " 1.0\n"
      << "comment vitamin_e TSDF mesh (world frame)\n"
      << "element vertex " << mesh.vertices.size() << "\n"
      << "property float x\nproperty float y\nproperty float z\n";
  if (normals) out << "property float nx\nproperty float ny\nproperty float nz\n";
  out << "element face " << mesh.faces.size() << "\nproperty list uchar int vertex_indices\nend_header\n";
  for (std::size_t i = 0; i < mesh.vertices.size(); ++i) {
    const auto& v = mesh.vertices[i];
    if (binary) {
      for (int k = 0; k < 3; ++k) put<float>(out, v[k]);
      if (normals)
        for (int k = 0; k < 3; ++k) put<float>(out, mesh.normals[i][k]);
    } else {
      out << v.x() << ' ' << v.y() << ' ' << v.z();
      if (normals) out << ' ' << mesh.normals[i].x() << ' ' << mesh.normals[i].y() << ' ' << mesh.normals[i].z();
      out << '\n';
    }
  }
  for (const auto& f : mesh.faces) {
    if (binary) {
      put<std::uint8_t>(out, 3);
      for (int k = 0; k < 3; ++k) put<std::int32_t>(out, f[k]);
    } else {
      out << "3 " << f[0] << ' ' << f[1] << ' ' << f[2] << '\n';
    }
  }
  out.flush();
  if (!out) return fail(error, "write error on '" + path + "'");
  return true;
}

}  // namespace vitamin_e::fusion
