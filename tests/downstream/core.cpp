// Uses the installed core library alone, as a robot with the real sensor does: a Pipeline given an
// RDMap of a plane with one point lifted 2 px and the robot standing still finds the floor, one
// obstacle point and a decision. Exits non-zero otherwise.
#include <multislit/odometry.h>
#include <multislit/pipeline.h>
#include <multislit/sources.h>

#include <cstdio>

int main() {
  auto rdmap = pcl::make_shared<pcl::PointCloud<multislit::PointRDM>>(40, 15);
  for (std::uint32_t s = 0; s < 15; ++s)
    for (std::uint32_t j = 0; j < 40; ++j) {
      multislit::PointRDM& p = rdmap->at(j, s);
      p.u = 100.0f + 40.0f * static_cast<float>(s) + 0.5f * static_cast<float>(j);
      p.v = 200.0f + 10.0f * static_cast<float>(j);
      p.dk = 0.002f * p.u - 0.001f * p.v + 0.5f + (s == 7 && j == 20 ? 2.0f : 0.0f);
      p.slit = static_cast<std::int32_t>(s);
    }
  multislit::Pipeline pipeline;
  const multislit::Odometry still({{0, Eigen::Isometry3d::Identity()}});
  multislit::PipelineInput input;
  input.cloud = rdmap;
  input.world_from_robot = *still.at(0);
  const multislit::PipelineResult r = pipeline.process(input);
  std::printf("Pipeline: floor %s, %zu obstacle point(s), decision %s\n",
              r.floor.found ? "found" : "not found", r.floor.obstacles.size(),
              multislit::commandName(r.walker.command));
  return r.floor.found && r.floor.obstacles.size() == 1 ? 0 : 1;
}
