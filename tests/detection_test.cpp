// Image to obstacles end to end (paper Sec. III-B and V): simulator, extractor, floor detector,
// judged against the simulator's ground truth.
#include "multislit/extractor.h"
#include "multislit/floor_detector.h"
#include "multislit/sim/scenarios.h"
#include "multislit/sim/simulator.h"
#include "test_support.h"

#include <gtest/gtest.h>

#include <map>
#include <set>

using namespace multislit;

namespace {

const Simulator& simulator() {
  static const Simulator sim{SensorConfig{}};
  return sim;
}

const Extractor& extractor() {
  static const Extractor ex = [] {
    const Scenario s = makeScenario("reference");
    Reference ref = Reference::fromImage(
        simulator()
            .render(s.scene, simulator().geometry().robotFromCamera(s.reference_mount), 1000)
            .image);
    ref.setNominalScale(simulator().geometry().config(), s.reference_mount);
    return Extractor(ref);
  }();
  return ex;
}

struct FrameResult {
  FloorResult floor;
  std::size_t truth_on_object = 0;     // crossings on the object high enough to be seen
  std::size_t detected_on_object = 0;  // obstacle points at those crossings
  std::size_t obstacles_off_object = 0;
};

// Objects lower than this above the floor give less than the 3 sigma threshold (0.9 px).
constexpr double kVisibleHeight = 0.0035;  // [m]

FrameResult runFrame(const Scenario& s, uint64_t frame) {
  const RenderedFrame f = simulator().render(
      s.scene, s.worldFromRobot(frame) * simulator().geometry().robotFromCamera(s.mount), frame);
  const auto cloud = extractor().extract(f.image, frame, static_cast<std::uint32_t>(frame));
  FrameResult r;
  r.floor = FloorDetector().detect(cloud);
  std::map<std::pair<int, int>, const SlitCrossing*> truth;
  for (const SlitCrossing& t : f.truth) {
    truth[{t.slit, t.row}] = &t;
    r.truth_on_object += t.object > 0 && t.height >= kVisibleHeight;
  }
  for (const int i : r.floor.obstacles) {
    const PointRDM& p = (*cloud)[static_cast<std::size_t>(i)];
    const auto it = truth.find({p.slit, static_cast<int>(p.v)});
    // An obstacle point is right when its slit lies on the object on that row, or next to it
    // (a profile cut by the object's edge).
    bool near_object = false;
    for (int dv = -3; dv <= 3 && !near_object; ++dv) {
      const auto jt = truth.find({p.slit, static_cast<int>(p.v) + dv});
      near_object = jt != truth.end() && jt->second->object > 0;
    }
    if (it != truth.end() && it->second->object > 0 && it->second->height >= kVisibleHeight)
      ++r.detected_on_object;
    if (!near_object) ++r.obstacles_off_object;
  }
  return r;
}

// Walks the robot towards the object (8 mm per frame, so the test stays short; 32 mm under the
// sanitizers) and checks every frame in which the slits touch the object.
void expectFoundWhenTouched(const std::string& scenario, int frames, int min_touched) {
  Scenario s = makeScenario(scenario);
  s.step = 0.008 * frameCount(1, 4);
  frames /= frameCount(1, 4);
  min_touched /= frameCount(1, 4);
  int touched = 0;
  std::size_t wrong = 0, valid = 0;
  for (int k = 0; k < frames; ++k) {
    const FrameResult r = runFrame(s, static_cast<uint64_t>(k));
    ASSERT_TRUE(r.floor.found) << scenario << " frame " << k;
    wrong += r.obstacles_off_object;
    valid += r.floor.valid_points;
    if (r.truth_on_object == 0) continue;
    ++touched;
    EXPECT_GE(r.detected_on_object, 1u) << scenario << " frame " << k << ": " << r.truth_on_object
                                        << " crossings on the object, none detected";
  }
  EXPECT_GE(touched, min_touched) << scenario;
  EXPECT_LE(static_cast<double>(wrong), 0.003 * static_cast<double>(valid)) << scenario;
  std::printf(
      "%s: touched in %d of %d frames, detected in all; obstacle points away from it: "
      "%zu of %zu\n",
      scenario.c_str(), touched, frames, wrong, valid);
}

}  // namespace

TEST(Detection, LanCableIsFoundInEveryFrameTheSlitsTouchIt) {
  // The 7 mm cable lies 0.45 m ahead: it crosses the field of view within 45 frames of 8 mm.
  expectFoundWhenTouched("cable", 48, 20);
}

TEST(Detection, PingPongBallIsFoundInEveryFrameTheSlitsTouchIt) {
  expectFoundWhenTouched("ball", 24, 10);
}

TEST(Detection, EmptyFloorsAtAllSevenPosesInventNothing) {
  for (int cond = 0; cond <= 6; ++cond) {
    const Scenario s = makeScenario(cond == 0 ? "reference" : "cond" + std::to_string(cond));
    std::size_t obstacles = 0, valid = 0;
    for (uint64_t k = 0; k < static_cast<uint64_t>(frameCount(4, 1)); ++k) {
      const FrameResult r = runFrame(s, 100 + k);
      ASSERT_TRUE(r.floor.found) << "condition " << cond << " frame " << k;
      EXPECT_LT(r.floor.residual_std, 0.3) << "condition " << cond;
      obstacles += r.floor.obstacles.size();
      valid += r.floor.valid_points;
    }
    // The paper's 3 sigma rule alone lets 0.27% of a Gaussian floor through.
    EXPECT_LE(static_cast<double>(obstacles), 0.003 * static_cast<double>(valid))
        << "condition " << cond;
    std::printf("condition %d: %zu of %zu points called obstacle\n", cond, obstacles, valid);
  }
}

TEST(Detection, DarkFrameIsNotAFloor) {
  const auto cloud = extractor().extract(cv::Mat(964, 1296, CV_8U, cv::Scalar(25)), 0, 0);
  EXPECT_FALSE(FloorDetector().detect(cloud).found);
}
