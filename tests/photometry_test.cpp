// Photometric variety of the simulator (speckle, stripe width, gamma, floors, presets, random
// draws) measured on renders of a 320 x 240 window of the paper's sensor, against exact truth.
#include "multislit/sim/photometry.h"
#include "multislit/sim/scenarios.h"
#include "multislit/sim/walk.h"
#include "test_support.h"

#include <gtest/gtest.h>
#include <opencv2/core.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

using namespace multislit;

namespace {

// The paper's sensor seen through a 320 x 240 window around the ping-pong ball of "ball": the
// same rays as the full image's columns 488..807 and rows 260..499, 1/16 of the render cost.
SensorConfig windowSensor() {
  SensorConfig s;
  s.camera.width = 320;
  s.camera.height = 240;
  s.camera.principal_x = 647.5 - 488;
  s.camera.principal_y = 481.5 - 260;
  return s;
}

Eigen::Isometry3d pose(const SensorGeometry& g, const Scenario& s) {
  return s.worldFromRobot(0) * g.robotFromCamera(s.mount);
}

// A render with only the optics: no noise, 16 bits, no ambient light, a uniform floor.
RenderConfig opticsOnly() {
  RenderConfig r;
  r.noise = false;
  r.bit_depth = 16;
  r.ambient = 0;
  return r;
}

double at(const cv::Mat& image, int row, int col) {
  return image.depth() == CV_8U ? image.at<uint8_t>(row, col) : image.at<uint16_t>(row, col);
}

// Full width at half maximum of the profile of row `row` around column u (linear interpolation
// of the half-maximum crossings), and its maximum. NaN when the profile is cut by the image.
struct Profile {
  double fwhm = NAN, peak = 0;
};

Profile rowProfile(const cv::Mat& image, int row, double u) {
  const int c = static_cast<int>(std::lround(u));
  Profile p;
  if (c < 30 || c >= image.cols - 30) return p;
  int top = c;
  for (int k = c - 3; k <= c + 3; ++k)
    if (at(image, row, k) > at(image, row, top)) top = k;
  p.peak = at(image, row, top);
  const double half = 0.5 * p.peak;
  int l = top, r = top;
  while (l > c - 30 && at(image, row, l) > half) --l;
  while (r < c + 30 && at(image, row, r) > half) ++r;
  if (at(image, row, l) > half || at(image, row, r) > half) return p;
  const double left = l + (half - at(image, row, l)) / (at(image, row, l + 1) - at(image, row, l));
  const double right = r - (half - at(image, row, r)) / (at(image, row, r - 1) - at(image, row, r));
  p.fwhm = right - left;
  return p;
}

double median(std::vector<double> v) {
  if (v.empty()) return NAN;
  std::nth_element(v.begin(), v.begin() + static_cast<long>(v.size() / 2), v.end());
  return v[v.size() / 2];
}

// The median FWHM and peak of the crossings on `object` (0 floor) in a noise-free render.
Profile medianProfile(const RenderedFrame& f, int object) {
  std::vector<double> widths, peaks;
  for (const SlitCrossing& x : f.truth) {
    if (x.object != object) continue;
    const Profile p = rowProfile(f.image, x.row, x.u);
    if (!std::isfinite(p.fwhm)) continue;
    widths.push_back(p.fwhm);
    peaks.push_back(p.peak);
  }
  return {median(widths), median(peaks)};
}

std::string fileText(const std::string& path) {
  std::ostringstream s;
  s << std::ifstream(path).rdbuf();
  return s.str();
}

}  // namespace

