// The ~mesh stream's bookkeeping (MeshBlockMarkers), without a ROS master: one
// TRIANGLE_LIST per TSDF block with an id that stays the block's, only the changed
// blocks in an update, DELETE for a block that lost its surface, DELETEALL when
// everything is replaced; a viewer that applies the updates as rviz does holds the
// TSDF's mesh after each one, and full() alone gives a late viewer the same.
#include <gtest/gtest.h>

#include <array>
#include <map>

#include "sphere_views.h"
#include "vitamin_e/fusion/tsdf_volume.h"
#include "vitamin_e/ros/mesh_markers.h"

using namespace vitamin_e;
using Eigen::Isometry3d;
using Eigen::Vector3d;
using visualization_msgs::Marker;
using vitamin_e_ros::MeshBlockMarkers;

namespace {

using Triangle = std::array<double, 9>;

// An rviz MarkerArray display: markers by (ns, id), ADD replaces, DELETE and DELETEALL remove.
struct Viewer {
  std::map<std::pair<std::string, int>, Marker> markers;
  void apply(const visualization_msgs::MarkerArray& array) {
    for (const Marker& m : array.markers) {
      if (m.action == Marker::DELETEALL) {
        markers.clear();
      } else if (m.action == Marker::DELETE) {
        EXPECT_EQ(markers.erase({m.ns, m.id}), 1u) << "DELETE of a marker never added: " << m.id;
      } else {
        ASSERT_EQ(m.action, Marker::ADD);
        ASSERT_EQ(m.type, Marker::TRIANGLE_LIST);
        ASSERT_EQ(m.points.size() % 3, 0u);
        ASSERT_TRUE(m.colors.empty() || m.colors.size() == m.points.size());
        markers[{m.ns, m.id}] = m;
      }
    }
  }
  std::vector<Triangle> triangles() const {
    std::vector<Triangle> out;
    for (const auto& [key, m] : markers)
      for (std::size_t i = 0; i + 2 < m.points.size(); i += 3) {
        const auto &a = m.points[i], &b = m.points[i + 1], &c = m.points[i + 2];
        out.push_back({a.x, a.y, a.z, b.x, b.y, b.z, c.x, c.y, c.z});
      }
    std::sort(out.begin(), out.end());
    return out;
  }
};

std::vector<Triangle> meshTriangles(const fusion::TriangleMesh& m) {
  std::vector<Triangle> out;
  for (const auto& f : m.faces) {
    const Eigen::Vector3f &a = m.vertices[f[0]], &b = m.vertices[f[1]], &c = m.vertices[f[2]];
    out.push_back({a.x(), a.y(), a.z(), b.x(), b.y(), b.z(), c.x(), c.y(), c.z()});
  }
  std::sort(out.begin(), out.end());
  return out;
}

std::map<std::array<int, 3>, int> idsByBlock(const visualization_msgs::MarkerArray& array,
                                             const fusion::MeshBlockUpdate& update) {
  // update() emits the blocks in order, skipping none that has triangles.
  std::map<std::array<int, 3>, int> out;
  std::size_t k = 0;
  for (const Marker& m : array.markers) {
    if (m.action != Marker::ADD) continue;
    while (k < update.blocks.size() && update.blocks[k].vertices.empty()) ++k;
    const auto& b = update.blocks.at(k++);
    out[{b.index.x(), b.index.y(), b.index.z()}] = m.id;
  }
  return out;
}

fusion::TsdfConfig config() {
  fusion::TsdfConfig c;
  c.voxel_size = 0.03;
  c.truncation = 0.09;
  return c;
}

}  // namespace

