#include "multislit/sim/scenarios.h"

#include <stdexcept>

namespace multislit {

MountConfig tableIPose(int condition) {
  MountConfig m;  // the reference: theta 66 deg, phi 0 deg, h 445 mm
  switch (condition) {
    case 0:
      break;
    case 1:
      m.tilt = 61;
      break;
    case 2:
      m.tilt = 71;
      break;
    case 3:
      m.roll = -5;
      break;
    case 4:
      m.roll = 5;
      break;
    case 5:
      m.height = 0.395;
      break;
    case 6:
      m.height = 0.495;
      break;
    default:
      throw std::out_of_range("Table I has conditions 0 (reference) to 6");
  }
  return m;
}

Eigen::Isometry3d Scenario::worldFromRobot(uint64_t frame) const {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.translation().x() = step * static_cast<double>(frame);
  return t;
}

std::vector<std::string> scenarioNames() {
  return {"reference", "cond1", "cond2", "cond3", "cond4", "cond5",
          "cond6",     "fig8",  "cable", "ball",  "floor"};
}

Scenario makeWallScenario(double depth) {
  if (!(depth > 0.1 && depth < 5)) throw std::invalid_argument("wall depth must be in (0.1, 5) m");
  Scenario s;
  s.name = "wall";
  s.description = "a wall " + std::to_string(depth) + " m in front of the level sensor";
  s.reference_mount = tableIPose(0);
  s.mount = s.reference_mount;
  s.mount.tilt = 0;
  s.mount.roll = 0;
  const double face = s.mount.forward + depth, thickness = 0.1;
  s.scene.objects.push_back(
      SceneObject::box("wall", Eigen::Vector3d(face + thickness / 2, 0, s.mount.height),
                       Eigen::Vector3d(thickness, 4.0, 2 * s.mount.height - 0.01)));
  s.scene.objects.back().albedo = 0.6;
  return s;
}

Scenario makeScenario(const std::string& name) {
  if (name == "wall") return makeWallScenario(0.5);
  Scenario s;
  s.name = name;
  s.reference_mount = tableIPose(0);
  s.mount = s.reference_mount;
  if (name == "reference") {
    s.description = "bare floor at the reference pose of Table I";
  } else if (name.size() == 5 && name.rfind("cond", 0) == 0 && name[4] >= '1' && name[4] <= '6') {
    s.mount = tableIPose(name[4] - '0');
    s.description = "bare floor at Table I condition " + name.substr(4);
  } else if (name == "fig8") {
    s.description =
        "Fig. 8: a 70 mm tennis ball and a 185 x 455 x 30 mm box, seen from 50 mm higher";
    s.mount.height += 0.050;
    s.scene.objects.push_back(
        SceneObject::sphere("tennis_ball", Eigen::Vector3d(0.20, -0.07, 0.035), 0.035));
    s.scene.objects.back().albedo = 0.6;
    s.scene.objects.push_back(SceneObject::box("box", Eigen::Vector3d(0.26, 0.30, 0.015),
                                               Eigen::Vector3d(0.185, 0.455, 0.030)));
    s.scene.objects.back().albedo = 0.5;
  } else if (name == "cable") {
    s.description = "a 7 mm LAN cable lying across the path, walking towards it at 1 mm/frame";
    s.step = 0.001;
    s.scene.objects.push_back(SceneObject::cylinder("lan_cable",
                                                    Eigen::Vector3d(0.45, -0.6, 0.0035),
                                                    Eigen::Vector3d(0.45, 0.6, 0.0035), 0.0035));
    s.scene.objects.back().albedo = 0.35;
  } else if (name == "ball") {
    s.description = "a 40 mm ping-pong ball in front of the foot";
    s.scene.objects.push_back(
        SceneObject::sphere("pingpong_ball", Eigen::Vector3d(0.18, 0.02, 0.020), 0.020));
    s.scene.objects.back().albedo = 0.85;
  } else if (name == "floor") {
    s.description = "walking over a bare floor at 1 mm/frame";
    s.step = 0.001;
  } else {
    std::string known;
    for (const std::string& n : scenarioNames()) known += (known.empty() ? "" : ", ") + n;
    throw std::invalid_argument("unknown scenario '" + name + "'; known: " + known);
  }
  return s;
}

}  // namespace multislit
