#include "vitamin_e/synth/street.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>

#include "street_textures.h"

namespace vitamin_e::synth {

namespace {

constexpr double kSlabBottom = -0.3;   // road and sidewalk slabs reach down to here
constexpr double kCarHalfWidth = 0.9;  // the path's car must stay this far inside the road

enum class CellKind { kBlock, kStreetX, kStreetY, kIntersection };

struct Cell {
  double x0, x1, y0, y1;
  CellKind kind = CellKind::kBlock;
  int street = -1;  // the street of a street cell
};

enum class ItemKind { kBuilding, kCar, kRoad, kIntersection, kSidewalk };

// A box before texturing, with what its textures need to know.
struct Item {
  AxisBox box;
  ItemKind kind = ItemKind::kBuilding;
  int along = 0;                        // roads, sidewalks, cars: the axis of the street
  bool zebra0 = false, zebra1 = false;  // roads: crossings at the min / max end
  double body = 0.5;                    // cars: body intensity
  int front_side = 1;                   // cars: the end face (0: min, 1: max) that is the front
};

const char* kindName(ItemKind k) {
  switch (k) {
    case ItemKind::kBuilding: return "building";
    case ItemKind::kCar: return "car";
    case ItemKind::kRoad: return "road";
    case ItemKind::kIntersection: return "intersection";
    case ItemKind::kSidewalk: return "sidewalk";
  }
  return "?";
}

// The town's cells: a grid whose lines are the street edges and the ring.
struct Town {
  StreetLayout layout;
  std::vector<double> xs, ys;  // cell edges
  std::vector<Cell> cells;     // row-major over (y, x)
  double half_total = 0.0;     // half a street with its sidewalks

