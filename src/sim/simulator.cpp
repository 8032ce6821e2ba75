#include "multislit/sim/simulator.h"

#include <boost/math/special_functions/gamma.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include <cmath>
#include <fstream>
#include <limits>
#include <stdexcept>

namespace multislit {
namespace {

// Counter-based random numbers: each image row has its own stream, so the bytes do not depend
// on how rows are shared between threads.
class RowRandom {
 public:
  RowRandom(uint64_t seed, uint64_t frame, uint64_t row, uint64_t stream)
      : state_(mix(mix(mix(seed) ^ frame) ^ (row << 8 | stream))) {}

  double uniform() { return static_cast<double>(next() >> 11) * 0x1.0p-53; }
  double normal() {
    if (has_spare_) {
      has_spare_ = false;
      return spare_;
    }
    const double u1 = 1.0 - uniform(), u2 = uniform();  // u1 in (0, 1]
    const double r = std::sqrt(-2.0 * std::log(u1));
    spare_ = r * std::sin(2.0 * M_PI * u2);
    has_spare_ = true;
    return r * std::cos(2.0 * M_PI * u2);
  }

 private:
  static uint64_t mix(uint64_t z) {
    z += 0x9E3779B97F4A7C15ULL;
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
    return z ^ (z >> 31);
  }
  uint64_t next() { return mix(state_ += 0x9E3779B97F4A7C15ULL); }

  uint64_t state_;
  double spare_ = 0.0;
  bool has_spare_ = false;
};

enum Stream : uint64_t { kSpeckle = 1, kSensorNoise = 2 };

// The gamma speckle's quantile table: standard normal values z in [-reach, reach], `step` per unit.
constexpr double kQuantileReach = 8.0, kQuantileStep = 128.0;

// Gamma(shape k, mean 1) quantile at the normal quantile of each z of the table.
std::vector<float> gammaQuantiles(double contrast) {
  const double k = 1.0 / (contrast * contrast);
  const int n = static_cast<int>(2 * kQuantileReach * kQuantileStep) + 1;
  std::vector<float> table(static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i) {
    const double z = i / kQuantileStep - kQuantileReach;
    // The lower tail from P, the upper tail from Q: both accurate far out.
    const double x = z < 0 ? boost::math::gamma_p_inv(k, 0.5 * std::erfc(-z / std::sqrt(2.0)))
                           : boost::math::gamma_q_inv(k, 0.5 * std::erfc(z / std::sqrt(2.0)));
    table[static_cast<std::size_t>(i)] = static_cast<float>(x / k);
  }
  return table;
}

// Mean of exp(-x^2 / 2 sigma^2) over a pixel on which x = d0 + a p + b q, p and q uniform in
// [-1/2, 1/2]: a Gaussian sheet profile integrated exactly over a pixel where the sheet offset
// is linear. With F(z) = z erf(z) + exp(-z^2) / sqrt(pi), the antiderivative of erf.
double pixelMeanOfGaussian(double d0, double a, double b, double sigma) {
  a = std::abs(a);
  b = std::abs(b);
  if (a < b) std::swap(a, b);
  const double k = 1.0 / (sigma * std::sqrt(2.0));
  if (a < 0.02 * sigma) return std::exp(-0.5 * d0 * d0 / (sigma * sigma));
  const double scale = sigma * std::sqrt(M_PI / 2.0) / a;
  if (b < 0.02 * sigma) return scale * (std::erf(k * (d0 + a / 2)) - std::erf(k * (d0 - a / 2)));
  auto F = [](double z) { return z * std::erf(z) + std::exp(-z * z) / std::sqrt(M_PI); };
  return scale / (b * k) *
         (F(k * (d0 + a / 2 + b / 2)) - F(k * (d0 - a / 2 + b / 2)) - F(k * (d0 + a / 2 - b / 2)) +
          F(k * (d0 - a / 2 - b / 2)));
}

// Everything needed to shade one ray, in world coordinates.
struct Shader {
  const Scene& scene;
  const SensorGeometry& geometry;
  const RenderConfig& render;
  Eigen::Isometry3d world_from_camera;
  Eigen::Vector3d camera_centre, projector_centre;
  double sigma;  // the sheet's width as rendered, before the surface's factor [rad]

