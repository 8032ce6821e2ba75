#include "multislit/sim/rdmap_synth.h"

#include "multislit/extractor.h"

#include <opencv2/core.hpp>

#include <cmath>
#include <limits>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

namespace multislit {

void RDMapSynthesizerConfig::validate() const {
  auto require = [](bool ok, const char* field, const char* rule) {
    if (!ok)
      throw std::invalid_argument(std::string("RDMapSynthesizerConfig.") + field + " " + rule);
  };
  require(noise_sigma >= 0 && noise_sigma < 10, "noise_sigma", "must be in [0, 10) px");
  require(dropout >= 0 && dropout < 1, "dropout", "must be in [0, 1)");
}

Reference renderFloorReference(const SensorConfig& sensor, const MountConfig& reference_mount,
                               const RenderConfig& render, const FloorConfig& floor) {
  const Simulator simulator(sensor, render);
  ReferenceConfig config;
  config.expected_slits = sensor.projector.slit_count;  // the sensor's own count, not the paper's
  Scene bare;
  bare.floor = floor;
  Reference reference =
      Reference::fromImage(simulator.renderReference(bare, reference_mount).image, config);
  reference.setNominalScale(sensor, reference_mount);
  return reference;
}

RDMapSynthesizer::RDMapSynthesizer(const SensorConfig& sensor, Reference reference,
                                   const RDMapSynthesizerConfig& config)
    : simulator_(sensor), reference_(std::move(reference)), config_(config) {
  config_.validate();
  if (reference_.image_width != sensor.camera.width ||
      reference_.image_height != sensor.camera.height)
    throw std::invalid_argument("RDMapSynthesizer: the reference was taken with another camera");
  // The Extractor's layout (u, v, slit of every cell, NaN elsewhere): what it returns for a frame
  // in which no slit is seen.
  const cv::Mat dark(reference_.image_height, reference_.image_width, CV_8UC1, cv::Scalar(0));
  ExtractorConfig extractor;
  extractor.frame_id = config_.frame_id;
  Extractor(reference_, extractor).extract(dark, layout_);
  layout_.header.frame_id = config_.frame_id;
}

pcl::PointCloud<PointRDM>::Ptr RDMapSynthesizer::synthesize(
    const Scene& scene, const Eigen::Isometry3d& world_from_camera, std::uint64_t frame,
    std::vector<SlitCrossing>* truth) const {
  auto cloud = pcl::make_shared<pcl::PointCloud<PointRDM>>(layout_);
  cloud->header.stamp = frame * 1000000ull / 30ull;
  cloud->header.seq = static_cast<std::uint32_t>(frame);

  // The exact slit centres of this frame, by image row.
  std::vector<std::vector<double>> centres(static_cast<std::size_t>(reference_.image_height));
  std::vector<SlitCrossing> crossings = simulator_.groundTruth(scene, world_from_camera);
  for (const SlitCrossing& c : crossings) centres[static_cast<std::size_t>(c.row)].push_back(c.u);
  if (truth) *truth = std::move(crossings);

  std::seed_seq seeds{config_.seed & 0xffffffffu, config_.seed >> 32, frame & 0xffffffffu,
                      frame >> 32};
  std::mt19937_64 rng(seeds);
  std::normal_distribution<double> noise(0.0, config_.noise_sigma);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  const MetricScale& scale = reference_.scale;
  const double half = 0.5 * reference_.region_width;
  for (std::size_t s = 0; s < reference_.slits.size(); ++s) {
    const ReferenceSlit& slit = reference_.slits[s];
    for (std::size_t k = 0; k < slit.u.size(); ++k) {
      const double u_ref = slit.u[k];
      const int row = slit.first_row + static_cast<int>(k);
      if (!std::isfinite(u_ref) || row < 0 || row >= reference_.image_height) continue;
      // The crossing inside this point's assigned region (Fig. 7), as the Extractor searches.
      double best = std::numeric_limits<double>::infinity();
      for (const double u : centres[static_cast<std::size_t>(row)])
        if (std::abs(u - u_ref) <= half && std::abs(u - u_ref) < std::abs(best - u_ref)) best = u;
      const double u_seen = best + noise(rng);
      if (!std::isfinite(best) || uniform(rng) < config_.dropout) continue;
      PointRDM& p = cloud->at(static_cast<int>(k), static_cast<int>(s));
      p.dk = static_cast<float>(u_seen - u_ref);
      // Metric position: the Extractor's formula with the reference's scale.
      if (!scale.valid() || k >= slit.u_inf.size() || !std::isfinite(slit.u_inf[k])) continue;
      const double depth = scale.disparity_constant / (u_seen - slit.u_inf[k]);
      if (depth <= 0) continue;
      p.x = static_cast<float>((u_seen - scale.cx) * depth / scale.f);
      p.y = static_cast<float>((row - scale.cy) * depth / scale.f);
      p.z = static_cast<float>(depth);
    }
  }
  return cloud;
}

}  // namespace multislit
