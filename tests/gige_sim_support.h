// Shared by the tests of the grabber over GigE Vision on 127.0.0.1 (grabber_gige_test,
// grabber_faults_test): the simulated sensor's reference and frames, the camera's settings, and
// the clouds the served images give.
#pragma once

#include "camera_test_support.h"
#include "grabber_test_support.h"
#include "multislit/extractor.h"
#include "multislit/sim/simulated_source.h"
#include "multislit/sources.h"

#include <memory>
#include <vector>

namespace multislit::test {

/// The simulated sensor: a reference with metric scale and two frames of the ball walk.
struct SimData {
  Reference reference;
  std::vector<cv::Mat> frames;
};

inline const SimData& simData() {
  static const SimData data = [] {
    SimulatorSourceConfig config;
    config.scenario = "ball";
    config.render.supersample = 1;
    config.frames = 2;
    SimulatorSource source(config);
    SimData d{source.makeReference(), {}};
    source.start();
    while (std::optional<Frame> f = source.next(std::chrono::milliseconds(100)))
      d.frames.push_back(f->image);
    return d;
  }();
  return data;
}

/// The emulated camera at `fps`, asked for the simulated frames' size.
inline AravisConfig gigeConfig(double fps) {
  AravisConfig c;
  c.camera = CameraEmulator::kAddress;
  c.roi_width = simData().frames[0].cols;
  c.roi_height = simData().frames[0].rows;
  c.frame_rate = fps;
  c.packet_size = 8192;  // loopback carries large datagrams
  return c;
}

inline std::shared_ptr<AravisSource> gigeSource(double fps) {
  return std::make_shared<AravisSource>(gigeConfig(fps));
}

/// The dk of the cloud of each simulated frame, extracted directly.
inline std::vector<std::vector<float>> expectedDk() {
  const Extractor extractor(simData().reference);
  std::vector<std::vector<float>> expected;
  for (const cv::Mat& image : simData().frames) {
    pcl::PointCloud<PointRDM> direct;
    extractor.extract(image, direct);
    expected.push_back(dkOf(direct));
  }
  return expected;
}

}  // namespace multislit::test
