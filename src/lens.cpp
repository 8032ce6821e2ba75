#include "multislit/lens.h"

#include "config_check.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace multislit {

void LensDistortion::validate(const std::string& where) const {
  for (const auto& [key, field] : kDistortionKeys) {
    const double value = this->*field;
    const bool tangential = field == &LensDistortion::p1 || field == &LensDistortion::p2;
    const double limit = tangential ? 1 : 1000;
    detail::require(
        std::isfinite(value) && std::abs(value) <= limit, where + "." + key,
        tangential ? "must be finite, within [-1, 1]" : "must be finite, within [-1000, 1000]");
  }
}

LensDistortion LensDistortion::fromOpenCV(const std::vector<double>& c) {
  const std::size_t n = c.size();
  if (n != 4 && n != 5 && n != 8 && n != 12 && n != 14)
    throw std::invalid_argument(
        "must hold 4, 5, 8, 12 or 14 numbers (OpenCV's k1, k2, p1, p2, "
        "k3, k4, k5, k6, ...), not " +
        std::to_string(n));
  for (std::size_t i = 8; i < n; ++i)
    if (c[i] != 0)
      throw std::invalid_argument(
          "has thin prism or tilt terms (the 9th number on), which this "
          "sensor does not model");
  LensDistortion d;
  d.k1 = c[0], d.k2 = c[1], d.p1 = c[2], d.p2 = c[3];
  if (n >= 5) d.k3 = c[4];
  if (n >= 8) d.k4 = c[5], d.k5 = c[6], d.k6 = c[7];
  return d;
}

Lens::Lens(double f, double cx, double cy, const LensDistortion& distortion)
    : f_(f), cx_(cx), cy_(cy), inverse_f_(1.0 / f), d_(distortion), rational_(d_.rational()) {}

Eigen::Vector2d Lens::distort(const Eigen::Vector2d& ideal, Eigen::Matrix2d* jacobian) const {
  // Many calls (the renderer's every pixel): no division but the rational model's.
  const double x = (ideal.x() - cx_) * inverse_f_, y = (ideal.y() - cy_) * inverse_f_;
  const double r2 = x * x + y * y;
  const double num = 1 + r2 * (d_.k1 + r2 * (d_.k2 + r2 * d_.k3));
  const double den = rational_ ? 1 + r2 * (d_.k4 + r2 * (d_.k5 + r2 * d_.k6)) : 1.0;
  const double radial = rational_ ? num / den : num;
  const double xd = x * radial + 2 * d_.p1 * x * y + d_.p2 * (r2 + 2 * x * x);
  const double yd = y * radial + d_.p1 * (r2 + 2 * y * y) + 2 * d_.p2 * x * y;
  if (jacobian) {
    // d radial / d r2, then the chain rule through r2 = x^2 + y^2.
    const double dnum = d_.k1 + r2 * (2 * d_.k2 + 3 * r2 * d_.k3);
    const double dden = d_.k4 + r2 * (2 * d_.k5 + 3 * r2 * d_.k6);
    const double dradial = (dnum * den - num * dden) / (den * den);
    (*jacobian)(0, 0) = radial + 2 * x * x * dradial + 2 * d_.p1 * y + 6 * d_.p2 * x;
    (*jacobian)(0, 1) = 2 * x * y * dradial + 2 * d_.p1 * x + 2 * d_.p2 * y;
    (*jacobian)(1, 0) = 2 * x * y * dradial + 2 * d_.p1 * x + 2 * d_.p2 * y;
    (*jacobian)(1, 1) = radial + 2 * y * y * dradial + 6 * d_.p1 * y + 2 * d_.p2 * x;
  }
  return {cx_ + f_ * xd, cy_ + f_ * yd};
}

Eigen::Vector2d Lens::undistort(const Eigen::Vector2d& recorded) const {
  if (!distorted()) return recorded;
  Eigen::Vector2d ideal = recorded;
  for (int i = 0; i < 50; ++i) {
    Eigen::Matrix2d j;
    const Eigen::Vector2d error = distort(ideal, &j) - recorded;
    if (error.norm() < 1e-9) return ideal;
    const double det = j.determinant();
    if (!(std::abs(det) > 1e-12)) break;
    ideal -= j.inverse() * error;
  }
  const double nan = std::numeric_limits<double>::quiet_NaN();
  return {nan, nan};
}

double Lens::largestShift(int width, int height) const {
  double shift = 0;
  const double w = width - 1, h = height - 1;
  const double us[] = {0, 0.5 * w, w}, vs[] = {0, 0.5 * h, h};
  for (const double u : us)
    for (const double v : vs) {
      const Eigen::Vector2d p(u, v);
      shift = std::max(shift, (undistort(p) - p).norm());
    }
  return shift;
}

bool Lens::monotonicOver(int width, int height) const {
  // The radial map must rise from the centre until it passes the recorded image's farthest
  // corner (5 % beyond): then every recorded pixel has one ideal point on the way.
  const double corner =
      std::hypot(std::max(cx_, width - 1 - cx_), std::max(cy_, height - 1 - cy_)) / f_;
  const double step = corner / 400.0;
  double last = 0;
  for (int i = 1; i <= 4000; ++i) {  // ten times the corner's radius at most
    const double r = step * i, r2 = r * r;
    const double num = 1 + r2 * (d_.k1 + r2 * (d_.k2 + r2 * d_.k3));
    const double den = 1 + r2 * (d_.k4 + r2 * (d_.k5 + r2 * d_.k6));
    const double mapped = r * num / den;
    if (!(den > 0) || !(mapped > last)) return false;
    if (mapped > 1.05 * corner) return true;
    last = mapped;
  }
  return false;
}

}  // namespace multislit
