// A scene's YAML file (Scene::load, Scene::save) and the names of its shapes and floor textures.
#include "multislit/sim/scene.h"

#include "yaml_io.h"

#include <stdexcept>
#include <string>

namespace multislit {
namespace {

Eigen::Vector3d readVec3(const cv::FileNode& node, const char* key,
                         const Eigen::Vector3d& fallback) {
  const cv::FileNode n = node[key];
  if (n.empty()) return fallback;
  const auto number = [&](int i) {
    if (!n[i].isInt() && !n[i].isReal())
      throw std::invalid_argument(std::string("field '") + key + "' must be a list of 3 numbers");
    return static_cast<double>(n[i]);
  };
  if (!n.isSeq() || n.size() != 3)
    throw std::invalid_argument(std::string("field '") + key + "' must be a list of 3 numbers");
  return Eigen::Vector3d(number(0), number(1), number(2));
}

// The keys an object of each type may have (a key of another type would be ignored).
void checkObjectKeys(const cv::FileNode& n, const std::string& where, const std::string& type) {
  if (type == "sphere")
    checkKeys(n, where, {"type", "name", "centre", "radius", "albedo", "stripe_width"});
  else if (type == "cylinder")
    checkKeys(n, where,
              {"type", "name", "axis_start", "axis_end", "radius", "albedo", "stripe_width"});
  else if (type == "box")
    checkKeys(n, where, {"type", "name", "centre", "size", "yaw", "albedo", "stripe_width"});
}

void writeVec3(cv::FileStorage& fs, const char* key, const Eigen::Vector3d& v) {
  fs << key << "[:" << v.x() << v.y() << v.z() << "]";
}

const char* shapeName(ShapeType t) {
  switch (t) {
    case ShapeType::Sphere:
      return "sphere";
    case ShapeType::Cylinder:
      return "cylinder";
    case ShapeType::Box:
      return "box";
  }
  return "?";
}

}  // namespace

const char* floorTextureName(FloorTexture texture) {
  switch (texture) {
    case FloorTexture::Wood:
      return "wood";
    case FloorTexture::Tiles:
      return "tiles";
    case FloorTexture::Carpet:
      return "carpet";
  }
  return "?";
}

FloorTexture floorTextureFromName(const std::string& name) {
  for (FloorTexture t : {FloorTexture::Wood, FloorTexture::Tiles, FloorTexture::Carpet})
    if (name == floorTextureName(t)) return t;
  throw std::invalid_argument("floor texture must be wood, tiles or carpet, not '" + name + "'");
}

Scene Scene::load(const std::string& path) {
  cv::FileStorage fs = openYamlForRead(path, "scene");
  Scene scene;
  try {
    checkKeys(fs.root(), "", {"floor", "objects"});
    const cv::FileNode f = fs["floor"];
    checkKeys(f, "floor",
              {"texture", "albedo", "texture_amplitude", "texture_scale", "texture_seed",
               "grout_width", "grout_albedo", "laser_albedo", "gloss", "stripe_width"});
    std::string texture = floorTextureName(scene.floor.texture);
    readField(f, "texture", texture);
    scene.floor.texture = floorTextureFromName(texture);
    readField(f, "albedo", scene.floor.albedo);
    readField(f, "texture_amplitude", scene.floor.texture_amplitude);
    readField(f, "texture_scale", scene.floor.texture_scale);
    readField(f, "texture_seed", scene.floor.texture_seed);
    readField(f, "grout_width", scene.floor.grout_width);
    readField(f, "grout_albedo", scene.floor.grout_albedo);
    readField(f, "laser_albedo", scene.floor.laser_albedo);
    readField(f, "gloss", scene.floor.gloss);
    readField(f, "stripe_width", scene.floor.stripe_width);
    const cv::FileNode list = fs["objects"];
    if (!list.empty() && !list.isSeq()) throw std::invalid_argument("'objects' must be a list");
    if (list.size() > kMaxObjects)
      throw std::invalid_argument(std::to_string(list.size()) +
                                  " objects, more than the limit of " +
                                  std::to_string(kMaxObjects));
    for (const cv::FileNode& n : list) {
      const std::string where = "objects[" + std::to_string(scene.objects.size()) + "]";
      if (!n.isMap()) throw std::invalid_argument("'" + where + "' must be a map of keys");
      std::string type;
      readField(n, "type", type);
      checkObjectKeys(n, where, type);
      SceneObject o;
      readField(n, "name", o.name);
      if (o.name.empty()) o.name = type + std::to_string(scene.objects.size());
      if (type == "sphere") {
        o = SceneObject::sphere(o.name, readVec3(n, "centre", o.centre), 0.0);
      } else if (type == "cylinder") {
        o = SceneObject::cylinder(o.name, readVec3(n, "axis_start", o.axis_start),
                                  readVec3(n, "axis_end", o.axis_end), 0.0);
      } else if (type == "box") {
        o = SceneObject::box(o.name, readVec3(n, "centre", o.centre), readVec3(n, "size", o.size));
        readField(n, "yaw", o.yaw);
      } else {
        throw std::invalid_argument("object '" + o.name +
                                    "': type must be sphere, cylinder or box, not '" + type + "'");
      }
      readField(n, "radius", o.radius);
      readField(n, "albedo", o.albedo);
      readField(n, "stripe_width", o.stripe_width);
      scene.objects.push_back(o);
    }
    scene.validate();
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(path + ": " + e.what());
  }
  return scene;
}

void Scene::save(const std::string& path) const {
  cv::FileStorage fs = openYamlForWrite(path, "scene");
  fs << "floor"
     << "{";
  fs << "texture" << floorTextureName(floor.texture);
  fs << "albedo" << floor.albedo << "texture_amplitude" << floor.texture_amplitude;
  fs << "texture_scale" << floor.texture_scale << "texture_seed"
     << static_cast<double>(floor.texture_seed);
  fs << "grout_width" << floor.grout_width << "grout_albedo" << floor.grout_albedo;
  fs << "laser_albedo" << floor.laser_albedo << "gloss" << floor.gloss;
  fs << "stripe_width" << floor.stripe_width;
  fs << "}";
  fs << "objects"
     << "[";
  for (const SceneObject& o : objects) {
    fs << "{"
       << "type" << shapeName(o.type) << "name" << o.name;
    if (o.type == ShapeType::Cylinder) {
      writeVec3(fs, "axis_start", o.axis_start);
      writeVec3(fs, "axis_end", o.axis_end);
    } else {
      writeVec3(fs, "centre", o.centre);
    }
    if (o.type == ShapeType::Box) {
      writeVec3(fs, "size", o.size);
      fs << "yaw" << o.yaw;
    } else {
      fs << "radius" << o.radius;
    }
    fs << "albedo" << o.albedo << "stripe_width" << o.stripe_width << "}";
  }
  fs << "]";
}

}  // namespace multislit
