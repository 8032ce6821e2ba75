// A camera whose lens distorts, against the pinhole camera, at the seven poses of Table I: with
// its coefficients the floor is a plane in the RDMap again (residual std and false obstacle
// points as the pinhole's); without them it is not, and calibrate's slit bend says so.
#include "multislit/extractor.h"
#include "multislit/floor_detector.h"
#include "multislit/plane_model.h"
#include "multislit/sim/rdmap_synth.h"
#include "multislit/sim/scenarios.h"
#include "multislit/sim/simulator.h"
#include "multislit/slit_bend.h"
#include "test_support.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numeric>

using namespace multislit;

namespace {

// A short lens's barrel distortion with tangential terms: the corners move by 12 px. (A stronger
// barrel squeezes the image's edges into fewer pixels, and the noise of a centre there grows in
// ideal pixels by as much: a camera with a worse view, not an error of the undistortion.)
SensorConfig distortedSensor() {
  SensorConfig s;
  s.camera.distortion.k1 = -0.03;
  s.camera.distortion.k2 = 0.005;
  s.camera.distortion.p1 = 5e-4;
  s.camera.distortion.p2 = -3e-4;
  return s;
}

// What one RDMap of the bare floor gives: eq. (2)'s residual std over all points (table1's
// measure) and the points the floor detector puts off the floor (all false on a bare floor).
// And the points' rms height above the floor in the robot frame (the metric step) [m].
struct FloorFigures {
  double residual_std = 0, height_rms = 0;
  std::size_t points = 0, false_points = 0;
};

FloorFigures floorFigures(const Extractor& extractor, const cv::Mat& image,
                          const Eigen::Isometry3d& robot_from_camera) {
  auto cloud = pcl::make_shared<pcl::PointCloud<PointRDM>>();
  extractor.extract(image, *cloud);
  pcl::Indices all(cloud->size());
  std::iota(all.begin(), all.end(), 0);
  const RDMapPlaneFit fit = fitRDMapPlane(*cloud, all);
  const FloorResult floor = FloorDetector().detect(cloud);
  double ss = 0;
  std::size_t n = 0;
  for (const PointRDM& p : cloud->points) {
    if (!std::isfinite(p.z)) continue;
    const double z = (robot_from_camera * Eigen::Vector3d(p.x, p.y, p.z)).z();
    ss += z * z, ++n;
  }
  return {fit.residual_std, std::sqrt(ss / static_cast<double>(std::max<std::size_t>(n, 1))),
          fit.points, floor.obstacles.size()};
}

// The floor images of the Table I poses, one per pose.
std::vector<cv::Mat> tableIImages(const Simulator& sim) {
  const Scene floor = makeScenario("reference").scene;
  std::vector<cv::Mat> images;
  for (int cond = 0; cond <= 6; ++cond) {
    const Eigen::Isometry3d pose = sim.geometry().robotFromCamera(tableIPose(cond));
    images.push_back(sim.render(floor, pose, 100 + static_cast<uint64_t>(cond)).image);
  }
  return images;
}

struct Cameras {
  SensorConfig pinhole, distorted;
  std::vector<cv::Mat> pinhole_images, distorted_images;
  Reference pinhole_ref, with_lens, without_lens;
};

const Cameras& cameras() {
  static const Cameras c = [] {
    Cameras out;
    out.distorted = distortedSensor();
    const MountConfig mount = makeScenario("reference").reference_mount;
    out.pinhole_ref = renderFloorReference(out.pinhole, mount);
    out.with_lens = renderFloorReference(out.distorted, mount);
    // The same reference image read as a pinhole's: the coefficients left out.
    out.without_lens = out.with_lens;
    out.without_lens.setNominalScale(out.pinhole, mount);
    out.pinhole_images = tableIImages(Simulator(out.pinhole));
    out.distorted_images = tableIImages(Simulator(out.distorted));
    return out;
  }();
  return c;
}

}  // namespace

TEST(Distortion, TheLensIsStrong) {
  const double shift = distortedSensor().camera.lens().largestShift(1296, 964);
  std::printf("largest shift of a pixel: %.1f px\n", shift);
  EXPECT_GE(shift, 5.0);
}

