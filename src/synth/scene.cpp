#include "vitamin_e/synth/scene.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>

namespace vitamin_e::synth {

Eigen::Vector3d Face::normal() const {
  Eigen::Vector3d n = Eigen::Vector3d::Zero();
  n[axis] = normal_sign;
  return n;
}

void SceneConfig::validate() const {
  for (int a = 0; a < 3; ++a)
    if (!(room_max[a] - room_min[a] > 0.5)) throw std::invalid_argument("room_max must exceed room_min by > 0.5 m");
  if (num_boxes < 0 || num_boxes > 64) throw std::invalid_argument("num_boxes must be in [0, 64]");
  if (!(box_clearance_m >= 0.0)) throw std::invalid_argument("box_clearance_m must be >= 0");
  if (!(texel_m >= 0.001 && texel_m <= 0.1)) throw std::invalid_argument("texel_m must be in [0.001, 0.1]");
}

void Scene::addFace(int axis, double plane, int normal_sign, const AxisBox& extent, int owner, Rng* rng) {
  Face f;
  f.axis = axis;
  f.u_axis = (axis + 1) % 3;
  f.v_axis = (axis + 2) % 3;
  f.plane = plane;
  f.normal_sign = normal_sign;
  f.lo = Eigen::Vector2d(extent.min[f.u_axis], extent.min[f.v_axis]);
  f.hi = Eigen::Vector2d(extent.max[f.u_axis], extent.max[f.v_axis]);
  f.owner = owner;
  f.brightness = static_cast<float>(rng->uniform(0.65, 1.0));
  const int w = std::max(2, static_cast<int>(std::ceil((f.hi.x() - f.lo.x()) / config_.texel_m)));
  const int h = std::max(2, static_cast<int>(std::ceil((f.hi.y() - f.lo.y()) / config_.texel_m)));
  f.texture = Texture(generateProceduralTexture(w, h, config_.texel_m, rng->next()), config_.texel_m);
  faces_.push_back(std::move(f));
}

Scene Scene::makeRoom(const SceneConfig& config, const std::vector<Eigen::Vector3d>& keep_clear) {
  config.validate();
  Scene s;
  s.config_ = config;
  s.room_.min = config.room_min;
  s.room_.max = config.room_max;
  Rng rng(mixSeed(config.seed, 0x5CE7E));
  // Room faces, seen from inside: the min side's normal points to +axis.
  for (int axis = 0; axis < 3; ++axis) {
    s.addFace(axis, config.room_min[axis], +1, s.room_, -1, &rng);
    s.addFace(axis, config.room_max[axis], -1, s.room_, -1, &rng);
  }
  // Boxes: standing on the floor (most) or hanging from nowhere (a few), clear
  // of the keep_clear points and of each other.
  Rng place(mixSeed(config.seed, 0xB0C5));
  const Eigen::Vector3d size = config.room_max - config.room_min;
  for (int attempt = 0; attempt < 2000 && static_cast<int>(s.boxes_.size()) < config.num_boxes; ++attempt) {
    AxisBox b;
    const Eigen::Vector3d ext(place.uniform(0.3, 1.0), place.uniform(0.3, 1.0), place.uniform(0.3, 1.4));
    const bool floating = place.uniform() < 0.25;
    for (int a = 0; a < 2; ++a) b.min[a] = config.room_min[a] + 0.05 + place.uniform() * (size[a] - ext[a] - 0.1);
    b.min.z() = floating ? config.room_min.z() + place.uniform(0.6, std::max(0.7, size.z() - ext.z() - 0.3))
                         : config.room_min.z();
    b.max = b.min + ext;
    if ((b.max.array() > config.room_max.array()).any()) continue;
    bool ok = true;
    for (const auto& p : keep_clear) {
      const Eigen::Vector3d q = p.cwiseMax(b.min).cwiseMin(b.max);
      if ((q - p).norm() < config.box_clearance_m) ok = false;
    }
    for (const auto& o : s.boxes_)
      if (((b.min.array() - 0.1) < o.max.array()).all() && ((b.max.array() + 0.1) > o.min.array()).all()) ok = false;
    if (ok) s.boxes_.push_back(b);
  }
  s.box_kinds_.assign(s.boxes_.size(), "box");
  for (std::size_t k = 0; k < s.boxes_.size(); ++k) {
    for (int axis = 0; axis < 3; ++axis) {
      s.addFace(axis, s.boxes_[k].min[axis], -1, s.boxes_[k], static_cast<int>(k), &rng);
      s.addFace(axis, s.boxes_[k].max[axis], +1, s.boxes_[k], static_cast<int>(k), &rng);
    }
  }
  return s;
}

Scene Scene::fromBoxes(std::vector<SceneBox> boxes, float sky_intensity, const SceneConfig& config,
                       const std::string& extra_json) {
  if (boxes.empty()) throw std::invalid_argument("scene: no boxes");
  if (!(sky_intensity >= 0.0f && sky_intensity <= 1.0f))
    throw std::invalid_argument("scene: sky intensity must be in [0, 1]");
  Scene s;
  s.config_ = config;
  s.has_room_ = false;
  s.sky_ = sky_intensity;
  s.first_box_face_ = 0;
  s.extra_json_ = extra_json;
  s.room_.min = boxes.front().box.min;
  s.room_.max = boxes.front().box.max;
  for (std::size_t k = 0; k < boxes.size(); ++k) {
    SceneBox& sb = boxes[k];
    if (!((sb.box.max.array() > sb.box.min.array()).all()))
      throw std::invalid_argument("scene: box " + std::to_string(k) + " (" + sb.kind + ") is empty or inverted");
    s.room_.min = s.room_.min.cwiseMin(sb.box.min);
    s.room_.max = s.room_.max.cwiseMax(sb.box.max);
    s.boxes_.push_back(sb.box);
    s.box_kinds_.push_back(sb.kind);
    for (int axis = 0; axis < 3; ++axis) {
      for (int side = 0; side < 2; ++side) {
        SceneBox::Surface& surface = sb.faces[2 * axis + side];
        if (surface.texture.width() == 0)
          throw std::invalid_argument("scene: box " + std::to_string(k) + " (" + sb.kind +
                                      ") has a face without texture");
        Face f;
        f.axis = axis;
        f.u_axis = (axis + 1) % 3;
        f.v_axis = (axis + 2) % 3;
        f.plane = side ? sb.box.max[axis] : sb.box.min[axis];
        f.normal_sign = side ? +1 : -1;
        f.lo = Eigen::Vector2d(sb.box.min[f.u_axis], sb.box.min[f.v_axis]);
        f.hi = Eigen::Vector2d(sb.box.max[f.u_axis], sb.box.max[f.v_axis]);
        f.owner = static_cast<int>(k);
        f.brightness = surface.brightness;
        f.texture = std::move(surface.texture);
        s.faces_.push_back(std::move(f));
      }
    }
  }
  return s;
}

bool Scene::intersect(const Eigen::Vector3d& o, const Eigen::Vector3d& d, RayHit* hit) const {
  return intersect(o, d, hit, static_cast<const std::vector<char>*>(nullptr));
}

std::vector<char> Scene::boxesInFront(const Eigen::Vector3d& o, const Eigen::Vector3d& forward, double min_cos) const {
  // Conservative: the box's bounding sphere touches the cone.
  const double half_angle = std::acos(std::clamp(min_cos, -1.0, 1.0));
  const Eigen::Vector3d f = forward.normalized();
  std::vector<char> mask(boxes_.size(), 1);
  for (std::size_t k = 0; k < boxes_.size(); ++k) {
    const Eigen::Vector3d c = 0.5 * (boxes_[k].min + boxes_[k].max);
    const double r = 0.5 * (boxes_[k].max - boxes_[k].min).norm();
    const Eigen::Vector3d v = c - o;
    const double dist = v.norm();
    if (dist <= r) continue;
    const double angle = std::acos(std::clamp(f.dot(v) / dist, -1.0, 1.0));
    if (angle - std::asin(r / dist) > half_angle + 1e-3) mask[k] = 0;
  }
  return mask;
}

void Scene::boxesInPyramid(const Eigen::Vector3d& o, const std::array<Eigen::Vector3d, 4>& normals,
                           std::vector<int>* out, std::vector<double>* near_dist) const {
  out->clear();
  for (std::size_t k = 0; k < boxes_.size(); ++k) {
    const AxisBox& b = boxes_[k];
    bool outside = false;
    for (const Eigen::Vector3d& n : normals) {
      // The box corner farthest along n: if even it is behind the plane, so is the box.
      double best = 0.0;
      for (int a = 0; a < 3; ++a) best += n[a] * ((n[a] >= 0.0 ? b.max[a] : b.min[a]) - o[a]);
      if (best < -1e-6) {
        outside = true;
        break;
      }
    }
    if (!outside) out->push_back(static_cast<int>(k));
  }
  if (!near_dist) return;
  std::vector<std::pair<double, int>> order;
  order.reserve(out->size());
  for (const int k : *out) {
    const Eigen::Vector3d q = o.cwiseMax(boxes_[k].min).cwiseMin(boxes_[k].max);
    order.emplace_back((q - o).norm(), k);
  }
  std::sort(order.begin(), order.end());
  near_dist->clear();
  for (std::size_t i = 0; i < order.size(); ++i) {
    (*out)[i] = order[i].second;
    near_dist->push_back(order[i].first);
  }
}

double Scene::roomExit(const Eigen::Vector3d& o, const Eigen::Vector3d& d, const double inv[3], int* best_face) const {
  double best = std::numeric_limits<double>::infinity();
  if (!has_room_) return best;
  // Leaving the room (from inside).
  for (int a = 0; a < 3; ++a) {
    if (d[a] == 0.0) continue;
    const bool to_max = d[a] > 0.0;
    const double t = ((to_max ? room_.max[a] : room_.min[a]) - o[a]) * inv[a];
    if (t > 1e-9 && t < best) {
      best = t;
      *best_face = 2 * a + (to_max ? 1 : 0);
    }
  }
  return best;
}

bool Scene::hitBox(int k, const Eigen::Vector3d& o, const Eigen::Vector3d& d, const double inv[3], double* best,
                   int* best_face) const {
  constexpr double kInf = std::numeric_limits<double>::infinity();
  // Entering the box (slab test).
  const AxisBox& b = boxes_[k];
  double t_near = -kInf, t_far = kInf;
  int near_axis = -1;
  for (int a = 0; a < 3; ++a) {
    if (d[a] == 0.0) {
      if (o[a] < b.min[a] || o[a] > b.max[a]) t_far = -kInf;
      continue;
    }
    double t0 = (b.min[a] - o[a]) * inv[a], t1 = (b.max[a] - o[a]) * inv[a];
    if (t0 > t1) std::swap(t0, t1);
    if (t0 > t_near) {
      t_near = t0;
      near_axis = a;
    }
    t_far = std::min(t_far, t1);
  }
  if (near_axis >= 0 && t_near <= t_far && t_near > 1e-9 && t_near < *best) {
    *best = t_near;
    // Box k's faces: first_box_face_ + 6k + 2*axis + (max side).
    *best_face = first_box_face_ + 6 * k + 2 * near_axis + (d[near_axis] < 0.0 ? 1 : 0);
    return true;
  }
  return false;
}

bool Scene::finishHit(const Eigen::Vector3d& o, const Eigen::Vector3d& d, double best, int best_face,
                      RayHit* hit) const {
  if (best_face < 0) return false;
  hit->t = best;
  hit->face = best_face;
  hit->p = o + best * d;
  hit->cos_incidence = std::abs(d[faces_[best_face].axis]);
  return true;
}

bool Scene::intersect(const Eigen::Vector3d& o, const Eigen::Vector3d& d, RayHit* hit,
                      const std::vector<char>* box_mask) const {
  constexpr double kInf = std::numeric_limits<double>::infinity();
  int best_face = -1;
  double inv[3];
  for (int a = 0; a < 3; ++a) inv[a] = d[a] != 0.0 ? 1.0 / d[a] : kInf;
  double best = roomExit(o, d, inv, &best_face);
  for (int k = 0; k < static_cast<int>(boxes_.size()); ++k) {
    if (box_mask && !(*box_mask)[k]) continue;
    hitBox(k, o, d, inv, &best, &best_face);
  }
  return finishHit(o, d, best, best_face, hit);
}

bool Scene::intersect(const Eigen::Vector3d& o, const Eigen::Vector3d& d, RayHit* hit, const std::vector<int>& box_list,
                      const std::vector<double>& near_dist) const {
  constexpr double kInf = std::numeric_limits<double>::infinity();
  int best_face = -1;
  double inv[3];
  for (int a = 0; a < 3; ++a) inv[a] = d[a] != 0.0 ? 1.0 / d[a] : kInf;
  double best = roomExit(o, d, inv, &best_face);
  for (std::size_t i = 0; i < box_list.size(); ++i) {
    // A box's hit is at least its distance away; hitBox takes only t < best.
    if (near_dist[i] >= best) break;
    hitBox(box_list[i], o, d, inv, &best, &best_face);
  }
  return finishHit(o, d, best, best_face, hit);
}

bool Scene::intersect(const Eigen::Vector3d& o, const Eigen::Vector3d& d, RayHit* hit,
                      const std::vector<int>* box_list) const {
  if (!box_list) return intersect(o, d, hit, static_cast<const std::vector<char>*>(nullptr));
  constexpr double kInf = std::numeric_limits<double>::infinity();
  int best_face = -1;
  double inv[3];
  for (int a = 0; a < 3; ++a) inv[a] = d[a] != 0.0 ? 1.0 / d[a] : kInf;
  double best = roomExit(o, d, inv, &best_face);
  for (const int k : *box_list) hitBox(k, o, d, inv, &best, &best_face);
  return finishHit(o, d, best, best_face, hit);
}

float Scene::textureAt(int face, const Eigen::Vector3d& p) const {
  const Face& f = faces_[face];
  return f.brightness * f.texture.sampleLevel0(p[f.u_axis] - f.lo.x(), p[f.v_axis] - f.lo.y());
}

float Scene::shade(const RayHit& hit, double footprint_m) const {
  const Face& f = faces_[hit.face];
  return f.brightness * f.texture.sample(hit.p[f.u_axis] - f.lo.x(), hit.p[f.v_axis] - f.lo.y(), footprint_m);
}

bool Scene::onFace(int face, const Eigen::Vector3d& p, double tol) const {
  const Face& f = faces_[face];
  return std::abs(p[f.axis] - f.plane) <= tol && p[f.u_axis] >= f.lo.x() - tol && p[f.u_axis] <= f.hi.x() + tol &&
         p[f.v_axis] >= f.lo.y() - tol && p[f.v_axis] <= f.hi.y() + tol;
}

namespace {
std::string vec(const Eigen::Vector3d& v) {
  std::ostringstream o;
  o.precision(9);
  o << "[" << v.x() << ", " << v.y() << ", " << v.z() << "]";
  return o.str();
}
}  // namespace

std::string Scene::toJson() const {
  std::ostringstream o;
  o.precision(9);
  o << "{\"world_frame\": \"z up, metres\", \"seed\": " << config_.seed << ", \"texel_m\": " << config_.texel_m;
  if (has_room_) {
    o << ",\n \"room\": {\"min\": " << vec(room_.min) << ", \"max\": " << vec(room_.max) << "},\n \"boxes\": [";
    for (std::size_t k = 0; k < boxes_.size(); ++k)
      o << (k ? ", " : "") << "{\"min\": " << vec(boxes_[k].min) << ", \"max\": " << vec(boxes_[k].max) << "}";
  } else {
    // An open scene: no room (rays that miss every box see the sky).
    o << ", \"sky_intensity\": " << sky_ << ",\n \"bounds\": {\"min\": " << vec(room_.min)
      << ", \"max\": " << vec(room_.max) << "},\n";
    if (!extra_json_.empty()) o << " " << extra_json_.substr(1, extra_json_.size() - 2) << ",\n";
    o << " \"boxes\": [";
    for (std::size_t k = 0; k < boxes_.size(); ++k)
      o << (k ? ",\n  " : "\n  ") << "{\"kind\": \"" << box_kinds_[k] << "\", \"min\": " << vec(boxes_[k].min)
        << ", \"max\": " << vec(boxes_[k].max) << "}";
  }
  o << "],\n \"faces\": [";
  for (std::size_t i = 0; i < faces_.size(); ++i) {
    const Face& f = faces_[i];
    o << (i ? ",\n  " : "\n  ") << "{\"index\": " << i << ", \"owner\": \""
      << (f.owner < 0 ? std::string("room") : "box" + std::to_string(f.owner)) << "\", \"axis\": " << f.axis
      << ", \"plane\": " << f.plane << ", \"normal\": " << vec(f.normal()) << ", \"u_axis\": " << f.u_axis
      << ", \"v_axis\": " << f.v_axis << ", \"uv_min\": [" << f.lo.x() << ", " << f.lo.y() << "], \"uv_max\": ["
      << f.hi.x() << ", " << f.hi.y() << "], \"brightness\": " << f.brightness << ", \"tex_size\": ["
      << f.texture.width() << ", " << f.texture.height() << "]";
    if (!has_room_) o << ", \"texel_m\": " << f.texture.texelSize();
    o << "}";
  }
  o << "]}";
  return o.str();
}

}  // namespace vitamin_e::synth
