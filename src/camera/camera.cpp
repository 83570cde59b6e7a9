#include "vitamin_e/camera/camera.h"

#include <cmath>
#include <cstdio>
#include <sstream>

namespace vitamin_e::camera {

namespace {

constexpr double kMinDepth = 1e-9;
constexpr double kConvergedPx = 1e-8;
constexpr int kMaxIterations = 60;

bool finite(double v) { return std::isfinite(v); }

std::size_t expectedCount(DistortionModel model, std::size_t given) {
  switch (model) {
    case DistortionModel::kNone: return 0;
    case DistortionModel::kRadialTangential: return given == 5 ? 5 : 4;
    case DistortionModel::kEquidistant: return 4;
  }
  return 0;
}

}  // namespace

const char* toString(DistortionModel model) {
  switch (model) {
    case DistortionModel::kNone: return "none";
    case DistortionModel::kRadialTangential: return "radial-tangential";
    case DistortionModel::kEquidistant: return "equidistant";
  }
  return "?";
}

Camera::Camera(int width, int height, double fx, double fy, double cx, double cy, DistortionModel model,
               std::vector<double> distortion)
    : width_(width), height_(height), pinhole_{fx, fy, cx, cy}, model_(model), distortion_(std::move(distortion)) {
  if (width <= 0 || height <= 0) {
    throw CalibrationError("camera: image size must be positive, got " + std::to_string(width) + "x" +
                           std::to_string(height));
  }
  if (!finite(fx) || !finite(fy) || !finite(cx) || !finite(cy)) {
    throw CalibrationError("camera: intrinsics must be finite numbers");
  }
  if (fx <= 0.0 || fy <= 0.0) {
    throw CalibrationError("camera: focal lengths must be positive, got fx=" + std::to_string(fx) +
                           " fy=" + std::to_string(fy));
  }
  const std::size_t want = expectedCount(model, distortion_.size());
  if (distortion_.size() != want) {
    throw CalibrationError(std::string("camera: distortion model '") + toString(model) + "' needs " +
                           (model == DistortionModel::kRadialTangential ? "4 or 5" : std::to_string(want)) +
                           " coefficients, got " + std::to_string(distortion_.size()));
  }
  for (double d : distortion_) {
    if (!finite(d)) throw CalibrationError("camera: distortion coefficients must be finite numbers");
  }
}

bool Pinhole::valid() const { return finite(fx) && finite(fy) && finite(cx) && finite(cy) && fx > 0.0 && fy > 0.0; }

Eigen::Vector2d Camera::distortNormalized(const Eigen::Vector2d& xy, Eigen::Matrix2d* d_uv_d_xy) const {
  const double x = xy.x(), y = xy.y();
  Eigen::Vector2d xy_d;
  Eigen::Matrix2d J = Eigen::Matrix2d::Identity();  // d xy_d / d xy
  switch (model_) {
    case DistortionModel::kNone: xy_d = xy; break;
    case DistortionModel::kRadialTangential: {
      const double k1 = distortion_[0], k2 = distortion_[1], p1 = distortion_[2], p2 = distortion_[3];
      const double k3 = distortion_.size() > 4 ? distortion_[4] : 0.0;
      const double r2 = x * x + y * y;
      const double radial = 1.0 + r2 * (k1 + r2 * (k2 + r2 * k3));
      const double d_radial_d_r2 = k1 + r2 * (2.0 * k2 + 3.0 * k3 * r2);
      xy_d.x() = x * radial + 2.0 * p1 * x * y + p2 * (r2 + 2.0 * x * x);
      xy_d.y() = y * radial + p1 * (r2 + 2.0 * y * y) + 2.0 * p2 * x * y;
      if (d_uv_d_xy) {
        const double cross = 2.0 * x * y * d_radial_d_r2 + 2.0 * p1 * x + 2.0 * p2 * y;
        J(0, 0) = radial + 2.0 * x * x * d_radial_d_r2 + 2.0 * p1 * y + 6.0 * p2 * x;
        J(0, 1) = cross;
        J(1, 0) = cross;
        J(1, 1) = radial + 2.0 * y * y * d_radial_d_r2 + 6.0 * p1 * y + 2.0 * p2 * x;
      }
      break;
    }
    case DistortionModel::kEquidistant: {
      const double k1 = distortion_[0], k2 = distortion_[1], k3 = distortion_[2], k4 = distortion_[3];
      const double r2 = x * x + y * y;
      const double r = std::sqrt(r2);
      if (r < 1e-8) {
        // theta_d / r = 1 + (k1 - 1/3) r^2 + O(r^4): identity at the centre.
        xy_d = xy;
        if (d_uv_d_xy) J = Eigen::Matrix2d::Identity() + 2.0 * (k1 - 1.0 / 3.0) * xy * xy.transpose();
        break;
      }
      const double th = std::atan(r);
      const double t2 = th * th;
      const double poly = 1.0 + t2 * (k1 + t2 * (k2 + t2 * (k3 + t2 * k4)));
      const double th_d = th * poly;
      const double s = th_d / r;
      xy_d = s * xy;
      if (d_uv_d_xy) {
        const double d_thd_d_th = 1.0 + t2 * (3.0 * k1 + t2 * (5.0 * k2 + t2 * (7.0 * k3 + t2 * 9.0 * k4)));
        const double d_thd_d_r = d_thd_d_th / (1.0 + r2);
        const double d_s_d_r = (d_thd_d_r * r - th_d) / r2;
        J = s * Eigen::Matrix2d::Identity() + (d_s_d_r / r) * xy * xy.transpose();
      }
      break;
    }
  }
  if (d_uv_d_xy) {
    d_uv_d_xy->row(0) = pinhole_.fx * J.row(0);
    d_uv_d_xy->row(1) = pinhole_.fy * J.row(1);
  }
  return pinhole_.project(xy_d);
}

bool Camera::project(const Eigen::Vector3d& p_c, Eigen::Vector2d* uv, Eigen::Matrix<double, 2, 3>* d_uv_d_p_c) const {
  const double z = p_c.z();
  if (!(z > kMinDepth)) return false;
  const double inv_z = 1.0 / z;
  const Eigen::Vector2d xy(p_c.x() * inv_z, p_c.y() * inv_z);
  if (!d_uv_d_p_c) {
    *uv = distortNormalized(xy);
    return true;
  }
  Eigen::Matrix2d d_uv_d_xy;
  *uv = distortNormalized(xy, &d_uv_d_xy);
  Eigen::Matrix<double, 2, 3> d_xy_d_p;
  d_xy_d_p << inv_z, 0.0, -xy.x() * inv_z, 0.0, inv_z, -xy.y() * inv_z;
  *d_uv_d_p_c = d_uv_d_xy * d_xy_d_p;
  return true;
}

namespace {

// Equidistant: theta from theta_d by 1-D Newton (theta_d(theta) is increasing
// over the lens' field of view). Returns false if no solution below 90 degrees.
bool solveTheta(const std::vector<double>& k, double theta_d, double* theta) {
  double th = theta_d;
  for (int it = 0; it < kMaxIterations; ++it) {
    const double t2 = th * th;
    const double f = th * (1.0 + t2 * (k[0] + t2 * (k[1] + t2 * (k[2] + t2 * k[3])))) - theta_d;
    const double df = 1.0 + t2 * (3.0 * k[0] + t2 * (5.0 * k[1] + t2 * (7.0 * k[2] + t2 * 9.0 * k[3])));
    if (!(df > 1e-12)) return false;
    const double step = f / df;
    th -= step;
    if (!std::isfinite(th)) return false;
    if (std::abs(step) < 1e-15) break;
  }
  *theta = th;
  return th >= 0.0 && th < M_PI / 2 - 1e-6;
}

}  // namespace

bool Camera::unprojectNormalized(const Eigen::Vector2d& uv, Eigen::Vector2d* xy_out) const {
  if (!uv.allFinite()) return false;
  const Eigen::Vector2d xy_d = pinhole_.unproject(uv);
  if (model_ == DistortionModel::kNone) {
    *xy_out = xy_d;
    return true;
  }
  Eigen::Vector2d xy = xy_d;
  if (model_ == DistortionModel::kEquidistant) {
    const double rd = xy_d.norm();
    if (rd > 1e-12) {
      double th = 0.0;
      if (!solveTheta(distortion_, rd, &th)) return false;
      xy = xy_d * (std::tan(th) / rd);
    }
  }
  // Gauss-Newton (2x2, so Newton) with step halving on the pixel residual; for
  // the equidistant model this only polishes the closed-form start.
  Eigen::Matrix2d J;
  Eigen::Vector2d res = distortNormalized(xy, &J) - uv;
  double err = res.norm();
  for (int it = 0; it < kMaxIterations && err >= kConvergedPx; ++it) {
    const double det = J.determinant();
    if (!(std::abs(det) > 1e-12)) return false;
    Eigen::Vector2d step = J.inverse() * res;
    bool improved = false;
    for (int halvings = 0; halvings < 30; ++halvings) {
      const Eigen::Vector2d cand = xy - step;
      Eigen::Matrix2d Jc;
      const Eigen::Vector2d rc = distortNormalized(cand, &Jc) - uv;
      if (rc.allFinite() && rc.norm() < err) {
        xy = cand;
        res = rc;
        J = Jc;
        err = rc.norm();
        improved = true;
        break;
      }
      step *= 0.5;
    }
    if (!improved) break;
  }
  if (!(err < kConvergedPx)) return false;
  // Reject the folded branch of strong radial distortion (mapping not locally invertible).
  if (!(J.determinant() > 0.0)) return false;
  *xy_out = xy;
  return true;
}

bool Camera::unproject(const Eigen::Vector2d& uv, Eigen::Vector3d* bearing_c) const {
  Eigen::Vector2d xy;
  if (!unprojectNormalized(uv, &xy)) return false;
  *bearing_c = Eigen::Vector3d(xy.x(), xy.y(), 1.0).normalized();
  return true;
}

bool Camera::inImage(const Eigen::Vector2d& uv, double border) const {
  return uv.x() >= border && uv.y() >= border && uv.x() <= width_ - 1.0 - border && uv.y() <= height_ - 1.0 - border;
}

void Camera::undistortionMaps(cv::Mat* map_x, cv::Mat* map_y) const {
  map_x->create(height_, width_, CV_32FC1);
  map_y->create(height_, width_, CV_32FC1);
  for (int v = 0; v < height_; ++v) {
    float* mx = map_x->ptr<float>(v);
    float* my = map_y->ptr<float>(v);
    for (int u = 0; u < width_; ++u) {
      const Eigen::Vector2d d = distortNormalized(pinhole_.unproject(Eigen::Vector2d(u, v)));
      mx[u] = static_cast<float>(d.x());
      my[u] = static_cast<float>(d.y());
    }
  }
}

std::string Camera::describe() const {
  std::ostringstream os;
  os.precision(10);
  os << width_ << "x" << height_ << " fx=" << fx() << " fy=" << fy() << " cx=" << cx() << " cy=" << cy() << " "
     << toString(model_);
  if (!distortion_.empty()) {
    os << " [";
    for (std::size_t i = 0; i < distortion_.size(); ++i) os << (i ? " " : "") << distortion_[i];
    os << "]";
  }
  return os.str();
}

}  // namespace vitamin_e::camera