TEST(MeshBlockMarkers, UpdatesKeepAViewerEqualToTheMesh) {
  const meshing::PinholeImage image = test::sphereTestImage();
  const Vector3d c(0.2, 0.1, 0.3);
  fusion::TsdfVolume volume(config());
  MeshBlockMarkers stream;
  Viewer early;
  std::map<std::array<int, 3>, int> first_ids;
  const auto views = test::viewsAround(c, 1.5);
  std::size_t last_update_markers = 0;
  for (std::size_t k = 0; k < views.size(); ++k) {
    volume.integrateDepth(test::sphereDepth(c, 0.4, views[k], image), views[k], image);
    if (k % 4 != 3) continue;
    const fusion::MeshBlockUpdate update = volume.takeChangedBlocks();
    const visualization_msgs::MarkerArray array = stream.update(update, ros::Time(1.0 + static_cast<double>(k)));
    if (k == 3) {
      ASSERT_EQ(array.markers.front().action, Marker::DELETEALL);  // the first update replaces everything
      first_ids = idsByBlock(array, update);
    } else {
      // A block keeps its marker id.
      for (const auto& [block, id] : idsByBlock(array, update)) {
        const auto it = first_ids.find(block);
        if (it != first_ids.end()) {
          EXPECT_EQ(id, it->second);
        }
      }
    }
    last_update_markers = array.markers.size();
    early.apply(array);
    EXPECT_EQ(early.triangles(), meshTriangles(volume.extractMesh())) << "after view " << k;
  }
  EXPECT_GT(stream.numMarkers(), 50u);
  EXPECT_LT(last_update_markers, stream.numMarkers()) << "the last update is not the whole mesh";
  EXPECT_EQ(stream.numMarkers(), early.markers.size());

  // A viewer that connects now gets full() and holds the same.
  Viewer late;
  late.apply(stream.full());
  EXPECT_EQ(late.triangles(), early.triangles());

  // A rescale: every block again, same ids; colours follow the height.
  volume.rescale(Vector3d(1.0, 0.0, 0.0), 1.2);
  const visualization_msgs::MarkerArray moved = stream.update(volume.takeChangedBlocks(), ros::Time(100.0));
  EXPECT_EQ(moved.markers.size(), stream.numMarkers());
  early.apply(moved);
  late.apply(moved);
  EXPECT_EQ(early.triangles(), meshTriangles(volume.extractMesh()));
  EXPECT_EQ(late.triangles(), early.triangles());

  // A new map: one DELETEALL, the ids start over.
  Viewer after_clear = early;
  after_clear.apply(stream.clear(ros::Time(200.0)));
  EXPECT_TRUE(after_clear.markers.empty());
  EXPECT_EQ(stream.numMarkers(), 0u);
}

TEST(MeshBlockMarkers, AnEmptiedBlockIsDeletedAndColoursAreStable) {
  MeshBlockMarkers stream;
  fusion::MeshBlockUpdate u;
  u.replace_all = true;
  fusion::MeshBlock a, b;
  a.index = {0, 0, 0};
  a.vertices = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0.5f}};
  b.index = {1, 0, 0};
  b.vertices = {{1, 0, 0}, {2, 0, 0}, {1, 1, 0.5f}, {2, 2, 2}, {3, 2, 2}, {2, 3, std::nanf("")}};
  u.blocks = {a, b};
  std::size_t skipped = 0;
  const auto first = stream.update(u, ros::Time(1.0), &skipped);
  EXPECT_EQ(skipped, 1u);  // b's second triangle has a NaN
  ASSERT_EQ(first.markers.size(), 3u);
  EXPECT_EQ(first.markers[2].points.size(), 3u);
  const int id_b = first.markers[2].id;
  // The same vertex height has the same colour in every block.
  EXPECT_EQ(first.markers[1].colors[2].r, first.markers[2].colors[2].r);
  EXPECT_EQ(first.markers[1].colors[2].g, first.markers[2].colors[2].g);

  fusion::MeshBlockUpdate gone;
  fusion::MeshBlock empty_b;
  empty_b.index = b.index;
  gone.blocks = {empty_b};
  const auto second = stream.update(gone, ros::Time(2.0));
  ASSERT_EQ(second.markers.size(), 1u);
  EXPECT_EQ(second.markers[0].action, Marker::DELETE);
  EXPECT_EQ(second.markers[0].id, id_b);
  EXPECT_TRUE(stream.update(gone, ros::Time(3.0)).markers.empty()) << "deleted twice";
  EXPECT_EQ(stream.numMarkers(), 1u);

  // Grey on request: every kept marker recoloured.
  vitamin_e_ros::MeshMarkerOptions grey;
  grey.color_by_height = false;
  EXPECT_TRUE(stream.setOptions(grey));
  const auto all = stream.full();
  ASSERT_EQ(all.markers.size(), 2u);
  EXPECT_TRUE(all.markers[1].colors.empty());
  EXPECT_FALSE(stream.setOptions(grey));
}

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