  const Cell* cellAt(double x, double y) const {
    if (x < xs.front() || x > xs.back() || y < ys.front() || y > ys.back()) return nullptr;
    const int i = std::clamp(static_cast<int>(std::upper_bound(xs.begin(), xs.end(), x) - xs.begin()) - 1, 0,
                             static_cast<int>(xs.size()) - 2);
    const int j = std::clamp(static_cast<int>(std::upper_bound(ys.begin(), ys.end(), y) - ys.begin()) - 1, 0,
                             static_cast<int>(ys.size()) - 2);
    return &cells[static_cast<std::size_t>(j) * (xs.size() - 1) + i];
  }
};

std::vector<double> uniqueSorted(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  std::vector<double> out;
  for (const double x : v)
    if (out.empty() || x - out.back() > 1e-6) out.push_back(x);
  return out;
}

// Point to axis-aligned rectangle (face) distance in 3D.
double distanceToFace(const Face& f, const Eigen::Vector3d& p) {
  const double du = std::max({f.lo.x() - p[f.u_axis], 0.0, p[f.u_axis] - f.hi.x()});
  const double dv = std::max({f.lo.y() - p[f.v_axis], 0.0, p[f.v_axis] - f.hi.y()});
  const double dn = p[f.axis] - f.plane;
  return std::sqrt(du * du + dv * dv + dn * dn);
}

// Fake directional light: faces of each orientation get one brightness.
float faceBrightness(int axis, int side) {
  static const float k[6] = {0.78f, 0.93f, 0.72f, 0.86f, 0.5f, 1.0f};
  return k[2 * axis + side];
}

}  // namespace

void StreetConfig::validate() const {
  auto positive = [](double v, const char* key) {
    if (!(v > 0.0) || !std::isfinite(v)) throw std::invalid_argument(std::string("street: ") + key + " must be > 0");
  };
  positive(road_width_m, "road_width_m");
  positive(sidewalk_width_m, "sidewalk_width_m");
  positive(kerb_height_m, "kerb_height_m");
  positive(block_min_m, "block_min_m");
  positive(building_width_min_m, "building_width_min_m");
  positive(building_height_min_m, "building_height_min_m");
  positive(margin_m, "margin_m");
  positive(ring_depth_m, "ring_depth_m");
  positive(texel_m, "texel_m");
  if (!(road_width_m >= 6.0))
    throw std::invalid_argument("street: road_width_m must be >= 6 (two lanes and parked cars)");
  if (!(std::abs(lane_offset_m) + kCarHalfWidth < 0.5 * road_width_m))
    throw std::invalid_argument("street: lane_offset_m must keep the car on the road");
  if (!(block_max_m >= block_min_m)) throw std::invalid_argument("street: block_max_m must be >= block_min_m");
  if (!(block_min_m >= road_width_m + 2.0 * sidewalk_width_m + 10.0))
    throw std::invalid_argument("street: block_min_m must leave at least 10 m of buildings between streets");
  if (!(building_width_max_m >= building_width_min_m))
    throw std::invalid_argument("street: building_width_max_m must be >= building_width_min_m");
  if (!(building_height_max_m >= building_height_min_m && building_height_min_m > 3.0))
    throw std::invalid_argument("street: building heights must be > 3 m, max >= min");
  if (!(parking_probability >= 0.0 && parking_probability <= 1.0))
    throw std::invalid_argument("street: parking_probability must be in [0, 1]");
  if (!(margin_m >= ring_depth_m + 20.0))
    throw std::invalid_argument("street: margin_m must exceed ring_depth_m by 20 m");
  if (!(car_clearance_m >= 0.0)) throw std::invalid_argument("street: car_clearance_m must be >= 0");
  if (!(texel_m >= 0.001 && texel_m <= 0.2)) throw std::invalid_argument("street: texel_m must be in [0.001, 0.2]");
  if (!(texel_per_m >= 0.0 && max_texel_m >= texel_m))
    throw std::invalid_argument("street: texel_per_m must be >= 0, max_texel_m >= texel_m");
  if (!(sky_intensity >= 0.0 && sky_intensity <= 1.0))
    throw std::invalid_argument("street: sky_intensity must be in [0, 1]");
}

StreetLayout makeStreetLayout(const StreetConfig& cfg, const DrivePath& path) {
  cfg.validate();
  StreetLayout L;
  Eigen::Vector2d lo = path.config().start, hi = lo;
  for (double s = 0.0;; s = std::min(path.length(), s + 0.5)) {
    const Eigen::Vector2d p = path.groundPosition(path.timeAtArcLength(s));
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
    if (s >= path.length()) break;
  }
  L.min = lo - Eigen::Vector2d::Constant(cfg.margin_m);
  L.max = hi + Eigen::Vector2d::Constant(cfg.margin_m);
  const double half_total = 0.5 * cfg.road_width_m + cfg.sidewalk_width_m;

  // The path's own streets: one per straight leg (legs on one line share it).
  for (int i = 0; i < static_cast<int>(path.config().legs.size()); ++i) {
    if (path.config().legs[i].kind != DriveLeg::Kind::kStraight) continue;
    const double s0 = path.legStart(i);
    const double h = path.headingAt(s0 + 0.5 * path.config().legs[i].length_m);
    const double k = std::round(h / (0.5 * M_PI));
    if (std::abs(h - k * 0.5 * M_PI) > 1e-6)
      throw std::invalid_argument("street: leg " + std::to_string(i) + " of path '" + path.config().name + "' heads " +
                                  std::to_string(h * 180.0 / M_PI) + " degrees: straights must run along x or y");
    const int axis = (static_cast<long long>(std::abs(k)) % 2 == 0) ? 0 : 1;
    const Eigen::Vector2d left(-std::sin(h), std::cos(h));
    const Eigen::Vector2d centre = path.groundPosition(path.timeAtArcLength(s0)) + cfg.lane_offset_m * left;
    const double offset = centre[1 - axis];
    bool merged = false;
    for (const Street& st : L.streets) {
      if (st.axis != axis) continue;
      const double gap = std::abs(st.offset - offset);
      if (gap < 0.01) {
        merged = true;
      } else if (gap < 2.0 * half_total + cfg.block_min_m) {
        throw std::invalid_argument("street: two streets of path '" + path.config().name + "' are " +
                                    std::to_string(gap) + " m apart (at least " +
                                    std::to_string(2.0 * half_total + cfg.block_min_m) + " needed)");
      }
    }
    if (!merged)
      L.streets.push_back({axis, offset, L.min[axis] + cfg.ring_depth_m, L.max[axis] - cfg.ring_depth_m, true});
  }
  // Side streets at random spacing, clear of the path's streets and the ring.
  Rng rng(mixSeed(cfg.seed, 0x57EE7));
  for (int axis = 0; axis < 2; ++axis) {
    const int p = 1 - axis;
    const double lo_p = L.min[p] + cfg.ring_depth_m + half_total + 0.5 * cfg.block_min_m;
    const double hi_p = L.max[p] - cfg.ring_depth_m - half_total - 0.5 * cfg.block_min_m;
    std::vector<double> fixed;
    for (const Street& st : L.streets)
      if (st.axis == axis) fixed.push_back(st.offset);
    std::sort(fixed.begin(), fixed.end());
    // Walk each gap between the path's streets (and the town's ends) at random
    // spacing, keeping block_min from the path's streets.
    std::vector<double> added;
    std::vector<double> anchors = {lo_p - cfg.block_min_m};  // soft lower end: a street may come right after it
    anchors.insert(anchors.end(), fixed.begin(), fixed.end());
    for (std::size_t g = 0; g < anchors.size(); ++g) {
      const bool soft_lo = g == 0;
      const double upper = g + 1 < anchors.size() ? anchors[g + 1] - cfg.block_min_m : hi_p;
      double x = soft_lo ? lo_p + rng.uniform(0.0, cfg.block_min_m)
                         : anchors[g] + rng.uniform(cfg.block_min_m, cfg.block_max_m);
      for (; x <= upper; x += rng.uniform(cfg.block_min_m, cfg.block_max_m))
        if (x >= lo_p && x <= hi_p) added.push_back(x);
    }
    for (const double x : added)
      L.streets.push_back({axis, x, L.min[axis] + cfg.ring_depth_m, L.max[axis] - cfg.ring_depth_m, false});
  }
  return L;
}

Scene makeStreetScene(const StreetConfig& cfg, const DrivePath& path) {
  Town town;
  town.layout = makeStreetLayout(cfg, path);
  const StreetLayout& L = town.layout;
  const double W = cfg.road_width_m, S = cfg.sidewalk_width_m;
  town.half_total = 0.5 * W + S;
  const double ht = town.half_total;

  // Cells.
  std::vector<double> xs = {L.min.x(), L.min.x() + cfg.ring_depth_m, L.max.x() - cfg.ring_depth_m, L.max.x()};
  std::vector<double> ys = {L.min.y(), L.min.y() + cfg.ring_depth_m, L.max.y() - cfg.ring_depth_m, L.max.y()};
  for (const Street& st : L.streets) {
    auto& edges = st.axis == 0 ? ys : xs;
    edges.push_back(st.offset - ht);
    edges.push_back(st.offset + ht);
  }
  town.xs = uniqueSorted(xs);
  town.ys = uniqueSorted(ys);
  for (std::size_t j = 0; j + 1 < town.ys.size(); ++j) {
    for (std::size_t i = 0; i + 1 < town.xs.size(); ++i) {
      Cell c{town.xs[i], town.xs[i + 1], town.ys[j], town.ys[j + 1]};
      const double cx = 0.5 * (c.x0 + c.x1), cy = 0.5 * (c.y0 + c.y1);
      int sx = -1, sy = -1;
      for (int k = 0; k < static_cast<int>(L.streets.size()); ++k) {
        const Street& st = L.streets[k];
        const double along = st.axis == 0 ? cx : cy, across = st.axis == 0 ? cy : cx;
        if (std::abs(across - st.offset) < ht && along > st.from && along < st.to) (st.axis == 0 ? sx : sy) = k;
      }
      if (sx >= 0 && sy >= 0) {
        c.kind = CellKind::kIntersection;
      } else if (sx >= 0) {
        c.kind = CellKind::kStreetX;
        c.street = sx;
      } else if (sy >= 0) {
        c.kind = CellKind::kStreetY;
        c.street = sy;
      }
      town.cells.push_back(c);
    }
  }
  auto is_street = [&](double x, double y) {
    const Cell* c = town.cellAt(x, y);
    return c && c->kind != CellKind::kBlock;
  };

  // The path must stay on the road: every 0.25 m, the car's centre 0.9 m inside it.
  std::vector<Eigen::Vector2d> ground;
  for (double s = 0.0;; s = std::min(path.length(), s + 0.25)) {
    ground.push_back(path.groundPosition(path.timeAtArcLength(s)));
    if (s >= path.length()) break;
  }
  for (const Eigen::Vector2d& g : ground) {
    const Cell* c = town.cellAt(g.x(), g.y());
    bool ok = c && c->kind != CellKind::kBlock;
    if (ok && c->kind != CellKind::kIntersection) {
      const Street& st = L.streets[c->street];
      ok = std::abs((st.axis == 0 ? g.y() : g.x()) - st.offset) <= 0.5 * W - kCarHalfWidth;
    }
    if (!ok) {
      std::ostringstream m;
      m << "street: path '" << path.config().name << "' leaves the road at (" << g.x() << ", " << g.y() << ")";
      throw std::invalid_argument(m.str());
    }
  }

  std::vector<Item> items;
  Rng place(mixSeed(cfg.seed, 0xB1D6));
  // Roads, sidewalks and buildings, cell by cell.
  for (const Cell& c : town.cells) {
    if (c.kind == CellKind::kIntersection) {
      Item it;
      it.kind = ItemKind::kIntersection;
      it.box.min = Eigen::Vector3d(c.x0, c.y0, kSlabBottom);
      it.box.max = Eigen::Vector3d(c.x1, c.y1, 0.0);
      items.push_back(it);
    } else if (c.kind != CellKind::kBlock) {
      const Street& st = L.streets[c.street];
      const int a = st.axis, p = 1 - a;
      const double a0 = a == 0 ? c.x0 : c.y0, a1 = a == 0 ? c.x1 : c.y1;
      auto slab = [&](ItemKind kind, double p0, double p1, double top) {
        Item it;
        it.kind = kind;
        it.along = a;
        it.box.min[a] = a0;
        it.box.max[a] = a1;
        it.box.min[p] = p0;
        it.box.max[p] = p1;
        it.box.min.z() = kSlabBottom;
        it.box.max.z() = top;
        return it;
      };
      Item road = slab(ItemKind::kRoad, st.offset - 0.5 * W, st.offset + 0.5 * W, 0.0);
      // Zebra crossings where the segment meets an intersection.
      auto probe = [&](double along) { return a == 0 ? town.cellAt(along, st.offset) : town.cellAt(st.offset, along); };
      const Cell* before = probe(a0 - 1.0);
      const Cell* after = probe(a1 + 1.0);
      road.zebra0 = before && before->kind == CellKind::kIntersection;
      road.zebra1 = after && after->kind == CellKind::kIntersection;
      items.push_back(road);
      items.push_back(slab(ItemKind::kSidewalk, st.offset - ht, st.offset - 0.5 * W, cfg.kerb_height_m));
      items.push_back(slab(ItemKind::kSidewalk, st.offset + 0.5 * W, st.offset + ht, cfg.kerb_height_m));
      // Parked cars along both kerbs, 3.5 m clear of the segment's ends.
      for (const int side : {-1, 1}) {
        for (double x = a0 + 3.5 + place.uniform(0.0, 3.0);;) {
          const double len = place.uniform(3.9, 4.5), wid = place.uniform(1.7, 1.9), hgt = place.uniform(1.4, 1.6);
          const bool parked = place.uniform() < cfg.parking_probability;
          const double body = place.uniform(0.1, 0.9);
          const int front = place.uniform() < 0.5 ? 0 : 1;
          if (x + len > a1 - 3.5) break;
          if (parked) {
            Item car;
            car.kind = ItemKind::kCar;
            car.along = a;
            car.body = body;
            car.front_side = front;
            car.box.min[a] = x;
            car.box.max[a] = x + len;
            const double kerb = st.offset + side * 0.5 * W;
            car.box.min[p] = side > 0 ? kerb - 0.2 - wid : kerb + 0.2;
            car.box.max[p] = car.box.min[p] + wid;
            car.box.min.z() = 0.0;
            car.box.max.z() = hgt;
            bool clear = true;
            for (const Eigen::Vector2d& g : ground) {
              const Eigen::Vector2d q = g.cwiseMax(car.box.min.head<2>()).cwiseMin(car.box.max.head<2>());
              if ((q - g).norm() < cfg.car_clearance_m) {
                clear = false;
                break;
              }
            }
            if (clear) items.push_back(car);
          }
          x += len + place.uniform(0.8, 2.5);
        }
      }
    } else {
      // A block: one or two rows of buildings along its longer side.
      const int a = (c.x1 - c.x0) >= (c.y1 - c.y0) ? 0 : 1, p = 1 - a;
      const double a0 = a == 0 ? c.x0 : c.y0, a1 = a == 0 ? c.x1 : c.y1;
      const double p0 = a == 0 ? c.y0 : c.x0, p1 = a == 0 ? c.y1 : c.x1;
      std::vector<std::pair<double, double>> rows = {{p0, p1}};
      if (p1 - p0 >= 24.0) {
        const double mid = 0.5 * (p0 + p1) + place.uniform(-0.15, 0.15) * (p1 - p0);
        rows = {{p0, mid}, {mid, p1}};
      }
      for (const auto& [r0, r1] : rows) {
        for (double x = a0; x < a1 - 1e-6;) {
          double w = place.uniform(cfg.building_width_min_m, cfg.building_width_max_m);
          if (a1 - (x + w) < cfg.building_width_min_m) w = a1 - x;  // the last one takes the rest
          Item b;
          b.kind = ItemKind::kBuilding;
          b.box.min[a] = x;
          b.box.max[a] = x + w;
          b.box.min[p] = r0;
          b.box.max[p] = r1;
          b.box.min.z() = 0.0;
          b.box.max.z() = place.uniform(cfg.building_height_min_m, cfg.building_height_max_m);
          items.push_back(b);
          x += w;
        }
      }
    }
  }

  // Textures: the finest texel near the path, coarser with distance; none on
  // faces that no camera position of the path is in front of.
  std::vector<Eigen::Vector3d> eyes;
  for (double s = 0.0;; s = std::min(path.length(), s + 1.0)) {
    eyes.push_back(path.position(path.timeAtArcLength(s)));
    if (s >= path.length()) break;
  }
  std::vector<SceneBox> boxes;
  int n_buildings = 0, n_cars = 0;
  for (std::size_t k = 0; k < items.size(); ++k) {
    const Item& it = items[k];
    if (it.kind == ItemKind::kBuilding) ++n_buildings;
    if (it.kind == ItemKind::kCar) ++n_cars;
    SceneBox sb;
    sb.box = it.box;
    sb.kind = kindName(it.kind);
    const Eigen::Vector3d ext = it.box.max - it.box.min;
    for (int axis = 0; axis < 3; ++axis) {
      for (int side = 0; side < 2; ++side) {
        Face f;
        f.axis = axis;
        f.u_axis = (axis + 1) % 3;
        f.v_axis = (axis + 2) % 3;
        f.plane = side ? it.box.max[axis] : it.box.min[axis];
        f.lo = Eigen::Vector2d(it.box.min[f.u_axis], it.box.min[f.v_axis]);
        f.hi = Eigen::Vector2d(it.box.max[f.u_axis], it.box.max[f.v_axis]);
        const double sign = side ? 1.0 : -1.0;
        double dist = std::numeric_limits<double>::infinity();
        for (const Eigen::Vector3d& e : eyes)
          if (sign * (e[axis] - f.plane) > 0.05) dist = std::min(dist, distanceToFace(f, e));
        SceneBox::Surface& surf = sb.faces[2 * axis + side];
        surf.brightness = faceBrightness(axis, side);
        if (!std::isfinite(dist)) {
          surf.texture = Texture(detail::flatTexture(0.5f), 1.0);
          continue;
        }
        double texel = std::clamp(dist * cfg.texel_per_m, cfg.texel_m, cfg.max_texel_m);
        // Bound the memory of one face (16 M texels).
        const double area = (f.hi - f.lo).prod();
        texel = std::max(texel, std::sqrt(area / 16e6));
        const int face = 2 * axis + side;
        Rng rng(mixSeed(cfg.seed, 0x7E47 + k, static_cast<std::uint64_t>(face)));
        // Vertical faces: canonical rows run up z, which is u (columns) on an axis-1 face.
        // Top faces: canonical columns run along `along`, which is u (x) unless along = y.
        const bool vertical = axis != 2;
        const double along_m = vertical ? ext[1 - axis] : ext[it.along];
        const double across_m = vertical ? ext.z() : ext[1 - it.along];
        const bool transpose = vertical ? axis == 1 : it.along == 1;
        cv::Mat img;
        switch (it.kind) {
          case ItemKind::kBuilding: {
            if (!vertical) {
              img = detail::flatTexture(0.45f);
              break;
            }
            // A street face has windows; a face onto the block's inside or a neighbour is a plain wall.
            Eigen::Vector3d out = 0.5 * (it.box.min + it.box.max);
            out[axis] = f.plane + sign * 0.5;
            img = is_street(out.x(), out.y()) ? detail::facadeTexture(along_m, across_m, texel, &rng)
                                              : detail::plainWallTexture(along_m, across_m, texel, &rng);
            break;
          }
          case ItemKind::kCar:
            if (!vertical) {
              img = side ? detail::carTopTexture(along_m, across_m, texel, it.body, &rng) : detail::flatTexture(0.05f);
            } else if (axis == it.along) {
              img = detail::carEndTexture(along_m, across_m, texel, it.body, side == it.front_side, &rng);
            } else {
              img = detail::carSideTexture(along_m, across_m, texel, it.body, &rng);
            }
            break;
          case ItemKind::kRoad:
          case ItemKind::kIntersection:
            img = !vertical && side ? detail::roadTexture(along_m, across_m, texel, it.kind == ItemKind::kRoad,
                                                          it.zebra0, it.zebra1, &rng)
                                    : detail::flatTexture(0.3f);
            break;
          case ItemKind::kSidewalk:
            img = !vertical
                      ? (side ? detail::sidewalkTexture(along_m, across_m, texel, &rng) : detail::flatTexture(0.3f))
                      : detail::kerbTexture(along_m, across_m, texel, &rng);
            break;
        }
        if (img.rows == 2 && img.cols == 2) {
          surf.texture = Texture(img, 1.0);
          continue;
        }
        if (transpose) img = img.t();
        surf.texture = Texture(img, texel);
      }
    }
    boxes.push_back(std::move(sb));
  }

  std::ostringstream js;
  js.precision(9);
  js << "{\"street\": {\"road_width_m\": " << W << ", \"sidewalk_width_m\": " << S
     << ", \"kerb_height_m\": " << cfg.kerb_height_m << ", \"lane_offset_m\": " << cfg.lane_offset_m
     << ", \"extent\": {\"min\": [" << L.min.x() << ", " << L.min.y() << "], \"max\": [" << L.max.x() << ", "
     << L.max.y() << "]}, \"buildings\": " << n_buildings << ", \"cars\": " << n_cars << ",\n  \"streets\": [";
  for (std::size_t k = 0; k < L.streets.size(); ++k) {
    const Street& st = L.streets[k];
    js << (k ? ", " : "") << "{\"along\": \"" << (st.axis == 0 ? "x" : "y") << "\", \"offset\": " << st.offset
       << ", \"from\": " << st.from << ", \"to\": " << st.to << ", \"on_path\": " << (st.on_path ? "true" : "false")
       << "}";
  }
  js << "]}}";
  SceneConfig sc;
  sc.seed = cfg.seed;
  sc.texel_m = cfg.texel_m;
  sc.num_boxes = static_cast<int>(boxes.size());
  return Scene::fromBoxes(std::move(boxes), static_cast<float>(cfg.sky_intensity), sc, js.str());
}

}  // namespace vitamin_e::synth
