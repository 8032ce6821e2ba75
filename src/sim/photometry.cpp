#include "multislit/sim/photometry.h"

#include "yaml_fields.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <functional>
#include <map>
#include <stdexcept>
#include <utility>
#include <vector>

namespace multislit {
namespace {

// splitmix64: the same draws on every platform (std distributions are not specified exactly).
class Draw {
 public:
  explicit Draw(uint64_t seed) : state_(seed ^ 0x5DEECE66DULL) {}
  double uniform(double lo, double hi) {
    return lo + (hi - lo) * static_cast<double>(next() >> 11) * 0x1.0p-53;
  }
  double logUniform(double lo, double hi) { return std::exp(uniform(std::log(lo), std::log(hi))); }
  bool chance(double p) { return uniform(0, 1) < p; }
  uint64_t next() {
    uint64_t z = (state_ += 0x9E3779B97F4A7C15ULL);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
    return z ^ (z >> 31);
  }

 private:
  uint64_t state_;
};

using Edit = std::function<void(Photometry&)>;

using Preset = std::pair<std::string, Edit>;

// The light that reaches the camera: the laser's power against the room's light, the stripe's
// focus and its speckle.
std::vector<Preset> lightPresets() {
  return {
      {"default", [](Photometry&) {}},
      {"bright-room", [](Photometry& p) { p.render.ambient *= 4; }},
      {"dark-floor",
       [](Photometry& p) {
         p.render.laser_peak *= 0.4;
         p.floor.albedo = 0.25;
       }},
      {"saturated", [](Photometry& p) { p.render.laser_peak *= 2; }},
      {"narrow",
       [](Photometry& p) {
         p.render.stripe_width = 0.5;
         p.render.blur_sigma = 0.3;
       }},
      {"defocus",
       [](Photometry& p) {
         p.render.stripe_width = 2.0;
         p.render.blur_sigma = 1.2;
       }},
      {"speckle",
       [](Photometry& p) {
         p.render.speckle_model = SpeckleModel::Gamma;
         p.render.speckle_contrast = 0.9;
         p.render.speckle_grain = 1.0;
       }},
  };
}

// The surfaces (textured, glossy, translucent) and the camera (bit depth, gamma, noise).
std::vector<Preset> surfaceAndCameraPresets() {
  return {
      {"tiles",
       [](Photometry& p) {
         p.floor.texture = FloorTexture::Tiles;
         p.floor.albedo = 0.6;
         p.floor.texture_amplitude = 0.12;
         p.floor.texture_scale = 0.2;
         p.floor.grout_width = 0.004;
         p.floor.grout_albedo = 0.08;
       }},
      {"carpet",
       [](Photometry& p) {
         p.floor.texture = FloorTexture::Carpet;
         p.floor.albedo = 0.4;
         p.floor.texture_amplitude = 0.6;
         p.floor.texture_scale = 0.0015;
         p.floor.stripe_width = 1.4;  // light scattered inside the pile
       }},
      {"glossy",
       [](Photometry& p) {
         p.floor.texture_amplitude = 0.05;
         p.floor.laser_albedo = 0.35;
         p.floor.gloss = 1.5;
       }},
      {"16bit", [](Photometry& p) { p.render.bit_depth = 16; }},
      {"gamma", [](Photometry& p) { p.render.gamma = 2.2; }},
      {"noisy",
       [](Photometry& p) {
         p.render.read_noise = 0.015;
         p.render.full_well = 3000;
       }},
      {"translucent-objects",
       [](Photometry& p) {
         p.object_albedo = 0.9;
         p.object_stripe_width = 2.0;  // subsurface scattering: a wider, dimmer stripe
       }},
  };
}

// The presets, as edits of today's photometry (RenderConfig{}, FloorConfig{}), in this order.
const std::vector<Preset>& presets() {
  static const std::vector<Preset> list = [] {
    std::vector<Preset> all = lightPresets();
    for (Preset& preset : surfaceAndCameraPresets()) all.push_back(std::move(preset));
    return all;
  }();
  return list;
}

// The stripe on the floor's far rows of the reference pose (range 0.66 m, incidence 42 deg:
// 0.38 of the laser_peak geometry) against the background and its noise, before gamma.
struct FarRowStripe {
  double peak = 0, background = 0, noise = 0;
};

FarRowStripe farRowStripe(const Photometry& p) {
  const RenderConfig& r = p.render;
  const double width = r.stripe_width * p.floor.stripe_width;
  const double sheet_px = 1.3 * width;  // the sheet's 1-sigma width in the image [px]
  const double spread = std::sqrt(sheet_px * sheet_px + r.blur_sigma * r.blur_sigma + 1.0 / 12);
  const double dark = p.floor.texture == FloorTexture::Carpet
                          ? 1 - 0.5 * p.floor.texture_amplitude  // the darker fibres
                          : 1.0;
  FarRowStripe s;
  s.peak = r.laser_peak * p.floor.albedo * dark * p.floor.laser_albedo * 0.38 / width * sheet_px /
           spread * (1 - 0.5 * r.speckle_contrast);
  s.background = r.ambient * p.floor.albedo * (1 + p.floor.gloss);
  const double quantum = 1.0 / (r.bit_depth == 8 ? 255.0 : 65535.0);
  s.noise =
      std::sqrt(s.background / r.full_well + r.read_noise * r.read_noise + quantum * quantum / 12);
  return s;
}

bool measurable(const Photometry& p) {
  const FarRowStripe s = farRowStripe(p);
  return s.peak >= 6 * s.noise && s.peak >= 0.15 * s.background && s.background < 0.7;
}

void drawRender(Draw& d, RenderConfig& r) {
  r.laser_peak *= d.logUniform(0.4, 2.0);
  r.ambient *= d.logUniform(0.5, 4.0);
  r.speckle_contrast = d.logUniform(0.02, 1.0);
  // Fully developed speckle is gamma; the old Gaussian model only up to contrast 0.3.
  r.speckle_model =
      r.speckle_contrast > 0.3 || d.chance(0.5) ? SpeckleModel::Gamma : SpeckleModel::Gaussian;
  r.speckle_grain = d.uniform(0.5, 2.0);
  r.stripe_width = d.logUniform(0.5, 2.0);
  r.blur_sigma = d.uniform(0.3, 1.5);
  r.read_noise = d.logUniform(0.002, 0.02);
  r.full_well = d.logUniform(3000, 30000);
  r.gamma = d.chance(0.5) ? 1.0 : d.uniform(0.8, 2.2);
  r.bit_depth = d.chance(0.25) ? 16 : 8;
}

void drawFloor(Draw& d, FloorConfig& f) {
  f = FloorConfig{};
  f.texture = static_cast<FloorTexture>(d.next() % 3);
  f.texture_seed = static_cast<unsigned>(d.next() % 100000);
  f.albedo = d.uniform(0.15, 0.8);
  if (f.texture == FloorTexture::Wood) {
    f.texture_amplitude = d.uniform(0.05, 0.35);
    f.texture_scale = d.logUniform(0.005, 0.03);
  } else if (f.texture == FloorTexture::Tiles) {
    f.texture_amplitude = d.uniform(0.0, 0.2);
    f.texture_scale = d.uniform(0.1, 0.3);
    f.grout_width = d.uniform(0.002, 0.006);
    f.grout_albedo = d.uniform(0.03, 0.2);
  } else {
    f.texture_amplitude = d.uniform(0.3, 0.8);
    f.texture_scale = d.logUniform(0.001, 0.004);
    f.stripe_width = d.uniform(1.0, 1.5);
  }
  if (d.chance(0.25)) {  // glossy: less diffuse laser light back, a lamp's glare
    f.laser_albedo = d.uniform(0.3, 0.7);
    f.gloss = d.uniform(0.3, 2.0);
  }
}

}  // namespace

void Photometry::validate() const {
  render.validate();
  floor.validate();
  if (!(object_albedo < 0 || object_albedo <= 1))
    throw std::invalid_argument("photometry: object_albedo must be <= 1 (< 0: keep)");
  if (!(object_stripe_width >= 0.25 && object_stripe_width <= 4))
    throw std::invalid_argument("photometry: object_stripe_width must be in [0.25, 4]");
  distortion.validate("photometry");
}

std::vector<std::string> photometryPresetNames() {
  std::vector<std::string> names;
  for (const auto& [name, edit] : presets()) names.push_back(name);
  return names;
}

Photometry photometryPreset(const std::string& name) {
  for (const auto& [preset, edit] : presets()) {
    if (preset != name) continue;
    Photometry p;
    p.name = name;
    edit(p);
    p.validate();
    return p;
  }
  std::string known;
  for (const std::string& n : photometryPresetNames()) known += (known.empty() ? "" : ", ") + n;
  throw std::invalid_argument("unknown photometry '" + name + "'; known: " + known + ", random");
}

Photometry randomPhotometry(uint64_t seed) {
  Draw d(seed);
  Photometry p;
  for (int attempt = 0; attempt < 1000; ++attempt) {
    p = Photometry{};
    drawRender(d, p.render);
    drawFloor(d, p.floor);
    p.object_albedo = d.uniform(0.15, 0.95);
    p.object_stripe_width = d.logUniform(0.6, 2.5);
    if (measurable(p)) break;
  }
  p.name = "random-" + std::to_string(seed);
  p.render.seed = seed;
  p.validate();
  return p;
}

Photometry choosePhotometry(const std::string& choice, uint64_t seed) {
  if (choice == "random") return randomPhotometry(seed);
  if (isPhotometryFile(choice)) return loadPhotometry(choice);
  return photometryPreset(choice);
}

bool isPhotometryFile(const std::string& choice) {
  const std::filesystem::path extension = std::filesystem::path(choice).extension();
  return extension == ".yaml" || extension == ".yml";
}

void setObjectSurfaces(std::vector<SceneObject>& objects, double albedo, double stripe_width) {
  for (SceneObject& o : objects) {
    if (albedo >= 0) o.albedo = albedo;
    if (stripe_width >= 0) o.stripe_width = stripe_width;
  }
}

RenderConfig applyPhotometry(const Photometry& photometry, Scene& scene) {
  photometry.validate();
  scene.floor = photometry.floor;
  setObjectSurfaces(scene.objects, photometry.object_albedo, photometry.object_stripe_width);
  return photometry.render;
}

namespace {

// The seed is written as a string: a 64-bit value does not fit OpenCV's int.
uint64_t parseSeed(const std::string& text) {
  std::size_t end = 0;
  unsigned long long seed = 0;
  try {
    seed = std::stoull(text, &end);
  } catch (const std::logic_error&) {
    end = 0;
  }
  if (text.empty() || end != text.size() || !std::isdigit(static_cast<unsigned char>(text[0])))
    throw std::invalid_argument("field 'seed' must be an unsigned 64-bit integer, not '" + text +
                                "'");
  return seed;
}

// The keys of a photometry file, in the file's order: first its name and the values converted by
// hand (an enum by name, a 64-bit seed as a string), then its numbers.
const Field<Photometry> kHeadKeys[] = {
    {"name", &Photometry::name},
    {"speckle_model",
     Codec<Photometry>{
         [](const cv::FileNode& node, const char* key, Photometry& p) {
           std::string model = p.render.speckle_model == SpeckleModel::Gamma ? "gamma" : "gaussian";
           readField(node, key, model);
           if (model != "gaussian" && model != "gamma")
             throw std::invalid_argument("field 'speckle_model' must be gaussian or gamma");
           p.render.speckle_model = model == "gamma" ? SpeckleModel::Gamma : SpeckleModel::Gaussian;
         },
         [](cv::FileStorage& fs, const char* key, const Photometry& p) {
           fs << key << (p.render.speckle_model == SpeckleModel::Gamma ? "gamma" : "gaussian");
         }}},
    {"noise", Codec<Photometry>{[](const cv::FileNode& node, const char* key, Photometry& p) {
                                  int noise = p.render.noise ? 1 : 0;
                                  readField(node, key, noise);
                                  if (noise != 0 && noise != 1)
                                    throw std::invalid_argument("field 'noise' must be 0 or 1");
                                  p.render.noise = noise != 0;
                                },
                                [](cv::FileStorage& fs, const char* key, const Photometry& p) {
                                  fs << key << static_cast<int>(p.render.noise);
                                }}},
    {"seed", Codec<Photometry>{[](const cv::FileNode& node, const char* key, Photometry& p) {
                                 std::string seed = std::to_string(p.render.seed);
                                 readField(node, key, seed);
                                 p.render.seed = parseSeed(seed);
                               },
                               [](cv::FileStorage& fs, const char* key, const Photometry& p) {
                                 fs << key << std::to_string(p.render.seed);
                               }}},
    {"floor_texture",
     Codec<Photometry>{[](const cv::FileNode& node, const char* key, Photometry& p) {
                         std::string texture = floorTextureName(p.floor.texture);
                         readField(node, key, texture);
                         p.floor.texture = floorTextureFromName(texture);
                       },
                       [](cv::FileStorage& fs, const char* key, const Photometry& p) {
                         fs << key << floorTextureName(p.floor.texture);
                       }}}};
const Field<FloorConfig> kTextureSeedKeys[] = {{"floor_texture_seed", &FloorConfig::texture_seed}};
const Field<RenderConfig> kRenderKeys[] = {{"laser_peak", &RenderConfig::laser_peak},
                                           {"ambient", &RenderConfig::ambient},
                                           {"speckle_contrast", &RenderConfig::speckle_contrast},
                                           {"speckle_grain", &RenderConfig::speckle_grain},
                                           {"blur_sigma", &RenderConfig::blur_sigma},
                                           {"full_well", &RenderConfig::full_well},
                                           {"read_noise", &RenderConfig::read_noise},
                                           {"stripe_width", &RenderConfig::stripe_width},
                                           {"gamma", &RenderConfig::gamma}};
const Field<FloorConfig> kFloorKeys[] = {
    {"floor_albedo", &FloorConfig::albedo},
    {"floor_texture_amplitude", &FloorConfig::texture_amplitude},
    {"floor_texture_scale", &FloorConfig::texture_scale},
    {"floor_grout_width", &FloorConfig::grout_width},
    {"floor_grout_albedo", &FloorConfig::grout_albedo},
    {"floor_laser_albedo", &FloorConfig::laser_albedo},
    {"floor_gloss", &FloorConfig::gloss},
    {"floor_stripe_width", &FloorConfig::stripe_width}};
const Field<Photometry> kObjectKeys[] = {{"object_albedo", &Photometry::object_albedo},
                                         {"object_stripe_width", &Photometry::object_stripe_width}};
const Field<RenderConfig> kSamplingKeys[] = {{"bit_depth", &RenderConfig::bit_depth},
                                             {"supersample", &RenderConfig::supersample}};
const Field<Photometry> kLensKeys[] = {{"distortion", &Photometry::distortion}};  // when any

// visit(keys, part) for the tables of a photometry file's numbers, in the file's order.
template <typename P, typename Visit>
void forEachTable(P& p, Visit&& visit) {
  visit(kHeadKeys, p);
  visit(kTextureSeedKeys, p.floor);
  visit(kRenderKeys, p.render);
  visit(kFloorKeys, p.floor);
  visit(kObjectKeys, p);
  visit(kSamplingKeys, p.render);
  visit(kLensKeys, p);
}

}  // namespace

void savePhotometry(const Photometry& p, const std::string& path) {
  cv::FileStorage fs = openYamlForWrite(path, "photometry");
  forEachTable(p, [&](const auto& keys, const auto& part) { writeFields(fs, keys, part); });
}

Photometry loadPhotometry(const std::string& path) {
  cv::FileStorage fs = openYamlForRead(path, "photometry");
  const cv::FileNode root = fs.root();
  Photometry p;
  try {
    std::vector<std::string> known;
    forEachTable(p, [&](const auto& keys, auto&) {
      for (std::string& key : keysOf(keys)) known.push_back(std::move(key));
    });
    checkKeys(root, "", known);
    forEachTable(p, [&](const auto& keys, auto& part) { readFields(root, keys, part); });
    p.validate();
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(path + ": " + e.what());
  }
  return p;
}

}  // namespace multislit
