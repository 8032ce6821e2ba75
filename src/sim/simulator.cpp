#include "multislit/sim/simulator.h"

#include "image_noise.h"
#include "laser_integral.h"
#include "object_bounds.h"
#include "parallel_rows.h"
#include "pixel_centres.h"
#include "render_buffers.h"
#include "shader.h"

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include <chrono>
#include <cmath>
#include <fstream>
#include <limits>
#include <stdexcept>

namespace multislit {
namespace {

// The crossings of one slit of the ground truth (Simulator::groundTruth).
std::vector<SlitCrossing> slitTruth(const SensorGeometry& geometry, const Scene& scene,
                                    const Eigen::Isometry3d& world_from_camera, int slit) {
  const Eigen::Isometry3d camera_from_world = world_from_camera.inverse();
  const Eigen::Vector3d camera_centre = world_from_camera.translation();
  const Eigen::Vector3d projector_centre = world_from_camera * geometry.projectorCentre();
  const int width = geometry.config().camera.width;
  std::vector<SlitCrossing> truth;
  const auto [first, last] = geometry.slitRows(slit);
  for (int row = first; row <= last; ++row) {
    // The light on row `row` comes from one ray of the slit, whatever the depth.
    const std::optional<double> t = geometry.slitParamForRow(slit, row);
    if (!t) continue;
    const Eigen::Vector3d dir =
        (world_from_camera.linear() * geometry.slitRay(slit, *t)).normalized();
    const Hit hit = scene.intersect(projector_centre, dir);
    if (!hit.valid() || hit.normal.dot(dir) >= 0) continue;
    const Eigen::Vector3d point_w = projector_centre + hit.distance * dir;
    const Eigen::Vector3d point_c = camera_from_world * point_w;
    if (point_c.z() <= 0) continue;
    const Eigen::Vector3d to_point = point_w - camera_centre;
    const double range = to_point.norm();
    const Hit seen = scene.intersect(camera_centre, to_point / range, range * (1.0 - 1e-9));
    if (seen.valid()) continue;  // hidden from the camera
    // Through a distorting lens the crossing is given in the ideal image, whose rows these are.
    const Eigen::Vector2d uv = geometry.lens().distorted()
                                   ? geometry.lens().undistort(geometry.project(point_c))
                                   : geometry.project(point_c);
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
  return truth;
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
    : geometry_(sensor), render_(render), pool_(std::make_shared<RenderPool>()) {
  render_.validate();
  if (render_.speckle_model == SpeckleModel::Gamma && render_.speckle_contrast > 0)
    gamma_quantiles_ = gammaQuantiles(render_.speckle_contrast);
}

RenderedFrame Simulator::renderReference(const Scene& floor,
                                         const MountConfig& reference_mount) const {
  return render(floor, geometry_.robotFromCamera(reference_mount), kReferenceFrame);
}

RenderedFrame Simulator::render(const Scene& scene, const Eigen::Isometry3d& world_from_camera,
                                uint64_t frame, RenderTimes* times) const {
  RenderTimes spent;
  auto lap = [clock = std::chrono::steady_clock::now()](double& into) mutable {
    const auto now = std::chrono::steady_clock::now();
    into = std::chrono::duration<double>(now - clock).count();
    clock = now;
  };
  const double sigma = geometry_.config().projector.sheet_sigma * render_.stripe_width,
               pixel = 1.0 / geometry_.config().camera.f();
  Shader shader{scene,
                geometry_,
                render_,
                world_from_camera,
                world_from_camera.translation(),
                world_from_camera * geometry_.projectorCentre(),
                sigma};
  const double reach = sheetReach(scene, sigma, pixel);
  const std::vector<ShadowBox> casters = shadowBoxes(shader);
  // The culled method's closed-form rows and object bounds are a pinhole's: a distorting lens
  // has every pixel's ray traced.
  const RenderMethod method =
      geometry_.lens().distorted() ? RenderMethod::Exhaustive : render_.method;
  if (method == RenderMethod::Culled) shader.casters = &casters;
  const FloorAlbedo floor_albedo(
      scene.floor, method == RenderMethod::Culled ? floorInView(shader) : Eigen::AlignedBox2d());
  shader.floor_albedo = &floor_albedo;

  // 1. Every pixel centre: its surface, ambient light and where the laser sheets are.
  std::unique_ptr<RenderBuffers> buffers = pool_->take();
  const CentreSamples& centre = buffers->centre;
  traceCentres(shader, reach, pixel, method, buffers->centre);
  lap(spent.centres);
  // 2. Laser light integrated over each pixel near a sheet. With the laser off every pixel has
  // none; integrateLaser() would sample each near pixel n x n, finding no lit neighbours.
  cv::Mat& laser = buffers->laser;
  if (render_.laser_peak > 0)
    integrateLaser(shader, centre, reach, laser);
  else
    laser.create(centre.height, centre.width, CV_32F), laser.setTo(0);
  lap(spent.laser);
  // 3. Laser speckle: multiplicative, spatially correlated over a grain.
  if (render_.noise && render_.speckle_contrast > 0)
    applySpeckle(laser, centre.near, render_, frame, gamma_quantiles_, buffers->field,
                 buffers->blurred);
  // 4. Lens blur, then shot and read noise, saturation and quantization.
  RenderedFrame out;
  parallelRows(laser.rows, [&](const cv::Range& rows) {
    cv::Mat band = laser.rowRange(rows);
    cv::add(band, centre.ambient.rowRange(rows), band);
  });
  out.image = exposeSensor(laser, render_, frame, buffers->blurred);
  pool_->give(std::move(buffers));
  lap(spent.noise);
  out.truth = groundTruth(scene, world_from_camera);
  lap(spent.truth);
  if (times) *times = spent;
  return out;
}

std::vector<SlitCrossing> Simulator::groundTruth(const Scene& scene,
                                                 const Eigen::Isometry3d& world_from_camera) const {
  // Each slit's crossings on OpenCV's threads, then in slit order.
  std::vector<std::vector<SlitCrossing>> of_slit(static_cast<std::size_t>(geometry_.slitCount()));
  parallelRows(geometry_.slitCount(), [&](const cv::Range& slits) {
    for (int slit = slits.start; slit < slits.end; ++slit)
      of_slit[static_cast<std::size_t>(slit)] =
          slitTruth(geometry_, scene, world_from_camera, slit);
  });
  std::vector<SlitCrossing> truth;
  for (const std::vector<SlitCrossing>& crossings : of_slit)
    truth.insert(truth.end(), crossings.begin(), crossings.end());
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
  out.close();  // flushes: a full disk fails here
  if (!out) throw std::runtime_error("ground truth '" + path + "' could not be written completely");
}

}  // namespace multislit