TEST(Photometry, GammaSpeckleOfShapeOneIsFullyDevelopedAndOthersHaveTheirContrast) {
  Scenario s = makeScenario("reference");
  s.scene.floor.texture_amplitude = 0;
  RenderConfig r = opticsOnly();
  r.laser_peak = 0.05;  // the exponential tail stays below full scale
  r.blur_sigma = 0;     // the contrast per pixel, before the lens
  const Simulator clean(windowSensor(), r);
  const cv::Mat base = clean.render(s.scene, pose(clean.geometry(), s)).image;
  double top = 0;
  cv::minMaxLoc(base, nullptr, &top);
  for (const double contrast : {1.0, 0.5, 0.2}) {
    r.noise = true;  // only speckle: no shot noise (a huge well), no read noise
    r.full_well = 1e12;
    r.read_noise = 0;
    r.speckle_model = SpeckleModel::Gamma;
    r.speckle_contrast = contrast;
    const Simulator sim(windowSensor(), r);
    const cv::Mat speckled = sim.render(s.scene, pose(sim.geometry(), s)).image;
    double sum = 0, sum2 = 0, n = 0;
    for (int v = 0; v < base.rows; ++v)
      for (int u = 0; u < base.cols; ++u) {
        if (at(base, v, u) < 0.5 * top) continue;  // on the stripes
        const double ratio = at(speckled, v, u) / at(base, v, u);
        sum += ratio;
        sum2 += ratio * ratio;
        ++n;
      }
    ASSERT_GT(n, 1500);
    const double mean = sum / n, measured = std::sqrt(sum2 / n - mean * mean) / mean;
    std::printf("speckle contrast %.2f: measured %.3f (mean %.3f, %.0f px)\n", contrast, measured,
                mean, n);
    EXPECT_NEAR(mean, 1.0, 0.1 * contrast) << contrast;
    EXPECT_NEAR(measured, contrast, 0.15 * contrast) << contrast;
  }
}

TEST(Photometry, StripeWidthFactorTwoDoublesTheStripeOnFloorAndObject) {
  Scenario s = makeScenario("ball");
  s.scene.floor.texture_amplitude = 0;
  RenderConfig r = opticsOnly();
  r.blur_sigma = 0;
  const Simulator narrow(windowSensor(), r);
  const RenderedFrame a = narrow.render(s.scene, pose(narrow.geometry(), s));
  r.stripe_width = 2;  // focus: every stripe twice as wide, half as high
  const Simulator wide(windowSensor(), r);
  const RenderedFrame b = wide.render(s.scene, pose(wide.geometry(), s));
  s.scene.objects[0].stripe_width = 2;  // only on the ball (subsurface scattering)
  const RenderedFrame c = narrow.render(s.scene, pose(narrow.geometry(), s));
  const Profile floor_a = medianProfile(a, 0), floor_b = medianProfile(b, 0);
  const Profile ball_a = medianProfile(a, 1), ball_c = medianProfile(c, 1);
  std::printf("floor FWHM %.3f -> %.3f px, peak %.0f -> %.0f; ball FWHM %.3f -> %.3f px\n",
              floor_a.fwhm, floor_b.fwhm, floor_a.peak, floor_b.peak, ball_a.fwhm, ball_c.fwhm);
  ASSERT_GT(floor_a.fwhm, 2.0);
  // The pixel's box widens both a little: sqrt(1.3^2 + 1/12) against sqrt(2.6^2 + 1/12).
  EXPECT_NEAR(floor_b.fwhm / floor_a.fwhm, 2.0, 0.1);
  EXPECT_NEAR(floor_b.peak / floor_a.peak, 0.5, 0.05);  // the sheet's power is kept
  EXPECT_NEAR(ball_c.fwhm / ball_a.fwhm, 2.0, 0.2);
  EXPECT_NEAR(ball_c.peak / ball_a.peak, 0.5, 0.1);
  EXPECT_EQ(medianProfile(c, 0).fwhm, floor_a.fwhm);  // the floor did not change
}

