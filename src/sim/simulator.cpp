#include "multislit/sim/simulator.h"

#include "sim/image_noise.h"
#include "sim/parallel_rows.h"

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include <cmath>
#include <fstream>
#include <limits>
#include <stdexcept>

namespace multislit {
namespace {

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

// The samples of the pixel centres, row-major, with the light that does not depend on the sheets.
struct CentreSamples {
  int width = 0, height = 0;
  std::vector<Shader::Sample> samples;
  cv::Mat ambient;  // ambient light and glare per pixel, CV_32F [FS]
  cv::Mat near;     // CV_8U: 1 where a sheet may light the pixel

  const Shader::Sample& at(int r, int c) const {
    return samples[static_cast<std::size_t>(r) * width + c];
  }
};

// How far from a sheet's centre [rad] light is traced: beyond 4.5 sigma a sheet adds < 4e-5 of
// its peak, for the widest sheet on any surface.
double sheetReach(const Scene& scene, double sigma, double pixel) {
  double widest = scene.stripeWidth(0);
  for (std::size_t k = 0; k < scene.objects.size(); ++k)
    widest = std::max(widest, scene.stripeWidth(static_cast<int>(k) + 1));
  return 4.5 * sigma * widest + 2 * pixel;
}

// Every pixel centre: its surface, ambient light and where the laser sheets are.
CentreSamples traceCentres(const Shader& shader, double reach, double pixel) {
  const SensorGeometry& geometry = shader.geometry;
  const int width = geometry.config().camera.width, height = geometry.config().camera.height;
  CentreSamples centre{width, height,
                       std::vector<Shader::Sample>(static_cast<std::size_t>(width) * height),
                       cv::Mat(height, width, CV_32F), cv::Mat(height, width, CV_8U)};
  parallelRows(height, [&](const cv::Range& rows) {
    for (int r = rows.start; r < rows.end; ++r) {
      for (int c = 0; c < width; ++c) {
        const Shader::Sample& s = centre.samples[static_cast<std::size_t>(r) * width + c] =
            shader.trace(c, r, reach);
        centre.ambient.ptr<float>(r)[c] =
            static_cast<float>(shader.render.ambient * (s.albedo + s.glare));
        centre.near.ptr<uchar>(r)[c] =
            std::abs(s.offset) < reach && std::abs(s.t) < geometry.slitTMax() + 2 * pixel;
      }
    }
  });
  // Catch pixels split by an edge.
  cv::dilate(centre.near, centre.near, cv::Mat::ones(3, 3, CV_8U));
  return centre;
}

// Whether the sheet's offset is linear over pixel (r, c): the same surface and slit, lit, not at
// the slit's end (|t| <= t_inner) on the pixel and its four neighbours, and no curvature.
inline bool offsetIsLinear(const CentreSamples& centre, int r, int c, double t_inner,
                           double sigma) {
  if (r < 1 || c < 1 || r >= centre.height - 1 || c >= centre.width - 1) return false;
  const Shader::Sample& m = centre.at(r, c);
  for (const Shader::Sample* q :
       {&centre.at(r, c - 1), &centre.at(r, c + 1), &centre.at(r - 1, c), &centre.at(r + 1, c), &m})
    if (q->object != m.object || q->slit != m.slit || !(q->radiance > 0) ||
        std::abs(q->t) > t_inner)
      return false;
  return std::abs(centre.at(r, c - 1).offset + centre.at(r, c + 1).offset - 2 * m.offset) <
             0.02 * sigma &&
         std::abs(centre.at(r - 1, c).offset + centre.at(r + 1, c).offset - 2 * m.offset) <
             0.02 * sigma;
}

// Laser light integrated over each pixel near a sheet: exactly where the sheet's offset is
// linear over the pixel (same surface and slit, lit, not at the slit's end), else sampled at
// n x n sub-pixel positions (edges, shadows, slit ends).
cv::Mat integrateLaser(const Shader& shader, const CentreSamples& centre, double reach,
                       double pixel) {
  const int n = shader.render.supersample, width = centre.width, height = centre.height;
  const double sigma = shader.sigma, t_inner = shader.geometry.slitTMax() - 3 * pixel;
  cv::Mat laser(height, width, CV_32F, cv::Scalar(0));
  parallelRows(height, [&](const cv::Range& rows) {
    for (int r = rows.start; r < rows.end; ++r) {
      for (int c = 0; c < width; ++c) {
        if (!centre.near.ptr<uchar>(r)[c]) continue;
        const Shader::Sample& m = centre.at(r, c);
        double value = 0;
        if (offsetIsLinear(centre, r, c, t_inner, sigma)) {
          const double gu = 0.5 * (centre.at(r, c + 1).offset - centre.at(r, c - 1).offset);
          const double gv = 0.5 * (centre.at(r + 1, c).offset - centre.at(r - 1, c).offset);
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
  return laser;
}

}  // namespace

void RenderConfig::validate() const {
  auto require = [](bool ok, const char* field, const char* rule) {
    if (!ok) throw std::invalid_argument(std::string("render config: ") + field + " " + rule);
  };
  require(laser_peak >= 0 && laser_peak <= 100, "laser_peak", "must be in [0, 100] FS");
  require(ambient >= 0 && ambient <= 100, "ambient", "must be in [0, 100] FS");
  if (speckle_model == SpeckleModel::Gaussian)
    require(speckle_contrast >= 0 && speckle_contrast < 1, "speckle_contrast",
            "must be in [0, 1) (Gaussian speckle)");
  else
    require(speckle_contrast >= 0 && speckle_contrast <= 1, "speckle_contrast",
            "must be in [0, 1] (gamma speckle)");
  require(speckle_grain >= 0.3 && speckle_grain <= 10, "speckle_grain", "must be in [0.3, 10] px");
  require(blur_sigma >= 0 && blur_sigma <= 10, "blur_sigma", "must be in [0, 10] px");
  require(full_well >= 100 && full_well <= 1e15, "full_well", "must be in [100, 1e15] e-");
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
  const double sigma = geometry_.config().projector.sheet_sigma * render_.stripe_width,
               pixel = 1.0 / geometry_.config().camera.f();
  const Shader shader{scene,
                      geometry_,
                      render_,
                      world_from_camera,
                      world_from_camera.translation(),
                      world_from_camera * geometry_.projectorCentre(),
                      sigma};
  const double reach = sheetReach(scene, sigma, pixel);

  // 1. Every pixel centre: its surface, ambient light and where the laser sheets are.
  const CentreSamples centre = traceCentres(shader, reach, pixel);
  // 2. Laser light integrated over each pixel near a sheet.
  cv::Mat laser = integrateLaser(shader, centre, reach, pixel);
  // 3. Laser speckle: multiplicative, spatially correlated over a grain.
  if (render_.noise && render_.speckle_contrast > 0)
    applySpeckle(laser, render_, frame, gamma_quantiles_);
  // 4. Lens blur, then shot and read noise, saturation and quantization.
  RenderedFrame out;
  out.image = exposeSensor(centre.ambient + laser, render_, frame);
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
