// The Pipeline on frames of any source: a simulated walk recorded as a sequence (PNG frames,
// frames.csv, odometry.csv, calibration.yaml) and replayed through the sequence source, the
// odometry file and a Pipeline gives the same occupied voxels and the same decisions as the walk.
#include "multislit/pipeline.h"
#include "multislit/extractor.h"
#include "multislit/odometry.h"
#include "multislit/sim/walk.h"
#include "multislit/sources.h"
#include "test_support.h"

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <set>
#include <tuple>

using namespace multislit;

namespace {

using KeySet = std::set<std::tuple<unsigned, unsigned, unsigned>>;

KeySet occupiedKeys(const OccupancyMap& map) {
  KeySet keys;
  const octomap::OcTree& tree = map.tree();
  for (auto it = tree.begin_leafs(), end = tree.end_leafs(); it != end; ++it)
    if (tree.isNodeOccupied(*it)) {
      const octomap::OcTreeKey k = it.getKey();
      keys.emplace(k[0], k[1], k[2]);
    }
  return keys;
}

struct WalkRun {
  KeySet occupied;
  std::vector<Command> decisions;
};

/// The walk with the ball thrown in at frame 6, every frame written as a recording to `dir`.
WalkRun walkAndRecord(const std::filesystem::path& dir, int frames) {
  WalkConfig config;
  config.scene.cable = false;
  config.scene.ball_frame = 6;
  config.scene.ball_roll_frame = 1000;
  WalkSimulation walk(config);
  std::filesystem::create_directories(dir);
  walk.reference().save((dir / "calibration.yaml").string());
  std::ofstream index(dir / "frames.csv");
  index << "frame,file,stamp_us\n";
  std::vector<OdometrySample> poses;
  WalkRun run;
  for (int k = 0; k < frames; ++k) {
    const WalkFrame f = walk.step();
    char name[32];
    std::snprintf(name, sizeof name, "frame_%06d.png", k);
    cv::imwrite((dir / name).string(), f.image);
    index << k << ',' << name << ',' << f.stamp_us << '\n';
    poses.push_back({f.stamp_us, f.world_from_torso});
    run.decisions.push_back(f.walker.command);
  }
  saveOdometry((dir / "odometry.csv").string(), poses);
  run.occupied = occupiedKeys(walk.map());
  return run;
}

/// What a user with the recording does: sequence source, calibration, odometry, Pipeline.
WalkRun replay(const std::filesystem::path& dir) {
  ImageSequenceConfig source_config;
  source_config.folder = dir.string();
  ImageSequenceSource source(source_config);
  const Extractor extractor(Reference::load((dir / "calibration.yaml").string()));
  const Odometry odometry = Odometry::load((dir / "odometry.csv").string());
  Pipeline pipeline;  // the paper's sensor on its nominal mount, as in the walk
  WalkRun run;
  source.start();
  while (const std::optional<Frame> frame = source.next(std::chrono::milliseconds(1000))) {
    PipelineInput in;
    in.cloud =
        extractor.extract(frame->image, frame->stamp_us, static_cast<std::uint32_t>(frame->seq));
    const auto pose = odometry.at(frame->stamp_us);
    EXPECT_TRUE(pose) << "frame " << frame->seq;
    if (!pose) continue;
    in.world_from_robot = *pose;
    run.decisions.push_back(pipeline.process(in).walker.command);
  }
  source.stop();
  run.occupied = occupiedKeys(pipeline.map());
  return run;
}

}  // namespace

TEST(Pipeline, ReplayedRecordingOfAWalkGivesTheWalksOccupiedVoxels) {
  const int frames = frameCount(40, 14);
  const auto dir = std::filesystem::path(tempPath("multislit_pipeline_replay"));
  std::filesystem::remove_all(dir);
  const WalkRun walked = walkAndRecord(dir, frames);
  const WalkRun replayed = replay(dir);
  ASSERT_EQ(replayed.decisions.size(), static_cast<std::size_t>(frames));
  EXPECT_GT(walked.occupied.size(), 3u);  // the ball
  EXPECT_EQ(replayed.occupied, walked.occupied);
  EXPECT_EQ(replayed.decisions, walked.decisions);
  const auto stops = std::count(walked.decisions.begin(), walked.decisions.end(), Command::Stop);
  EXPECT_GT(stops, 0);  // the ball appeared suddenly just in front of the foot
  std::printf("%d frames: %zu occupied voxels in both, %ld stops\n", frames, walked.occupied.size(),
              static_cast<long>(stops));
}

TEST(Pipeline, ConfigIsValidatedNamingTheStage) {
  PipelineConfig config;
  config.walker.stop_frames = -1;
  try {
    Pipeline pipeline(config);
    FAIL() << "an invalid walker config was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("stop_frames"), std::string::npos) << e.what();
  }
}

// A corrupt calibration put points at +-inf, and `map` decided "walk, path clear" on them: a
// frame with an infinite or far point, or a pose that is not finite, is dropped with a reason;
// the walker stops as for no floor and the map learns nothing.
TEST(Pipeline, FramesWithInfinitePointsOrPosesAreDroppedAndTheWalkerStops) {
  WalkConfig walk_config;
  walk_config.render = false;
  WalkSimulation walk(walk_config);
  const WalkFrame f = walk.step();
  const auto input = [](pcl::PointCloud<PointRDM>::ConstPtr cloud, const Eigen::Isometry3d& pose) {
    PipelineInput in;
    in.cloud = std::move(cloud);
    in.world_from_robot = pose;
    return in;
  };
  Pipeline pipeline(walk_config.pipeline);
  const PipelineResult good = pipeline.process(input(f.cloud, f.world_from_torso));
  ASSERT_TRUE(good.dropped.empty()) << good.dropped;
  ASSERT_TRUE(good.floor.found);
  const std::size_t voxels = pipeline.map().leafCount();

  auto bad = pcl::make_shared<pcl::PointCloud<PointRDM>>(*f.cloud);
  std::size_t k = 0;
  while (k < bad->size() && !hasXYZ((*bad)[k])) ++k;
  ASSERT_LT(k, bad->size());
  (*bad)[k].x = std::numeric_limits<float>::infinity();
  const PipelineResult r = pipeline.process(input(bad, f.world_from_torso));
  EXPECT_NE(r.dropped.find("point " + std::to_string(k) + " is infinite"), std::string::npos)
      << r.dropped;
  EXPECT_FALSE(r.floor.found);
  EXPECT_EQ(r.walker.command, Command::Stop);
  EXPECT_EQ(r.walker.reason, Reason::NoFloor);
  EXPECT_EQ(pipeline.map().leafCount(), voxels);

  (*bad)[k].x = 5000.0f;  // finite, but no sensor of this kind sees 5 km
  EXPECT_NE(pipeline.process(input(bad, f.world_from_torso)).dropped.find("farther than 1000 m"),
            std::string::npos);
  Eigen::Isometry3d far = f.world_from_torso;
  far.translation().x() = 1e12;
  const PipelineResult lost = pipeline.process(input(f.cloud, far));
  EXPECT_NE(lost.dropped.find("the robot's pose"), std::string::npos) << lost.dropped;
  EXPECT_EQ(lost.walker.command, Command::Stop);
}
