#include "multislit/intrinsics_file.h"

#include "yaml_io.h"

#include <cmath>
#include <stdexcept>
#include <vector>

namespace multislit {

namespace {

// The numbers of a matrix: an !!opencv-matrix (OpenCV) or a map with `data` (ROS), row-major.
std::vector<double> matrixData(const cv::FileNode& node, const std::string& key) {
  const cv::FileNode n = node[key];
  if (n.empty() || n.isNone()) throw std::invalid_argument("missing key '" + key + "'");
  if (!n.isMap()) throw std::invalid_argument("'" + key + "' must be a matrix");
  std::vector<double> data;
  if (!n["dt"].empty()) {  // OpenCV's !!opencv-matrix
    cv::Mat m;
    n >> m;
    if (m.empty() || m.channels() != 1)
      throw std::invalid_argument("'" + key + "' must be a one-channel matrix");
    m.convertTo(m, CV_64F);
    data.assign(m.begin<double>(), m.end<double>());
  } else {
    const cv::FileNode d = n["data"];
    if (!d.isSeq()) throw std::invalid_argument("'" + key + ".data' must be a list of numbers");
    for (const cv::FileNode& x : d) {
      if (!x.isInt() && !x.isReal())
        throw std::invalid_argument("'" + key + ".data' must be a list of numbers");
      data.push_back(static_cast<double>(x));
    }
  }
  for (const double x : data)
    if (!std::isfinite(x)) throw std::invalid_argument("'" + key + "' must be finite numbers");
  return data;
}

int imageSide(const cv::FileNode& root, const char* key) {
  if (root[key].empty()) throw std::invalid_argument(std::string("missing key '") + key + "'");
  int side = 0;
  readField(root, key, side);
  return side;
}

// The coefficients of `model` ("" for OpenCV's file: any count fromOpenCV takes).
LensDistortion distortionOf(const std::vector<double>& c, const std::string& model) {
  if (model == "plumb_bob" && c.size() != 5)
    throw std::invalid_argument("'distortion_coefficients' of plumb_bob must hold 5 numbers");
  if (model == "rational_polynomial" && c.size() != 8)
    throw std::invalid_argument(
        "'distortion_coefficients' of rational_polynomial must hold 8 numbers");
  try {
    return LensDistortion::fromOpenCV(c);
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(std::string("'distortion_coefficients' ") + e.what());
  }
}

CameraConfig readIntrinsics(const cv::FileStorage& fs, CameraConfig camera) {
  const cv::FileNode root = fs.root();
  const int width = imageSide(root, "image_width"), height = imageSide(root, "image_height");
  if (width != camera.width || height != camera.height)
    throw std::invalid_argument("image_width x image_height is " + std::to_string(width) + "x" +
                                std::to_string(height) + ", the camera's " +
                                std::to_string(camera.width) + "x" + std::to_string(camera.height));
  std::string model;
  if (!root["distortion_model"].empty()) {
    readField(root, "distortion_model", model);
    if (model != "plumb_bob" && model != "rational_polynomial")
      throw std::invalid_argument(
          "'distortion_model' must be plumb_bob or rational_polynomial, "
          "not '" +
          model + "'");
  }
  const std::vector<double> k = matrixData(root, "camera_matrix");
  if (k.size() != 9) throw std::invalid_argument("'camera_matrix' must be 3x3");
  const double fx = k[0], fy = k[4], mean = 0.5 * (fx + fy);
  if (!(fx > 0 && fy > 0) || k[3] != 0 || k[6] != 0 || k[7] != 0 || k[8] != 1)
    throw std::invalid_argument("'camera_matrix' must be [fx 0 cx; 0 fy cy; 0 0 1], fx, fy > 0");
  if (std::abs(k[1]) > 1e-6 * mean)
    throw std::invalid_argument("'camera_matrix' has a skew, which this sensor does not model");
  if (std::abs(fx - fy) > kMaxFocalMismatch * mean)
    throw std::invalid_argument("'camera_matrix' fx " + std::to_string(fx) + " and fy " +
                                std::to_string(fy) +
                                " differ by more than 1 %: this sensor models square pixels");
  camera.focal_length = mean * camera.pixel_size;
  camera.principal_x = k[2];
  camera.principal_y = k[5];
  camera.distortion = distortionOf(matrixData(root, "distortion_coefficients"), model);
  SensorConfig check;
  check.camera = camera;
  check.validate();
  return camera;
}

}  // namespace

CameraConfig withIntrinsicsFile(const CameraConfig& camera, const std::string& path) {
  // ROS writes plain YAML; OpenCV reads only what begins with its directive.
  std::string text = detail::readWholeFile(path, "intrinsics", kMaxYamlBytes);
  if (text.rfind("%YAML", 0) != 0) text = "%YAML:1.0\n---\n" + text;
  cv::FileStorage fs = openYamlText(text, path, "intrinsics");
  try {
    return readIntrinsics(fs, camera);
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument("intrinsics '" + path + "': " + e.what());
  } catch (const cv::Exception& e) {
    throw std::invalid_argument("intrinsics '" + path + "': " + e.err);
  }
}

CameraConfig intrinsicsForImage(int width, int height, const std::string& path) {
  CameraConfig camera;
  camera.width = width;
  camera.height = height;
  return withIntrinsicsFile(camera, path);
}

}  // namespace multislit