TEST(Photometry, WideStripesStaySymmetricAboutTheTruth) {
  Scenario s = makeScenario("reference");
  s.scene.floor.texture_amplitude = 0;
  RenderConfig r = opticsOnly();
  r.stripe_width = 2;
  const Simulator sim(windowSensor(), r);
  const RenderedFrame f = sim.render(s.scene, pose(sim.geometry(), s));
  // The noise-free centroid of a row is on the truth. Along a row the stripe (20 deg from the
  // rows) is 3 times its width: +-40 px hold it whole.
  int measured = 0;
  double worst = 0;
  for (const SlitCrossing& x : f.truth) {
    // The image's first and last rows are sampled (no neighbours for the exact pixel integral).
    if (x.u < 41 || x.u > 278 || x.row == 0 || x.row == f.image.rows - 1) continue;
    double sum = 0, moment = 0;
    for (int u = static_cast<int>(x.u) - 40; u <= static_cast<int>(x.u) + 41; ++u) {
      sum += at(f.image, x.row, u);
      moment += at(f.image, x.row, u) * u;
    }
    worst = std::max(worst, std::abs(moment / sum - x.u));
    ++measured;
  }
  std::printf("%d rows, worst centroid error %.4f px\n", measured, worst);
  EXPECT_GT(measured, 400);
  EXPECT_LT(worst, 0.05);
}

TEST(Photometry, GammaCurveMapsEveryValue) {
  const Scenario s = makeScenario("reference");
  RenderConfig r = opticsOnly();
  r.ambient = 0.1;
  const Simulator linear(windowSensor(), r);
  r.gamma = 2.2;
  const Simulator curved(windowSensor(), r);
  const cv::Mat a = linear.render(s.scene, pose(linear.geometry(), s)).image;
  const cv::Mat b = curved.render(s.scene, pose(curved.geometry(), s)).image;
  int checked = 0;
  for (int v = 0; v < a.rows; v += 3)
    for (int u = 0; u < a.cols; u += 3) {
      const double x = at(a, v, u) / 65535.0;
      if (x < 0.01) continue;
      // a is x rounded to 1/65535: the curve's slope there bounds the difference.
      const double slope = std::pow(x, 1 / 2.2 - 1) / 2.2;
      EXPECT_NEAR(at(b, v, u), 65535.0 * std::pow(x, 1 / 2.2), 0.5 * slope + 0.5);
      ++checked;
    }
  EXPECT_GT(checked, 5000);
}

TEST(Photometry, TilesShowDarkGroutLinesInTheImage) {
  Scenario s = makeScenario("reference");
  const Photometry tiles = photometryPreset("tiles");
  RenderConfig r = applyPhotometry(tiles, s.scene);
  r.noise = false;
  r.laser_peak = 0;   // only the ambient image of the floor
  SensorConfig half;  // the middle quarter of the image: 648 x 482 px
  half.camera.width = 648;
  half.camera.height = 482;
  const Simulator sim(half, r);
  const cv::Mat image = sim.render(s.scene, pose(sim.geometry(), s)).image;
  const double tile = r.ambient * tiles.floor.albedo * 255, grout = r.ambient * 0.08 * 255;
  int dark = 0;
  for (int v = 0; v < image.rows; ++v)
    for (int u = 0; u < image.cols; ++u) dark += at(image, v, u) <= 0.5 * (tile + grout);
  // 4 mm lines around 200 mm tiles: 4 % of the floor, seen obliquely a little more or less.
  const double share = dark / static_cast<double>(image.total());
  EXPECT_GT(share, 0.02);
  EXPECT_LT(share, 0.10);
}

TEST(Photometry, TruthIsTheSameWhateverThePhotometry) {
  const SensorConfig sensor = windowSensor();
  const Scenario base = makeScenario("ball");
  std::vector<SlitCrossing> first;
  for (const std::string name : {"default", "defocus", "translucent-objects", "glossy", "random"}) {
    Scenario s = base;
    const Photometry p = name == "random" ? randomPhotometry(11) : photometryPreset(name);
    const Simulator sim(sensor, applyPhotometry(p, s.scene));
    const auto truth = sim.render(s.scene, pose(sim.geometry(), s)).truth;
    if (first.empty()) {
      first = truth;
      ASSERT_GT(first.size(), 500u);
      continue;
    }
    ASSERT_EQ(truth.size(), first.size()) << name;
    for (std::size_t k = 0; k < truth.size(); ++k) {
      EXPECT_EQ(truth[k].slit, first[k].slit);
      EXPECT_EQ(truth[k].row, first[k].row);
      EXPECT_EQ(truth[k].u, first[k].u);  // bit for bit
      EXPECT_EQ(truth[k].world_point, first[k].world_point);
      EXPECT_EQ(truth[k].object, first[k].object);
    }
  }
}

