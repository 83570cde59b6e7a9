// Calibration file loaders: EuRoC sensor.yaml, Kalibr camchain, ROS
// camera_info yaml, KITTI calib.txt, and format detection.
#include <algorithm>
#include <cctype>
#include <fstream>
#include <sstream>

#include <yaml-cpp/yaml.h>

#include "vitamin_e/camera/camera.h"

namespace vitamin_e::camera {

namespace {

[[noreturn]] void fail(const std::string& path, const std::string& what) {
  throw CalibrationError("calibration file '" + path + "': " + what);
}

std::string readText(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) fail(path, "cannot be opened");
  std::ostringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

// OpenCV FileStorage yaml ("%YAML:1.0" directive, "!!opencv-matrix" tags) made
// readable by yaml-cpp: drop the directive line and the tags.
std::string sanitizeOpenCvYaml(const std::string& text) {
  std::istringstream in(text);
  std::ostringstream out;
  std::string line;
  while (std::getline(in, line)) {
    if (line.rfind("%YAML", 0) == 0) continue;
    std::size_t pos;
    while ((pos = line.find("!!opencv-matrix")) != std::string::npos) line.erase(pos, 15);
    out << line << "\n";
  }
  return out.str();
}

YAML::Node parseYaml(const std::string& path, const std::string& text) {
  try {
    YAML::Node root = YAML::Load(sanitizeOpenCvYaml(text));
    if (!root.IsMap()) fail(path, "is not a yaml mapping");
    return root;
  } catch (const YAML::Exception& e) {
    fail(path, std::string("yaml parse error: ") + e.what());
  }
}

const YAML::Node need(const std::string& path, const YAML::Node& node, const std::string& key) {
  const YAML::Node n = node[key];
  if (!n) fail(path, "missing key '" + key + "'");
  return n;
}

double toDouble(const std::string& path, const YAML::Node& n, const std::string& key) {
  try {
    return n.as<double>();
  } catch (const YAML::Exception&) {
    fail(path, "'" + key + "' must be a number");
  }
}

// A list of numbers: "[a, b, ...]", a nested list of rows, or an OpenCV matrix
// map {rows, cols, data}. Returns the numbers row-major.
std::vector<double> readNumbers(const std::string& path, const YAML::Node& n, const std::string& key) {
  std::vector<double> out;
  if (n.IsMap()) {
    const YAML::Node data = need(path, n, "data");
    out = readNumbers(path, data, key + ".data");
    if (n["rows"] && n["cols"]) {
      const double rows = toDouble(path, n["rows"], key + ".rows");
      const double cols = toDouble(path, n["cols"], key + ".cols");
      if (rows * cols != static_cast<double>(out.size())) {
        fail(path, "'" + key + "' has " + std::to_string(out.size()) + " values, rows*cols says " +
                       std::to_string(static_cast<int>(rows * cols)));
      }
    }
    return out;
  }
  if (!n.IsSequence()) fail(path, "'" + key + "' must be a list of numbers");
  for (const auto& item : n) {
    if (item.IsSequence()) {
      for (const auto& v : item) out.push_back(toDouble(path, v, key));
    } else {
      out.push_back(toDouble(path, item, key));
    }
  }
  return out;
}

std::vector<double> readNumbers(const std::string& path, const YAML::Node& node, const std::string& key,
                                std::size_t count) {
  std::vector<double> v = readNumbers(path, need(path, node, key), key);
  if (v.size() != count) {
    fail(path, "'" + key + "' must have " + std::to_string(count) + " values, has " + std::to_string(v.size()));
  }
  return v;
}

std::string readString(const std::string& path, const YAML::Node& node, const std::string& key) {
  try {
    return need(path, node, key).as<std::string>();
  } catch (const YAML::Exception&) {
    fail(path, "'" + key + "' must be a string");
  }
}

Eigen::Isometry3d toIsometry(const std::string& path, const std::vector<double>& m, const std::string& key) {
  Eigen::Matrix4d T;
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) T(r, c) = m[4 * r + c];
  const Eigen::Matrix3d R = T.topLeftCorner<3, 3>();
  if (!T.allFinite() || (R.transpose() * R - Eigen::Matrix3d::Identity()).norm() > 1e-3 || R.determinant() < 0.0 ||
      (T.row(3) - Eigen::RowVector4d(0, 0, 0, 1)).norm() > 1e-9) {
    fail(path, "'" + key + "' is not a rigid transform");
  }
  // Re-orthonormalize (files carry ~1e-6 rounding).
  Eigen::JacobiSVD<Eigen::Matrix3d> svd(R, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Isometry3d iso = Eigen::Isometry3d::Identity();
  iso.linear() = svd.matrixU() * svd.matrixV().transpose();
  iso.translation() = T.topRightCorner<3, 1>();
  return iso;
}

DistortionModel parseModel(const std::string& path, std::string name) {
  std::transform(name.begin(), name.end(), name.begin(), [](unsigned char c) { return std::tolower(c); });
  if (name == "radial-tangential" || name == "radtan" || name == "plumb_bob" || name == "radial_tangential")
    return DistortionModel::kRadialTangential;
  if (name == "equidistant" || name == "fisheye" || name == "kannala_brandt" || name == "kannala-brandt")
    return DistortionModel::kEquidistant;
  if (name == "none" || name.empty()) return DistortionModel::kNone;
  fail(path, "unsupported distortion model '" + name + "' (radial-tangential, equidistant or none)");
}

Camera makeCamera(const std::string& path, int w, int h, double fx, double fy, double cx, double cy,
                  DistortionModel model, std::vector<double> dist) {
  try {
    Camera cam(w, h, fx, fy, cx, cy, model, dist);
    // All-zero coefficients are the pinhole model (cheaper, same result).
    if (std::all_of(dist.begin(), dist.end(), [](double d) { return d == 0.0; })) cam = Camera(w, h, fx, fy, cx, cy);
    return cam;
  } catch (const CalibrationError& e) {
    fail(path, e.what());
  }
}

Camera cameraFromIntrinsics(const std::string& path, const YAML::Node& node, const std::string& dist_key) {
  const std::string model_name = node["camera_model"] ? readString(path, node, "camera_model") : "pinhole";
  if (model_name != "pinhole") fail(path, "unsupported camera_model '" + model_name + "' (only pinhole)");
  const std::vector<double> in = readNumbers(path, node, "intrinsics", 4);
  const std::vector<double> res = readNumbers(path, node, "resolution", 2);
  const DistortionModel model =
      node["distortion_model"] ? parseModel(path, readString(path, node, "distortion_model")) : DistortionModel::kNone;
  std::vector<double> dist;
  if (node[dist_key]) dist = readNumbers(path, node[dist_key], dist_key);
  return makeCamera(path, static_cast<int>(res[0]), static_cast<int>(res[1]), in[0], in[1], in[2], in[3], model, dist);
}

bool looksLikeKitti(const std::string& text) {
  std::istringstream in(text);
  std::string line;
  while (std::getline(in, line)) {
    std::istringstream ls(line);
    std::string first;
    if (!(ls >> first)) continue;
    if (first.size() == 3 && first[0] == 'P' && std::isdigit(static_cast<unsigned char>(first[1])) && first[2] == ':')
      return true;
    // Bare lines of 12 numbers (some KITTI excerpts drop the "P0:" labels).
    std::istringstream ns(line);
    double v;
    int count = 0;
    while (ns >> v) ++count;
    return count == 12 && ns.eof();
  }
  return false;
}

}  // namespace

CameraCalibration loadEurocSensorYaml(const std::string& path) {
  const YAML::Node root = parseYaml(path, readText(path));
  CameraCalibration calib;
  calib.format = "euroc";
  calib.camera = cameraFromIntrinsics(path, root, "distortion_coefficients");
  if (root["T_BS"]) calib.T_b_c = toIsometry(path, readNumbers(path, root, "T_BS", 16), "T_BS");
  if (root["rate_hz"]) calib.rate_hz = toDouble(path, root["rate_hz"], "rate_hz");
  return calib;
}

CameraCalibration loadKalibrCamchain(const std::string& path, int cam_index) {
  const YAML::Node root = parseYaml(path, readText(path));
  const std::string key = "cam" + std::to_string(cam_index);
  const YAML::Node cam = need(path, root, key);
  if (!cam.IsMap()) fail(path, "'" + key + "' must be a mapping");
  CameraCalibration calib;
  calib.format = "kalibr";
  calib.camera = cameraFromIntrinsics(path, cam, "distortion_coeffs");
  if (cam["T_cam_imu"])
    calib.T_b_c = toIsometry(path, readNumbers(path, cam, "T_cam_imu", 16), key + ".T_cam_imu").inverse();
  return calib;
}

CameraCalibration loadRosCameraInfoYaml(const std::string& path) {
  const YAML::Node root = parseYaml(path, readText(path));
  const int w = static_cast<int>(toDouble(path, need(path, root, "image_width"), "image_width"));
  const int h = static_cast<int>(toDouble(path, need(path, root, "image_height"), "image_height"));
  const std::vector<double> K = readNumbers(path, root, "camera_matrix", 9);
  if (K[1] != 0.0 || K[3] != 0.0 || K[6] != 0.0 || K[7] != 0.0 || K[8] != 1.0)
    fail(path, "'camera_matrix' must be [fx 0 cx; 0 fy cy; 0 0 1]");
  std::string model_name = root["distortion_model"] ? readString(path, root, "distortion_model") : "none";
  std::vector<double> dist;
  if (root["distortion_coefficients"])
    dist = readNumbers(path, root["distortion_coefficients"], "distortion_coefficients");
  if (model_name == "rational_polynomial") {
    // k1 k2 p1 p2 k3 k4 k5 k6: representable only when the denominator terms are zero.
    if (dist.size() != 8 || dist[5] != 0.0 || dist[6] != 0.0 || dist[7] != 0.0)
      fail(path, "rational_polynomial is supported only with k4 = k5 = k6 = 0");
    dist.resize(5);
    model_name = "plumb_bob";
  }
  const DistortionModel model = parseModel(path, model_name);
  if (model == DistortionModel::kRadialTangential && dist.size() == 5 && dist[4] == 0.0) dist.resize(4);
  CameraCalibration calib;
  calib.format = "ros_camera_info";
  calib.camera = makeCamera(path, w, h, K[0], K[4], K[2], K[5], model, dist);
  return calib;
}

CameraCalibration loadKittiCalib(const std::string& path, int width, int height, int camera_index) {
  std::istringstream in(readText(path));
  std::string line;
  std::vector<double> P;
  int bare_index = 0;
  const std::string label = "P" + std::to_string(camera_index) + ":";
  while (std::getline(in, line)) {
    std::istringstream ls(line);
    std::string first;
    if (!(ls >> first)) continue;
    std::vector<double> values;
    bool labelled = !first.empty() && first.back() == ':';
    if (labelled && first != label) continue;
    if (!labelled) {
      if (bare_index++ != camera_index) continue;
      ls.clear();
      ls.str(line);
    }
    double v;
    while (ls >> v) values.push_back(v);
    if (!ls.eof() || values.size() != 12)
      fail(path, "projection line for camera " + std::to_string(camera_index) + " must have 12 numbers");
    P = values;
    break;
  }
  if (P.empty()) fail(path, "no projection matrix " + label + " (KITTI calib.txt)");
  if (width <= 0 || height <= 0) fail(path, "KITTI calibration needs the image size (read from the first image)");
  CameraCalibration calib;
  calib.format = "kitti";
  calib.camera = makeCamera(path, width, height, P[0], P[5], P[2], P[6], DistortionModel::kNone, {});
  // P_i = K [I | t_i], t_i = cam0 origin seen from camera i; body = camera 0.
  calib.T_b_c.translation() = Eigen::Vector3d::Zero() - Eigen::Vector3d(P[3] / P[0], P[7] / P[5], P[11]);
  calib.rate_hz = 10.0;
  return calib;
}

CameraCalibration loadCalibration(const std::string& path, int width, int height) {
  const std::string text = readText(path);
  if (looksLikeKitti(text)) return loadKittiCalib(path, width, height, 0);
  const YAML::Node root = parseYaml(path, text);
  if (root["cam0"]) return loadKalibrCamchain(path, 0);
  if (root["camera_matrix"] || root["image_width"]) return loadRosCameraInfoYaml(path);
  if (root["intrinsics"]) return loadEurocSensorYaml(path);
  fail(path, "unknown calibration format (expected EuRoC sensor.yaml, Kalibr camchain, ROS camera_info yaml "
             "or KITTI calib.txt)");
}

}  // namespace vitamin_e::camera
