#include "multislit/odometry.h"

#include "file_read.h"

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <stdexcept>

namespace multislit {

namespace {

constexpr const char* kHeader = "stamp_us,x,y,z,roll,pitch,yaw";
constexpr const char* kFields[] = {"stamp_us", "x", "y", "z", "roll", "pitch", "yaw"};

std::string trimmed(const std::string& s) {
  const auto a = s.find_first_not_of(" \t\r");
  const auto b = s.find_last_not_of(" \t\r");
  return a == std::string::npos ? std::string() : s.substr(a, b - a + 1);
}

/// One row: 7 numbers, the first a non-negative integer. Throws std::runtime_error "at: ...".
OdometrySample parseRow(const std::string& line, const std::string& at) {
  std::vector<std::string> cells;
  std::stringstream row(line);
  for (std::string cell; std::getline(row, cell, ',');) cells.push_back(trimmed(cell));
  if (cells.size() != 7)
    throw std::runtime_error(at + ": " + std::to_string(cells.size()) + " values, expected 7 (" +
                             kHeader + ")");
  double v[7];
  for (int k = 0; k < 7; ++k) {
    const std::string& c = cells[static_cast<std::size_t>(k)];
    char* end = nullptr;
    errno = 0;
    v[k] = std::strtod(c.c_str(), &end);
    if (c.empty() || *end != '\0' || errno == ERANGE || !std::isfinite(v[k]))
      throw std::runtime_error(at + ": " + kFields[k] + " '" + c + "' is not a finite number");
  }
  for (int k = 1; k <= 3; ++k)
    if (std::abs(v[k]) > kMaxOdometryDistance)
      throw std::runtime_error(at + ": " + kFields[k] + " '" + cells[static_cast<std::size_t>(k)] +
                               "' is farther than " +
                               std::to_string(static_cast<long>(kMaxOdometryDistance)) +
                               " m from the origin");
  if (v[0] < 0 || v[0] > 9.0e18 || v[0] != std::floor(v[0]))
    throw std::runtime_error(at + ": stamp_us '" + cells[0] +
                             "' is not a whole number of microseconds >= 0");
  OdometrySample s;
  // Digits: exact to the microsecond, above 2^53 too; else (1e5, 100000.0) the whole double.
  const bool digits = std::all_of(cells[0].begin(), cells[0].end(),
                                  [](unsigned char c) { return std::isdigit(c) != 0; });
  s.stamp_us = digits ? static_cast<std::uint64_t>(std::strtoull(cells[0].c_str(), nullptr, 10))
                      : static_cast<std::uint64_t>(v[0]);
  s.world_from_robot.linear() = fromRollPitchYaw(v[4], v[5], v[6]);
  s.world_from_robot.translation() = Eigen::Vector3d(v[1], v[2], v[3]);
  return s;
}

std::string describe(const OdometrySample& s) { return "stamp_us " + std::to_string(s.stamp_us); }

}  // namespace

const char* poseMissName(PoseMiss miss) {
  switch (miss) {
    case PoseMiss::None:
      return "none";
    case PoseMiss::BeforeStart:
      return "before the odometry's first stamp";
    case PoseMiss::AfterEnd:
      return "after the odometry's last stamp";
    case PoseMiss::InGap:
      return "in a gap of the odometry";
  }
  return "?";
}

Odometry::Odometry(std::vector<OdometrySample> samples, std::uint64_t max_gap_us)
    : samples_(std::move(samples)), max_gap_us_(max_gap_us) {
  if (samples_.empty()) throw std::invalid_argument("Odometry: no samples");
  for (std::size_t k = 0; k < samples_.size(); ++k) {
    const OdometrySample& s = samples_[k];
    const std::string which = "Odometry sample " + std::to_string(k) + " (" + describe(s) + ")";
    if (!s.world_from_robot.matrix().allFinite())
      throw std::invalid_argument(which + ": pose is not finite");
    if (s.world_from_robot.translation().cwiseAbs().maxCoeff() > kMaxOdometryDistance)
      throw std::invalid_argument(which + ": position is farther than " +
                                  std::to_string(static_cast<long>(kMaxOdometryDistance)) +
                                  " m from the origin");
    const Eigen::Matrix3d r = s.world_from_robot.linear();
    if (!(r.transpose() * r).isApprox(Eigen::Matrix3d::Identity(), 1e-6) || r.determinant() < 0)
      throw std::invalid_argument(which + ": orientation is not a rotation");
    if (k == 0) continue;
    const std::uint64_t before = samples_[k - 1].stamp_us;
    if (s.stamp_us == before)
      throw std::invalid_argument(which + ": stamp repeats sample " + std::to_string(k - 1));
    if (s.stamp_us < before)
      throw std::invalid_argument(which + ": stamp goes back from " + std::to_string(before) +
                                  " (stamps must increase)");
  }
}

Odometry Odometry::load(const std::string& path, std::uint64_t max_gap_us) {
  constexpr std::size_t kMaxBytes = std::size_t{1} << 30;
  std::istringstream in(detail::readWholeFile(path, "odometry file", kMaxBytes));
  std::string line;
  if (!std::getline(in, line) || trimmed(line) != kHeader)
    throw std::runtime_error(path + ":1: the header must be '" + kHeader + "'");
  std::vector<OdometrySample> samples;
  for (int number = 2; std::getline(in, line); ++number) {
    if (trimmed(line).empty()) continue;
    const std::string at = path + ":" + std::to_string(number);
    samples.push_back(parseRow(line, at));
    if (samples.size() < 2) continue;
    const std::uint64_t before = samples[samples.size() - 2].stamp_us;
    if (samples.back().stamp_us == before)
      throw std::runtime_error(at + ": stamp_us " + std::to_string(before) +
                               " repeats the row before (stamps must increase)");
    if (samples.back().stamp_us < before)
      throw std::runtime_error(at + ": stamp_us " + std::to_string(samples.back().stamp_us) +
                               " goes back from " + std::to_string(before) +
                               " (stamps must increase)");
  }
  if (samples.empty()) throw std::runtime_error(path + ": no poses after the header");
  return Odometry(std::move(samples), max_gap_us);
}

std::optional<Eigen::Isometry3d> Odometry::at(std::uint64_t stamp_us, PoseMiss* miss) const {
  PoseMiss unused;
  PoseMiss& why = miss ? *miss : unused;
  why = PoseMiss::None;
  if (stamp_us < samples_.front().stamp_us) why = PoseMiss::BeforeStart;
  if (stamp_us > samples_.back().stamp_us) why = PoseMiss::AfterEnd;
  if (why != PoseMiss::None) return std::nullopt;
  // The first sample at or after the stamp.
  const auto it =
      std::lower_bound(samples_.begin(), samples_.end(), stamp_us,
                       [](const OdometrySample& s, std::uint64_t t) { return s.stamp_us < t; });
  const auto hi = static_cast<std::size_t>(it - samples_.begin());
  if (samples_[hi].stamp_us == stamp_us) return samples_[hi].world_from_robot;
  const OdometrySample& a = samples_[hi - 1];
  const OdometrySample& b = samples_[hi];
  if (b.stamp_us - a.stamp_us > max_gap_us_) {
    why = PoseMiss::InGap;
    return std::nullopt;
  }
  const double t =
      static_cast<double>(stamp_us - a.stamp_us) / static_cast<double>(b.stamp_us - a.stamp_us);
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  const Eigen::Quaterniond qa(a.world_from_robot.linear()), qb(b.world_from_robot.linear());
  pose.linear() = qa.slerp(t, qb).toRotationMatrix();
  pose.translation() =
      (1 - t) * a.world_from_robot.translation() + t * b.world_from_robot.translation();
  return pose;
}

Eigen::Vector3d rollPitchYaw(const Eigen::Matrix3d& r) {
  const double cos_pitch = std::hypot(r(0, 0), r(1, 0));
  const double pitch = std::atan2(-r(2, 0), cos_pitch);
  // Pitched +-90 deg (gimbal lock) only yaw -+ roll is defined, and the entries the two angles
  // come from are rounding noise: roll 0 and that angle as yaw (fuzz/fuzz_odometry: the file
  // written back gave another rotation). Below 1e-8 the error of either way is under 1e-8.
  if (cos_pitch < 1e-8) return {0.0, pitch, std::atan2(-r(0, 1), r(1, 1))};
  return {std::atan2(r(2, 1), r(2, 2)), pitch, std::atan2(r(1, 0), r(0, 0))};
}

Eigen::Matrix3d fromRollPitchYaw(double roll, double pitch, double yaw) {
  return (Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()) *
          Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitY()) *
          Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitX()))
      .toRotationMatrix();
}

void saveOdometry(const std::string& path, const std::vector<OdometrySample>& samples) {
  std::ofstream out(path);
  out << kHeader << '\n';
  char line[256];
  for (const OdometrySample& s : samples) {
    const Eigen::Vector3d t = s.world_from_robot.translation();
    const Eigen::Vector3d rpy = rollPitchYaw(s.world_from_robot.linear());
    std::snprintf(line, sizeof line, "%llu,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g\n",
                  static_cast<unsigned long long>(s.stamp_us), t.x(), t.y(), t.z(), rpy[0], rpy[1],
                  rpy[2]);
    out << line;
  }
  out.flush();
  if (!out) throw std::runtime_error(path + ": cannot write the odometry file");
}

}  // namespace multislit