TEST(Photometry, PresetsAndRandomDrawsAreValidAndDeterministic) {
  for (const std::string& name : photometryPresetNames())
    EXPECT_EQ(photometryPreset(name).name, name);
  EXPECT_THROW(photometryPreset("sunny"), std::invalid_argument);
  const std::string dir = tempPath("round_trip");
  std::filesystem::create_directories(dir);
  int gamma_speckle = 0, curved = 0, sixteen = 0, glossy = 0, textures[3] = {0, 0, 0};
  for (uint64_t seed = 1; seed <= 60; ++seed) {
    const Photometry p = randomPhotometry(seed);
    EXPECT_NO_THROW(p.validate());
    savePhotometry(p, dir + "/multislit_photometry_a.yaml");
    savePhotometry(randomPhotometry(seed), dir + "/multislit_photometry_b.yaml");
    // Same seed, same draw; and the file reproduces it exactly.
    savePhotometry(loadPhotometry(dir + "/multislit_photometry_a.yaml"),
                   dir + "/multislit_photometry_c.yaml");
    EXPECT_EQ(fileText(dir + "/multislit_photometry_a.yaml"),
              fileText(dir + "/multislit_photometry_b.yaml"));
    EXPECT_EQ(fileText(dir + "/multislit_photometry_a.yaml"),
              fileText(dir + "/multislit_photometry_c.yaml"));
    EXPECT_GE(p.render.laser_peak, 0.4 * 0.9 - 1e-12);
    EXPECT_LE(p.render.laser_peak, 2.0 * 0.9 + 1e-12);
    EXPECT_GE(p.render.ambient, 0.5 * 0.1 - 1e-12);
    EXPECT_LE(p.render.ambient, 4.0 * 0.1 + 1e-12);
    EXPECT_GE(p.render.stripe_width, 0.5 - 1e-12);
    EXPECT_LE(p.render.stripe_width, 2.0 + 1e-12);
    gamma_speckle += p.render.speckle_model == SpeckleModel::Gamma;
    curved += p.render.gamma != 1.0;
    sixteen += p.render.bit_depth == 16;
    glossy += p.floor.gloss > 0;
    ++textures[static_cast<int>(p.floor.texture)];
  }
  // Every kind of variety is drawn.
  EXPECT_GT(gamma_speckle, 10);
  EXPECT_LT(gamma_speckle, 60);
  EXPECT_GT(curved, 10);
  EXPECT_GT(sixteen, 5);
  EXPECT_GT(glossy, 5);
  for (int t : textures) EXPECT_GT(t, 8);
}

TEST(Photometry, RandomDrawsKeepTheFloorStripeMeasurableAndRenderTheSameBytes) {
  for (const uint64_t seed : {2u, 3u, 5u, 8u}) {
    Scenario s = makeScenario("reference");
    const Photometry p = randomPhotometry(seed);
    const Simulator sim(windowSensor(), applyPhotometry(p, s.scene));
    const RenderedFrame f = sim.render(s.scene, pose(sim.geometry(), s), 4);
    EXPECT_EQ(cv::norm(f.image, sim.render(s.scene, pose(sim.geometry(), s), 4).image, cv::NORM_L1),
              0.0);
    // The stripe's maximum near the truth stands out of the background 12 px to either side by
    // a few 8-bit levels on most rows.
    const double level = p.render.bit_depth == 8 ? 1.0 : 257.0;
    int rows = 0, visible = 0;
    for (const SlitCrossing& x : f.truth) {
      const int c = static_cast<int>(std::lround(x.u));
      if (c < 14 || c >= f.image.cols - 14) continue;
      double peak = 0;
      for (int k = c - 2; k <= c + 2; ++k) peak = std::max(peak, at(f.image, x.row, k));
      const double background = std::max(at(f.image, x.row, c - 12), at(f.image, x.row, c + 12));
      ++rows;
      visible += peak - background >= 5 * level;
    }
    ASSERT_GT(rows, 500);
    EXPECT_GT(visible, 0.7 * rows) << p.name;
  }
}