// With its coefficients the distorted camera's floor is the pinhole's: residual std and false
// points within 10 % at every pose. Without them the floor bends in the RDMap wherever the pose
// differs from the reference's (at the reference pose the relative disparity cancels the lens):
// the residual std grows up to twice the pinhole's and the floor's points leave the floor in
// the metric step.
TEST(Distortion, TableIPosesWithAndWithoutTheCoefficients) {
  const Cameras& c = cameras();
  const Extractor pinhole(c.pinhole_ref), with_lens(c.with_lens), without_lens(c.without_lens);
  double worst_std = 0, worst_height = 0, mean_std = 0;
  for (int cond = 0; cond <= 6; ++cond) {
    const std::size_t k = static_cast<std::size_t>(cond);
    const Eigen::Isometry3d robot = SensorGeometry(c.pinhole).robotFromCamera(tableIPose(cond));
    const FloorFigures p = floorFigures(pinhole, c.pinhole_images[k], robot);
    const FloorFigures w = floorFigures(with_lens, c.distorted_images[k], robot);
    const FloorFigures wo = floorFigures(without_lens, c.distorted_images[k], robot);
    std::printf(
        "cond %d: residual std pinhole %.4f, with coefficients %.4f, without %.4f px; false "
        "points %zu, %zu, %zu of %zu, %zu, %zu; height rms %.2f, %.2f, %.2f mm\n",
        cond, p.residual_std, w.residual_std, wo.residual_std, p.false_points, w.false_points,
        wo.false_points, p.points, w.points, wo.points, 1e3 * p.height_rms, 1e3 * w.height_rms,
        1e3 * wo.height_rms);
    SCOPED_TRACE("condition " + std::to_string(cond));
    EXPECT_NEAR(w.residual_std, p.residual_std, 0.1 * p.residual_std);
    EXPECT_LE(static_cast<double>(w.false_points),
              1.1 * static_cast<double>(p.false_points) + 0.001 * static_cast<double>(p.points));
    EXPECT_GE(static_cast<double>(w.points), 0.98 * static_cast<double>(p.points));
    EXPECT_LE(w.height_rms, 1.1 * p.height_rms);
    worst_std = std::max(worst_std, wo.residual_std / p.residual_std);
    worst_height = std::max(worst_height, wo.height_rms / p.height_rms);
    mean_std += wo.residual_std / p.residual_std / 7;
  }
  EXPECT_GT(worst_std, 1.6);
  EXPECT_GT(mean_std, 1.2);
  EXPECT_GT(worst_height, 2.0);
}

// calibrate's hint: the slits of the reference bend away from the projector model's only when
// the coefficients are missing.
TEST(Distortion, SlitBendFlagsTheMissingCoefficients) {
  const Cameras& c = cameras();
  const MountConfig mount = makeScenario("reference").reference_mount;
  const double pinhole = slitBend(c.pinhole_ref, c.pinhole, mount);
  const double with_lens = slitBend(c.with_lens, c.distorted, mount);
  const double without_lens = slitBend(c.without_lens, c.pinhole, mount);
  std::printf("slit bend: pinhole %.3f px, with coefficients %.3f px, without %.3f px\n", pinhole,
              with_lens, without_lens);
  EXPECT_LT(pinhole, kMaxSlitBend);
  EXPECT_LT(with_lens, kMaxSlitBend);
  EXPECT_GT(without_lens, kMaxSlitBend);
}

// The metric scale from walls at known depths through the distorting lens: the walls' slits are
// undistorted as the reference's are, so the scale is the pinhole's and the floor's depth as
// accurate (the wall test of extractor_test, with the lens).
TEST(Distortion, WallCalibrationThroughTheLens) {
  const Cameras& c = cameras();
  const Simulator sim(c.distorted);
  const std::vector<double> depths = {0.35, 0.5, 0.7};
  std::vector<cv::Mat> walls;
  for (double d : depths) {
    const Scenario wall = makeWallScenario(d);
    walls.push_back(sim.render(wall.scene,
                               wall.worldFromRobot(0) * sim.geometry().robotFromCamera(wall.mount),
                               0)
                        .image);
  }
  Reference ref = c.with_lens;
  const double rms = ref.calibrateWithPlanes(walls, depths, c.distorted.camera);
  const double fb = c.distorted.camera.f() * c.distorted.projector.baseline;
  const Extractor extractor(ref);
  const Eigen::Isometry3d robot = SensorGeometry(c.distorted).robotFromCamera(tableIPose(0));
  const FloorFigures w = floorFigures(extractor, c.distorted_images[0], robot);
  std::printf(
      "wall calibration through the lens: f*b %.4f (true %.4f) px m, fit rms %.3f px, "
      "floor height rms %.2f mm over %zu points\n",
      ref.scale.disparity_constant, fb, rms, 1e3 * w.height_rms, w.points);
  EXPECT_EQ(ref.scale.source, "planes");
  EXPECT_NEAR(ref.scale.disparity_constant, fb, 0.005 * fb);
  EXPECT_LT(rms, 0.3);
  EXPECT_LT(w.height_rms, 0.001);  // the pinhole's nominal scale gives 0.24 mm at this pose
  EXPECT_GE(w.points, 4300u);
}