  // What one ray sees: the surface, its albedo and ambient light and, near a sheet, the laser's
  // radiance before the sheet profile (0 when shadowed, facing away or beyond the slit's end).
  struct Sample {
    int object = -1;
    int slit = 0;
    double offset = std::numeric_limits<double>::infinity();  // from the nearest sheet [rad]
    double t = 0;         // position along the slit (projector y / z)
    double albedo = 0;    // at 660 nm
    double radiance = 0;  // laser at the sheet's centre [FS]
    float glare = 0;      // ambient mirrored by a glossy floor, relative to albedo 1
    float width = 1;      // factor on the sheet's width on this surface
  };

  // `known_object` and `known_albedo` pass the pixel centre's albedo to its sub-samples: the
  // floor's grain is many pixels wide.
  Sample trace(double u, double v, double reach, int known_object = -2,
               double known_albedo = 0) const {
    Sample s;
    const Eigen::Vector3d ray_c = geometry.pixelRay(u, v).normalized();
    const Eigen::Vector3d ray_w = world_from_camera.linear() * ray_c;
    const Hit hit = scene.intersect(camera_centre, ray_w);
    s.object = hit.object;
    if (!hit.valid()) return s;
    const Eigen::Vector2d xy = geometry.toProjector(hit.distance * ray_c);
    s.offset = geometry.nearestSheetOffset(xy, &s.slit);
    s.t = xy.y();
    const Eigen::Vector3d point_w = camera_centre + hit.distance * ray_w;
    s.albedo = hit.object == known_object ? known_albedo : scene.albedo(hit.object, point_w);
    if (hit.object == 0 && scene.floor.gloss > 0)
      s.glare = static_cast<float>(scene.floorGlare(point_w, ray_w));
    if (std::abs(s.offset) > reach || std::abs(s.t) > geometry.slitTMax()) return s;
    const Eigen::Vector3d to_point = point_w - projector_centre;
    const double range = to_point.norm();
    const Eigen::Vector3d dir = to_point / range;
    const double incidence = -hit.normal.dot(dir);
    if (incidence <= 0) return s;
    if (scene.intersect(projector_centre, dir, range * (1.0 - 1e-9)).valid()) return s;  // shadow
    // The sheet's power is kept when the surface widens it: its peak drops by the same factor.
    const double width = scene.stripeWidth(hit.object);
    s.width = static_cast<float>(width);
    s.radiance = render.laser_peak * s.albedo * incidence * (0.5 / range) * (0.5 / range) *
                 (scene.laserAlbedo(hit.object) / (render.stripe_width * width));
    return s;
  }

