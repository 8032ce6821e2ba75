// OpenCV's lens distortion model: between the image a camera records and the ideal pinhole image
// of the same focal length and principal point.
#pragma once

#include <Eigen/Core>

#include <array>
#include <string>
#include <utility>
#include <vector>

namespace multislit {

/// OpenCV's distortion coefficients of normalized image coordinates (x, y) = ((u - cx) / f,
/// (v - cy) / f): the plumb bob model (k1, k2, p1, p2, k3) and the rational model's k4, k5, k6.
/// With r^2 = x^2 + y^2 a recorded point is
///   x' = x (1 + k1 r^2 + k2 r^4 + k3 r^6) / (1 + k4 r^2 + k5 r^4 + k6 r^6) + 2 p1 x y + p2 (r^2 +
///   2 x^2), and y' likewise with p1 and p2 exchanged. All zero: a pinhole.
struct LensDistortion {
  double k1 = 0, k2 = 0, p1 = 0, p2 = 0, k3 = 0, k4 = 0, k5 = 0, k6 = 0;

  bool any() const { return k1 != 0 || k2 != 0 || p1 != 0 || p2 != 0 || k3 != 0 || rational(); }
  bool rational() const { return k4 != 0 || k5 != 0 || k6 != 0; }
  /// From OpenCV's order (k1, k2, p1, p2[, k3[, k4, k5, k6[, s1..s4[, tx, ty]]]]): 4, 5, 8, 12
  /// or 14 numbers, the thin prism and tilt terms zero. Throws std::invalid_argument otherwise.
  static LensDistortion fromOpenCV(const std::vector<double>& c);
  /// Throws std::invalid_argument naming `where`.<key> unless every coefficient is finite, the
  /// radial ones within +-1000 and the tangential ones within +-1.
  void validate(const std::string& where) const;
};

/// The coefficients by their names in OpenCV's order (the keys of the sensor and calibration
/// files).
using DistortionKey = std::pair<const char*, double LensDistortion::*>;
inline constexpr std::array<DistortionKey, 8> kDistortionKeys = {{{"k1", &LensDistortion::k1},
                                                                  {"k2", &LensDistortion::k2},
                                                                  {"p1", &LensDistortion::p1},
                                                                  {"p2", &LensDistortion::p2},
                                                                  {"k3", &LensDistortion::k3},
                                                                  {"k4", &LensDistortion::k4},
                                                                  {"k5", &LensDistortion::k5},
                                                                  {"k6", &LensDistortion::k6}}};

/// A camera's pinhole intrinsics with its distortion: maps pixels between the recorded image and
/// the ideal image (the pinhole's, where straight lines stay straight).
class Lens {
 public:
  Lens() = default;
  Lens(double f, double cx, double cy, const LensDistortion& distortion);

  double f() const { return f_; }
  double cx() const { return cx_; }
  double cy() const { return cy_; }
  const LensDistortion& distortion() const { return d_; }
  bool distorted() const { return d_.any(); }

  /// The recorded pixel of an ideal one, and (when `jacobian` is given) its derivative
  /// d recorded / d ideal there.
  Eigen::Vector2d distort(const Eigen::Vector2d& ideal, Eigen::Matrix2d* jacobian = nullptr) const;
  /// The ideal pixel of a recorded one (Newton's method to 1e-9 px); NaN where none is found
  /// (beyond where the model folds).
  Eigen::Vector2d undistort(const Eigen::Vector2d& recorded) const;
  /// Largest distance between a pixel of a w x h image and its ideal position [px] (at a corner
  /// or an edge's middle): how strongly the lens bends.
  double largestShift(int width, int height) const;
  /// Whether the radial map r -> r (1 + k1 r^2 ...) / (1 + k4 r^2 ...) rises over the ideal
  /// image of a w x h image (with a margin): where it does not, two ideal points share a recorded
  /// one and undistort() is ambiguous.
  bool monotonicOver(int width, int height) const;

 private:
  double f_ = 1, cx_ = 0, cy_ = 0, inverse_f_ = 1;
  LensDistortion d_;
  bool rational_ = false;  // d_.rational(): the radial factor has a denominator
};

}  // namespace multislit
