// Fuzz target: an odometry file (Odometry::load), the pose at and between its stamps, and the file
// written back (saveOdometry) read again to the same poses.
#include "fuzz_support.h"

#include "multislit/odometry.h"

#include <stdexcept>

using namespace multislit;

namespace {

bool isRotation(const Eigen::Matrix3d& r) {
  return (r.transpose() * r).isApprox(Eigen::Matrix3d::Identity(), 1e-6) && r.determinant() > 0;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string path = fuzz::writeInput("odometry.csv", data, size);
  std::vector<OdometrySample> samples;
  try {
    samples = Odometry::load(path).samples();
  } catch (const std::runtime_error&) {
    return 0;  // FILE:LINE: what is wrong
  }
  const Odometry odometry(samples, 1000);
  PoseMiss miss = PoseMiss::None;
  if (samples.front().stamp_us > 0)
    fuzz::expect(!odometry.at(samples.front().stamp_us - 1, &miss) && miss == PoseMiss::BeforeStart,
                 "no pose before the first stamp");
  for (std::size_t k = 0; k < samples.size(); ++k) {
    const std::uint64_t t = samples[k].stamp_us;
    const auto at = odometry.at(t);
    fuzz::expect(at && at->isApprox(samples[k].world_from_robot),
                 "a sample's own pose at its stamp");
    if (k + 1 == samples.size()) break;
    const std::uint64_t mid = t + (samples[k + 1].stamp_us - t) / 2;
    const auto between = odometry.at(mid, &miss);
    fuzz::expect(between ? isRotation(between->linear()) && between->matrix().allFinite()
                         : miss == PoseMiss::InGap,
                 "a rotation between two samples, or a gap");
  }
  saveOdometry(path, samples);
  const Odometry back = Odometry::load(path);
  fuzz::expect(back.samples().size() == samples.size(), "written back: as many samples");
  for (std::size_t k = 0; k < samples.size(); ++k) {
    const Eigen::Isometry3d &a = samples[k].world_from_robot,
                            &b = back.samples()[k].world_from_robot;
    fuzz::expect(back.samples()[k].stamp_us == samples[k].stamp_us &&
                     a.translation() == b.translation() &&
                     (a.linear() - b.linear()).cwiseAbs().maxCoeff() < 1e-6,
                 "written back: the same stamps, positions and (roll, pitch, yaw) rotations");
  }
  return 0;
}