  double laser(const Sample& s) const {
    const double sheet = sigma * s.width;
    return s.radiance * std::exp(-0.5 * s.offset * s.offset / (sheet * sheet));
  }
};

// Multiplies `laser` by the speckle of `render` (mean 1, std speckle_contrast per pixel): a
// white Gaussian field blurred by the grain, then either 1 + contrast x field clamped at 0
// (Gaussian) or the field's normal quantile mapped to the gamma distribution's (Gamma).
void applySpeckle(cv::Mat& laser, const RenderConfig& render, uint64_t frame,
                  const std::vector<float>& gamma_quantiles) {
  cv::Mat speckle(laser.rows, laser.cols, CV_32F);
  cv::parallel_for_(cv::Range(0, laser.rows), [&](const cv::Range& rows) {
    for (int r = rows.start; r < rows.end; ++r) {
      RowRandom rng(render.seed, frame, static_cast<uint64_t>(r), kSpeckle);
      float* s = speckle.ptr<float>(r);
      for (int c = 0; c < laser.cols; ++c) s[c] = static_cast<float>(rng.normal());
    }
  });
  const double g = render.speckle_grain;
  cv::GaussianBlur(speckle, speckle, cv::Size(), g, g, cv::BORDER_REFLECT);
  if (render.speckle_model == SpeckleModel::Gaussian) {
    speckle = 1.0 + render.speckle_contrast * 2.0 * std::sqrt(M_PI) * g * speckle;
    cv::max(speckle, 0.0, speckle);
  } else {
    // The blurred field's std is the sum of the squared 1-D kernel weights (OpenCV's kernel).
    const cv::Mat k = cv::getGaussianKernel(cv::saturate_cast<int>(g * 8 + 1) | 1, g, CV_64F);
    const double scale = 1.0 / k.dot(k), last = static_cast<double>(gamma_quantiles.size() - 1);
    cv::parallel_for_(cv::Range(0, laser.rows), [&](const cv::Range& rows) {
      for (int r = rows.start; r < rows.end; ++r) {
        float* s = speckle.ptr<float>(r);
        for (int c = 0; c < laser.cols; ++c) {
          const double x = std::clamp((s[c] * scale + kQuantileReach) * kQuantileStep, 0.0, last);
          const auto i = std::min(static_cast<std::size_t>(x), gamma_quantiles.size() - 2);
          const double f = x - static_cast<double>(i);
          s[c] = static_cast<float>((1 - f) * gamma_quantiles[i] + f * gamma_quantiles[i + 1]);
        }
      }
    });
  }
  laser = laser.mul(speckle);
}

}  // namespace

void RenderConfig::validate() const {
  auto require = [](bool ok, const char* field, const char* rule) {
    if (!ok) throw std::invalid_argument(std::string("render config: ") + field + " " + rule);
  };
  require(laser_peak >= 0, "laser_peak", "must be >= 0");
  require(ambient >= 0, "ambient", "must be >= 0");
  if (speckle_model == SpeckleModel::Gaussian)
    require(speckle_contrast >= 0 && speckle_contrast < 1, "speckle_contrast",
            "must be in [0, 1) (Gaussian speckle)");
  else
    require(speckle_contrast >= 0 && speckle_contrast <= 1, "speckle_contrast",
            "must be in [0, 1] (gamma speckle)");
  require(speckle_grain >= 0.3 && speckle_grain <= 10, "speckle_grain", "must be in [0.3, 10] px");
  require(blur_sigma >= 0 && blur_sigma <= 10, "blur_sigma", "must be in [0, 10] px");
  require(full_well >= 100, "full_well", "must be >= 100 e-");
  require(read_noise >= 0 && read_noise < 0.5, "read_noise", "must be in [0, 0.5) FS");
  require(bit_depth == 8 || bit_depth == 16, "bit_depth", "must be 8 or 16");
  require(supersample >= 1 && supersample <= 16, "supersample", "must be in [1, 16]");
  require(stripe_width >= 0.25 && stripe_width <= 4, "stripe_width", "must be in [0.25, 4]");
  require(gamma >= 0.2 && gamma <= 5, "gamma", "must be in [0.2, 5]");
}

Simulator::Simulator(const SensorConfig& sensor, const RenderConfig& render)
    : geometry_(sensor), render_(render) {
  render_.validate();
  if (render_.speckle_model == SpeckleModel::Gamma && render_.speckle_contrast > 0)
    gamma_quantiles_ = gammaQuantiles(render_.speckle_contrast);
}

RenderedFrame Simulator::renderReference(const Scene& floor,
                                         const MountConfig& reference_mount) const {
  return render(floor, geometry_.robotFromCamera(reference_mount), kReferenceFrame);
}

RenderedFrame Simulator::render(const Scene& scene, const Eigen::Isometry3d& world_from_camera,
                                uint64_t frame) const {
  const int width = geometry_.config().camera.width, height = geometry_.config().camera.height;
  const double sigma = geometry_.config().projector.sheet_sigma * render_.stripe_width,
               pixel = 1.0 / geometry_.config().camera.f();
  const Shader shader{scene,
                      geometry_,
                      render_,
                      world_from_camera,
                      world_from_camera.translation(),
                      world_from_camera * geometry_.projectorCentre(),
                      sigma};

  // 1. Every pixel centre: its surface, ambient light and where the laser sheets are.
  double widest = scene.stripeWidth(0);  // the widest sheet on any surface
  for (std::size_t k = 0; k < scene.objects.size(); ++k)
    widest = std::max(widest, scene.stripeWidth(static_cast<int>(k) + 1));
  // Beyond 4.5 sigma a sheet adds < 4e-5 of its peak.
  const double reach = 4.5 * sigma * widest + 2 * pixel;
  std::vector<Shader::Sample> centre(static_cast<std::size_t>(width) * height);
  cv::Mat ambient(height, width, CV_32F), near(height, width, CV_8U);
  cv::parallel_for_(cv::Range(0, height), [&](const cv::Range& rows) {
    for (int r = rows.start; r < rows.end; ++r) {
      for (int c = 0; c < width; ++c) {
        const Shader::Sample& s = centre[static_cast<std::size_t>(r) * width + c] =
            shader.trace(c, r, reach);
        ambient.ptr<float>(r)[c] = static_cast<float>(render_.ambient * (s.albedo + s.glare));
        near.ptr<uchar>(r)[c] =
            std::abs(s.offset) < reach && std::abs(s.t) < geometry_.slitTMax() + 2 * pixel;
      }
    }
  });
  cv::dilate(near, near, cv::Mat::ones(3, 3, CV_8U));  // catch pixels split by an edge

  // 2. Laser light integrated over each pixel near a sheet: exactly where the sheet's offset is
  // linear over the pixel (same surface and slit, lit, not at the slit's end), else sampled
  // at n x n sub-pixel positions (edges, shadows, slit ends).
  const int n = render_.supersample;
  const double t_inner = geometry_.slitTMax() - 3 * pixel;
  cv::Mat laser(height, width, CV_32F, cv::Scalar(0));
  auto at = [&](int r, int c) -> const Shader::Sample& {
    return centre[static_cast<std::size_t>(r) * width + c];
  };
  auto linear = [&](int r, int c) {
    if (r < 1 || c < 1 || r >= height - 1 || c >= width - 1) return false;
    const Shader::Sample& m = at(r, c);
    for (const Shader::Sample* q : {&at(r, c - 1), &at(r, c + 1), &at(r - 1, c), &at(r + 1, c), &m})
      if (q->object != m.object || q->slit != m.slit || !(q->radiance > 0) ||
          std::abs(q->t) > t_inner)
        return false;
    return std::abs(at(r, c - 1).offset + at(r, c + 1).offset - 2 * m.offset) < 0.02 * sigma &&
           std::abs(at(r - 1, c).offset + at(r + 1, c).offset - 2 * m.offset) < 0.02 * sigma;
  };
  cv::parallel_for_(cv::Range(0, height), [&](const cv::Range& rows) {
    for (int r = rows.start; r < rows.end; ++r) {
      for (int c = 0; c < width; ++c) {
        if (!near.ptr<uchar>(r)[c]) continue;
        const Shader::Sample& m = at(r, c);
        double value = 0;
        if (linear(r, c)) {
          const double gu = 0.5 * (at(r, c + 1).offset - at(r, c - 1).offset);
          const double gv = 0.5 * (at(r + 1, c).offset - at(r - 1, c).offset);
          value = m.radiance * pixelMeanOfGaussian(m.offset, gu, gv, sigma * m.width);
        } else {
          for (int j = 0; j < n; ++j)
            for (int i = 0; i < n; ++i)
              value += shader.laser(shader.trace(c - 0.5 + (i + 0.5) / n, r - 0.5 + (j + 0.5) / n,
                                                 reach, m.object, m.albedo));
          value /= n * n;
        }
        laser.ptr<float>(r)[c] = static_cast<float>(value);
      }
    }
  });

  // 3. Laser speckle: multiplicative, spatially correlated over a grain.
  if (render_.noise && render_.speckle_contrast > 0)
    applySpeckle(laser, render_, frame, gamma_quantiles_);

  // 4. Lens blur, then shot and read noise, saturation and quantization.
  cv::Mat irradiance = ambient + laser;
  if (render_.blur_sigma > 0)
    cv::GaussianBlur(irradiance, irradiance, cv::Size(), render_.blur_sigma, render_.blur_sigma,
                     cv::BORDER_REFLECT);
  const double full = render_.bit_depth == 8 ? 255.0 : 65535.0;
  RenderedFrame out;
  out.image.create(height, width, render_.bit_depth == 8 ? CV_8U : CV_16U);
  cv::parallel_for_(cv::Range(0, height), [&](const cv::Range& rows) {
    for (int r = rows.start; r < rows.end; ++r) {
      RowRandom rng(render_.seed, frame, static_cast<uint64_t>(r), kSensorNoise);
      const float* e = irradiance.ptr<float>(r);
      for (int c = 0; c < width; ++c) {
        double value = e[c];
        if (render_.noise) {
          const double noise = std::sqrt(std::max(value, 0.0) / render_.full_well +
                                         render_.read_noise * render_.read_noise);
          value += noise * rng.normal();
        }
        value = std::clamp(value, 0.0, 1.0);
        if (render_.gamma != 1.0) value = std::pow(value, 1.0 / render_.gamma);
        const double dn = std::round(value * full);
        if (render_.bit_depth == 8)
          out.image.ptr<uint8_t>(r)[c] = static_cast<uint8_t>(dn);
        else
          out.image.ptr<uint16_t>(r)[c] = static_cast<uint16_t>(dn);
      }
    }
  });
  out.truth = groundTruth(scene, world_from_camera);
  return out;
}

std::vector<SlitCrossing> Simulator::groundTruth(const Scene& scene,
                                                 const Eigen::Isometry3d& world_from_camera) const {
  const Eigen::Isometry3d camera_from_world = world_from_camera.inverse();
  const Eigen::Vector3d camera_centre = world_from_camera.translation();
  const Eigen::Vector3d projector_centre = world_from_camera * geometry_.projectorCentre();
  const int width = geometry_.config().camera.width;
  std::vector<SlitCrossing> truth;
  for (int slit = 0; slit < geometry_.slitCount(); ++slit) {
    const auto [first, last] = geometry_.slitRows(slit);
    for (int row = first; row <= last; ++row) {
      // The light on row `row` comes from one ray of the slit, whatever the depth.
      const std::optional<double> t = geometry_.slitParamForRow(slit, row);
      if (!t) continue;
      const Eigen::Vector3d dir =
          (world_from_camera.linear() * geometry_.slitRay(slit, *t)).normalized();
      const Hit hit = scene.intersect(projector_centre, dir);
      if (!hit.valid() || hit.normal.dot(dir) >= 0) continue;
      const Eigen::Vector3d point_w = projector_centre + hit.distance * dir;
      const Eigen::Vector3d point_c = camera_from_world * point_w;
      if (point_c.z() <= 0) continue;
      const Eigen::Vector3d to_point = point_w - camera_centre;
      const double range = to_point.norm();
      const Hit seen = scene.intersect(camera_centre, to_point / range, range * (1.0 - 1e-9));
      if (seen.valid()) continue;  // hidden from the camera
      const Eigen::Vector2d uv = geometry_.project(point_c);
      if (uv.x() < 0 || uv.x() > width - 1) continue;
      SlitCrossing x;
      x.slit = slit;
      x.row = row;
      x.u = uv.x();
      x.camera_point = point_c;
      x.world_point = point_w;
      x.object = hit.object;
      x.height = point_w.z();
      truth.push_back(x);
    }
  }
  return truth;
}

void writeGroundTruthCsv(const std::string& path, const std::vector<SlitCrossing>& truth,
                         const Scene& scene) {
  std::ofstream out(path);
  if (!out) throw std::runtime_error("ground truth '" + path + "' cannot be written");
  out << "slit,row,u,x,y,z,world_x,world_y,world_z,object,object_name,height\n";
  out.precision(10);
  for (const SlitCrossing& t : truth) {
    out << t.slit << ',' << t.row << ',' << t.u << ',' << t.camera_point.x() << ','
        << t.camera_point.y() << ',' << t.camera_point.z() << ',' << t.world_point.x() << ','
        << t.world_point.y() << ',' << t.world_point.z() << ',' << t.object << ','
        << scene.objectName(t.object) << ',' << t.height << '\n';
  }
  if (!out) throw std::runtime_error("ground truth '" + path + "' could not be written completely");
}

}  // namespace multislit