TEST(Photometry, FilesWithUnknownKeysOrValuesOutOfRangeAreRefusedNamingTheField) {
  const std::string path = tempPath("multislit_photometry_bad.yaml");
  savePhotometry(photometryPreset("speckle"), path);
  const std::string good = fileText(path);
  // (replacement line, message part): the saved file with one line changed or added.
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"laser_pek: 0.9", "unknown key 'laser_pek'"},
      {"laser_peak: .inf", "laser_peak must be in [0, 100]"},
      {"ambient: .nan", "ambient must be in [0, 100]"},
      {"full_well: .inf", "full_well must be in [100, 1e15]"},
      {"seed: \"-5\"", "field 'seed' must be an unsigned 64-bit integer"},
      {"seed: \"99999999999999999999999\"", "field 'seed' must be an unsigned 64-bit integer"},
      {"noise: 7", "field 'noise' must be 0 or 1"},
      {"floor_texture_seed: -1", "'floor_texture_seed' must be an integer"},
      {"bit_depth: 8.5", "'bit_depth' must be an integer"},
      {"k1: .nan", "photometry.k1 must be finite"},
  };
  for (const auto& [line, expected] : cases) {
    const std::string key = line.substr(0, line.find(':') + 1);
    std::string text = good;
    const std::size_t at = text.find("\n" + key);
    if (at == std::string::npos)
      text += line + "\n";
    else
      text.replace(at + 1, text.find('\n', at + 1) - at - 1, line);
    std::ofstream(path) << text;
    try {
      loadPhotometry(path);
      ADD_FAILURE() << line << " was accepted";
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find(expected), std::string::npos)
          << line << ": " << e.what();
      EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
    }
  }
  std::filesystem::remove(path);
}

// A photometry file may carry the lens the images are seen through: simulate and walk render
// through it (and the walk's reference and extractor undistort with it); a pinhole's file has no
// coefficient.
TEST(Photometry, ALensInTheFileIsReadBackAndTheWalkSeesThroughIt) {
  const std::string path = tempPath("multislit_photometry_lens.yaml");
  savePhotometry(photometryPreset("default"), path);
  EXPECT_EQ(fileText(path).find("k1:"), std::string::npos);
  Photometry lens = photometryPreset("default");
  lens.distortion.k1 = -0.03;
  lens.distortion.p1 = 5e-4;
  savePhotometry(lens, path);
  const Photometry back = loadPhotometry(path);
  EXPECT_DOUBLE_EQ(back.distortion.k1, -0.03);
  EXPECT_DOUBLE_EQ(back.distortion.p1, 5e-4);
  EXPECT_DOUBLE_EQ(back.distortion.k2, 0.0);
  WalkConfig walk;
  applyPhotometry(back, walk);
  EXPECT_DOUBLE_EQ(walk.pipeline.sensor.camera.distortion.k1, -0.03);
  EXPECT_DOUBLE_EQ(walk.pipeline.sensor.camera.distortion.p1, 5e-4);
  WalkConfig pinhole;
  pinhole.pipeline.sensor.camera.distortion.k2 = 0.01;  // a sensor file's lens is kept
  applyPhotometry(photometryPreset("tiles"), pinhole);
  EXPECT_DOUBLE_EQ(pinhole.pipeline.sensor.camera.distortion.k2, 0.01);
  std::filesystem::remove(path);
}
