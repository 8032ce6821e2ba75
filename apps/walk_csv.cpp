// obstacles.csv of multislit walk: one row per frame.
#include "walk_csv.h"

#include "multislit/units.h"

#include <cmath>
#include <cstdio>

namespace multislit::apps {

void writeWalkCsvHeader(std::ostream& csv) {
  csv << "frame,time_s,x_m,y_m,yaw_deg,decision,reason,motion,floor_found,valid_points,"
         "floor_std_px,obstacle_points,obstacles,nearest_m,map_occupied,map_voxels,map_bytes,"
         "ball_lit,ball_detected,cable_lit,cable_detected,footstep,footstep_clearance_m,sweep_mm,"
         "map_pending\n";
}

void writeWalkCsvLine(std::ostream& csv, const WalkFrame& f, const OccupancyMap& map, double fps) {
  std::size_t lit[2] = {0, 0}, detected[2] = {0, 0};
  for (const ObjectView& o : f.objects) {
    const int k = o.object.name == "pingpong_ball" ? 0 : o.object.name == "lan_cable" ? 1 : -1;
    if (k < 0) continue;
    lit[k] = o.lit_any;
    detected[k] = o.detected;
  }
  char s[512];
  std::snprintf(
      s, sizeof s, "%llu,%.3f,%.4f,%.4f,%.2f,%s,%s,%s,%d,%zu,%.4f,%zu,%zu,%.4f,%zu,%zu,%zu,",
      static_cast<unsigned long long>(f.frame), static_cast<double>(f.frame) / fps, f.body.x,
      f.body.y, f.body.yaw / kDeg, commandName(f.walker.command), reasonName(f.walker.reason),
      commandName(f.motion), f.floor.found ? 1 : 0, f.floor.valid_points, f.floor.residual_std,
      f.obstacles.pointCount(), f.obstacles.obstacles.size(),
      f.obstacles.obstacles.empty() ? NAN : f.obstacles.obstacles[0].distance, map.occupiedCount(),
      map.leafCount(), map.memoryUsage());
  csv << s << lit[0] << ',' << detected[0] << ',' << lit[1] << ',' << detected[1] << ',';
  if (f.footstep)
    csv << footName(f.footstep->foot) << ',' << f.footstep_clearance;
  else
    csv << ',';
  std::snprintf(s, sizeof s, ",%.2f,%zu\n", 1e3 * f.map.sweep, f.map.pending_voxels);
  csv << s;
}

}  // namespace multislit::apps
