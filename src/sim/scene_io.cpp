// A scene's YAML file (Scene::load, Scene::save) and the names of its shapes and floor textures.
#include "multislit/sim/scene.h"

#include "yaml_fields.h"

#include <stdexcept>
#include <string>
#include <vector>

namespace multislit {
namespace {

void readTexture(const cv::FileNode& node, const char* key, FloorConfig& floor) {
  std::string name = floorTextureName(floor.texture);
  readField(node, key, name);
  floor.texture = floorTextureFromName(name);
}

void writeTexture(cv::FileStorage& fs, const char* key, const FloorConfig& floor) {
  fs << key << floorTextureName(floor.texture);
}

// The keys of a scene file: the floor's, then each object's: its type, name, shape and surface.
constexpr const char* kFloor = "floor";
constexpr const char* kObjects = "objects";
const Field<FloorConfig> kFloorKeys[] = {{"texture", Codec<FloorConfig>{readTexture, writeTexture}},
                                         {"albedo", &FloorConfig::albedo},
                                         {"texture_amplitude", &FloorConfig::texture_amplitude},
                                         {"texture_scale", &FloorConfig::texture_scale},
                                         {"texture_seed", &FloorConfig::texture_seed},
                                         {"grout_width", &FloorConfig::grout_width},
                                         {"grout_albedo", &FloorConfig::grout_albedo},
                                         {"laser_albedo", &FloorConfig::laser_albedo},
                                         {"gloss", &FloorConfig::gloss},
                                         {"stripe_width", &FloorConfig::stripe_width}};
constexpr const char* kType = "type";
const Field<SceneObject> kNameKey[] = {{"name", &SceneObject::name}};
const Field<SceneObject> kSurfaceKeys[] = {{"albedo", &SceneObject::albedo},
                                           {"stripe_width", &SceneObject::stripe_width}};
struct Shape {
  const char* name;
  ShapeType type;
  std::vector<Field<SceneObject>> keys;
};
const Shape kShapes[] = {
    {"sphere",
     ShapeType::Sphere,
     {{"centre", &SceneObject::centre}, {"radius", &SceneObject::radius}}},
    {"cylinder",
     ShapeType::Cylinder,
     {{"axis_start", &SceneObject::axis_start},
      {"axis_end", &SceneObject::axis_end},
      {"radius", &SceneObject::radius}}},
    {"box",
     ShapeType::Box,
     {{"centre", &SceneObject::centre}, {"size", &SceneObject::size}, {"yaw", &SceneObject::yaw}}}};

const Shape* shapeNamed(const std::string& name) {
  for (const Shape& shape : kShapes)
    if (name == shape.name) return &shape;
  return nullptr;
}

const Shape& shapeOf(ShapeType type) {
  for (const Shape& shape : kShapes)
    if (type == shape.type) return shape;
  throw std::logic_error("a shape without a name");
}

// One entry of the list of objects; `index` is its place in the list. A key of another shape is
// an error: it would be ignored.
SceneObject readObject(const cv::FileNode& n, std::size_t index) {
  const std::string where = std::string(kObjects) + "[" + std::to_string(index) + "]";
  if (!n.isMap()) throw std::invalid_argument("'" + where + "' must be a map of keys");
  std::string type;
  readField(n, kType, type);
  const Shape* shape = shapeNamed(type);
  if (shape != nullptr) {
    std::vector<std::string> known = keysOf(kNameKey, shape->keys, kSurfaceKeys);
    known.insert(known.begin(), kType);
    checkKeys(n, where, known);
  }
  SceneObject o;
  readFields(n, kNameKey, o);
  if (o.name.empty()) o.name = type + std::to_string(index);
  if (shape == nullptr)
    throw std::invalid_argument("object '" + o.name +
                                "': type must be sphere, cylinder or box, not '" + type + "'");
  o.type = shape->type;
  readFields(n, shape->keys, o);
  readFields(n, kSurfaceKeys, o);
  if (o.type == ShapeType::Cylinder) o.centre = 0.5 * (o.axis_start + o.axis_end);
  return o;
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
    checkKeys(fs.root(), "", {kFloor, kObjects});
    checkKeys(fs[kFloor], kFloor, keysOf(kFloorKeys));
    readFields(fs[kFloor], kFloorKeys, scene.floor);
    const cv::FileNode list = fs[kObjects];
    if (!list.empty() && !list.isSeq()) throw std::invalid_argument("'objects' must be a list");
    if (list.size() > kMaxObjects)
      throw std::invalid_argument(std::to_string(list.size()) +
                                  " objects, more than the limit of " +
                                  std::to_string(kMaxObjects));
    for (const cv::FileNode& n : list) scene.objects.push_back(readObject(n, scene.objects.size()));
    scene.validate();
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(path + ": " + e.what());
  }
  return scene;
}

void Scene::save(const std::string& path) const {
  cv::FileStorage fs = openYamlForWrite(path, "scene");
  fs << kFloor << "{";
  writeFields(fs, kFloorKeys, floor);
  fs << "}";
  fs << kObjects << "[";
  for (const SceneObject& o : objects) {
    const Shape& shape = shapeOf(o.type);
    fs << "{" << kType << shape.name;
    writeFields(fs, kNameKey, o);
    writeFields(fs, shape.keys, o);
    writeFields(fs, kSurfaceKeys, o);
    fs << "}";
  }
  fs << "]";
}

}  // namespace multislit
