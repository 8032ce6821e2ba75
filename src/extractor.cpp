#include "multislit/extractor.h"

#include "stray_runs.h"
#include "stripe_across.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace multislit {

namespace {

/// Asks for the image's rows, every line of each in order, some way ahead of the row being
/// measured. A new frame is in memory, not in the cache: asked for this way it arrives while the
/// rows before it are measured, where the regions alone, a few batches ahead, left the measure
/// waiting on memory (and every other line, left to the CPU's own prefetcher, is slower).
class RowPrefetch {
 public:
  /// How far ahead: well inside the second-level cache (32 to 128 KB time alike; 8 KB ahead, or
  /// the whole frame at once, is slower).
  static constexpr std::size_t kAheadBytes = 64 * 1024;

  /// Rows first_row .. last_row of `image` (cut to the image) will be asked for.
  RowPrefetch(const cv::Mat& image, int first_row, int last_row)
      : image_(image),
        row_bytes_(static_cast<std::size_t>(image.cols) * image.elemSize()),
        last_row_(std::min(last_row, image.rows - 1)),
        ahead_(static_cast<int>(
            std::max<std::size_t>(1, kAheadBytes / std::max<std::size_t>(row_bytes_, 1)))),
        next_(std::max(first_row, 0)) {}
  /// Every row up to `row` + the rows ahead asked for.
  void upTo(int row) {
    for (const int last = std::min(last_row_, row + ahead_); next_ <= last; ++next_) {
      const char* bytes = image_.ptr<char>(next_);
      for (std::size_t b = 0; b < row_bytes_; b += 64) __builtin_prefetch(bytes + b);
    }
  }

 private:
  const cv::Mat& image_;
  std::size_t row_bytes_;
  int last_row_, ahead_, next_;
};

/// du/dv of a reference slit at row k: the central difference over up to two rows each side
/// where it has points (the reference's centres are smoothed along the slit). 0: none.
double slopeAt(const std::vector<float>& u, std::size_t k) {
  std::size_t lo = k, hi = k;
  for (std::size_t step = 1; step <= 2; ++step) {
    if (k >= step && std::isfinite(u[k - step])) lo = k - step;
    if (k + step < u.size() && std::isfinite(u[k + step])) hi = k + step;
  }
  return hi > lo ? (u[hi] - u[lo]) / static_cast<double>(hi - lo) : 0.0;
}

}  // namespace

void ExtractorConfig::validate() const {
  auto require = [](bool ok, const char* field, const char* rule) {
    if (!ok) throw std::invalid_argument(std::string("extractor config: ") + field + " " + rule);
  };
  require(min_contrast > 0 && min_contrast < 1, "min_contrast", "must be in (0, 1) of full scale");
  require(max_width_factor >= 1, "max_width_factor", "must be >= 1");
  require(min_width >= 0 && min_width <= 64, "min_width", "must be in [0, 64] px");
  require(max_saturated >= 0, "max_saturated", "must be >= 0 px");
  require(full_scale >= 0, "full_scale", "must be >= 0 (0: from the image type)");
  require(stray_run >= 0 && stray_run <= 1000, "stray_run", "must be in [0, 1000] points");
  require(std::isfinite(stray_step) && stray_step > 0, "stray_step", "must be > 0 px");
}

Extractor::Extractor(Reference reference, const ExtractorConfig& config)
    : reference_(std::move(reference)), config_(config) {
  config_.validate();
  if (reference_.slits.empty() || reference_.region_width < 3)
    throw std::invalid_argument("extractor: the reference has no slits or no assigned regions");
  // The cloud with nothing measured: one row per slit, one column per reference row.
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const auto width = static_cast<std::size_t>(reference_.maxSlitLength());
  blank_.resize(width * reference_.slits.size());
  const bool metric = reference_.scale.valid();
  const double half = 0.5 * reference_.region_width;
  for (std::size_t s = 0; s < reference_.slits.size(); ++s) {
    const ReferenceSlit& slit = reference_.slits[s];
    const bool has_inf = metric && slit.u_inf.size() == slit.u.size();
    for (std::size_t k = 0; k < width; ++k) {
      PointRDM& p = blank_[s * width + k];
      p.x = p.y = p.z = p.dk = nan;
      p.u = k < slit.u.size() ? slit.u[k] : nan;
      p.v = static_cast<float>(slit.first_row + static_cast<int>(k));
      p.slit = static_cast<std::int32_t>(s);
      if (!std::isfinite(p.u)) continue;
      // Search the slit only inside this point's assigned region on its row (Fig. 7).
      Task t;
      t.row = slit.first_row + static_cast<int>(k);
      t.first = static_cast<int>(std::ceil(p.u - half));
      t.last = static_cast<int>(std::floor(p.u + half));
      t.cell = static_cast<std::uint32_t>(s * width + k);
      t.u = p.u;
      t.u_inf = has_inf && std::isfinite(slit.u_inf[k]) ? slit.u_inf[k] : nan;
      t.slope = static_cast<float>(slopeAt(slit.u, k));
      t.across_half_rows = acrossHalfRows(halfWindow(), t.slope);
      tasks_.push_back(t);
    }
  }
  std::sort(tasks_.begin(), tasks_.end(), [](const Task& a, const Task& b) {
    return a.row != b.row ? a.row < b.row : a.first < b.first;
  });
  along_slits_.resize(tasks_.size());
  for (std::uint32_t i = 0; i < tasks_.size(); ++i) along_slits_[i] = i;
  std::sort(along_slits_.begin(), along_slits_.end(),
            [this](std::uint32_t a, std::uint32_t b) { return tasks_[a].cell < tasks_[b].cell; });

  if (reference_.lens.distorted()) prepareIdeal();
}

namespace {

/// Farthest a centre's ideal row may lie from its reference point's [px]: the lens moves two
/// points of one recorded row, a region apart, by less than a row of each other unless it bends
/// lines by tens of pixels; beyond, the linear reference slit is not trusted.
constexpr double kMaxIdealRowShift = 3.0;

// The cubic of IdealTask for a task on `row` around reference column u, through `lens`: exact at
// four columns spread over u +- reach.
Eigen::Matrix<double, 2, 4> idealCubic(const Lens& lens, double u, int row, double reach) {
  const double nodes[4] = {-1.0, -1.0 / 3.0, 1.0 / 3.0, 1.0};
  Eigen::Matrix4d vandermonde;
  Eigen::Matrix<double, 4, 2> values;
  for (int j = 0; j < 4; ++j) {
    for (int k = 0; k < 4; ++k) vandermonde(j, k) = std::pow(nodes[j], k);
    values.row(j) = lens.undistort(Eigen::Vector2d(u + reach * nodes[j], row)).transpose();
  }
  return vandermonde.fullPivLu().solve(values).transpose();
}

}  // namespace

void Extractor::prepareIdeal() {
  const Lens& lens = reference_.lens;
  const auto width = static_cast<std::size_t>(reference_.maxSlitLength());
  const double nan = std::numeric_limits<double>::quiet_NaN();
  // A centre lies in its task's region, or up to a profile's half window beyond it.
  const double reach = 0.5 * reference_.region_width + profileParams(CV_16U).half_window + 1.0;
  std::vector<std::vector<Eigen::Vector3d>> ideal;  // per slit and row: ideal u, v and u_inf
  for (const ReferenceSlit& slit : reference_.slits) {
    ideal.emplace_back();
    for (std::size_t k = 0; k < slit.u.size(); ++k) {
      const Eigen::Vector2d q =
          std::isfinite(slit.u[k]) ? reference_.idealPoint(slit, k) : Eigen::Vector2d(nan, nan);
      ideal.back().emplace_back(q.x(), q.y(), k < slit.u_inf.size() ? slit.u_inf[k] : nan);
    }
  }
  for (Task& t : tasks_) {
    const std::vector<Eigen::Vector3d>& slit = ideal[t.cell / width];
    const std::size_t k = t.cell % width;
    // The slit's slope by the rows next to this one that have a point.
    const std::size_t a = k > 0 && std::isfinite(slit[k - 1].x()) ? k - 1 : k;
    const std::size_t b = k + 1 < slit.size() && std::isfinite(slit[k + 1].x()) ? k + 1 : k;
    const Eigen::Vector3d slope =
        b > a ? Eigen::Vector3d((slit[b] - slit[a]) / (slit[b].y() - slit[a].y()))
              : Eigen::Vector3d::Zero();
    IdealTask it;
    it.cubic = idealCubic(lens, t.u, t.row, reach);
    it.inverse_reach = 1.0 / reach;
    it.u = slit[k].x(), it.v = slit[k].y(), it.u_inf = slit[k].z();
    it.du_dv = slope.x(), it.du_inf_dv = std::isfinite(slope.z()) ? slope.z() : 0.0;
    t.lens = static_cast<std::uint32_t>(ideal_tasks_.size());
    ideal_tasks_.push_back(it);
    PointRDM& p = blank_[t.cell];  // the cell's reference point in the ideal image
    p.u = static_cast<float>(it.u);
    p.v = static_cast<float>(it.v);
  }
}

bool Extractor::finishIdeal(const Task& t, double centre, PointRDM* p) const {
  const IdealTask& it = ideal_tasks_[t.lens];
  const double s = (centre - t.u) * it.inverse_reach;
  const Eigen::Vector2d q =
      it.cubic.col(0) + s * (it.cubic.col(1) + s * (it.cubic.col(2) + s * it.cubic.col(3)));
  // The reference slit at the centre's ideal row.
  const double dv = q.y() - it.v;
  if (!(std::abs(dv) <= kMaxIdealRowShift)) return false;
  const double u = it.u + dv * it.du_dv;
  p->u = static_cast<float>(u);
  p->v = static_cast<float>(q.y());
  p->dk = static_cast<float>(q.x() - u);
  const double u_inf = it.u_inf + dv * it.du_inf_dv;
  if (!std::isfinite(u_inf) || !reference_.scale.valid()) return true;
  const MetricScale& scale = reference_.scale;
  const double depth = scale.disparity_constant / (q.x() - u_inf);
  if (!(depth > 0)) return true;
  const double depth_per_px = depth / scale.f;
  p->x = static_cast<float>((q.x() - scale.cx) * depth_per_px);
  p->y = static_cast<float>((q.y() - scale.cy) * depth_per_px);
  p->z = static_cast<float>(depth);
  return true;
}

bool Extractor::finish(const cv::Mat& image, const Task& t, double centre, PointRDM* p) const {
  // The image spans columns -0.5 to cols - 0.5 (pixel centres at whole numbers).
  if (!(centre > -0.5 && centre < image.cols - 0.5)) return false;
  if (!ideal_tasks_.empty()) return finishIdeal(t, centre, p);
  p->dk = static_cast<float>(centre - t.u);
  if (!std::isfinite(t.u_inf)) return true;
  const MetricScale& scale = reference_.scale;
  const double depth = scale.disparity_constant / (centre - t.u_inf);
  if (!(depth > 0)) return true;
  const double depth_per_px = depth / scale.f;
  p->x = static_cast<float>((centre - scale.cx) * depth_per_px);
  p->y = static_cast<float>((t.row - scale.cy) * depth_per_px);
  p->z = static_cast<float>(depth);
  return true;
}

template <typename T>
void Extractor::measureAll(const cv::Mat& image, const ProfileParams& params,
                           pcl::PointCloud<PointRDM>& cloud, ExtractionStats& stats) const {
  // First every row's profile, top to bottom (the image is read once, in order); then each slit's
  // points in order along it, so that the columns measured across the stripe for one point serve
  // the next (SlitColumns).
  if (tasks_.empty()) return;
  thread_local std::vector<double> centres;
  centres.assign(tasks_.size(), std::numeric_limits<double>::quiet_NaN());
  constexpr std::size_t kBatch = 8;  // regions measured per call
  RowPrefetch prefetch(image, tasks_.front().row, tasks_.back().row);
  PeakRegion<T> regions[kBatch];
  Peak peaks[kBatch];
  bool found[kBatch];
  for (std::size_t begin = 0; begin < tasks_.size(); begin += kBatch) {
    const std::size_t n = std::min(kBatch, tasks_.size() - begin);
    const Task* tasks = tasks_.data() + begin;
    for (std::size_t i = 0; i < n; ++i)
      regions[i] = {image.ptr<T>(tasks[i].row), tasks[i].first, tasks[i].last};
    prefetch.upTo(tasks[0].row);
    measurePeaks(regions, n, image.cols, params, peaks, found);
    for (std::size_t i = 0; i < n; ++i)
      if (found[i]) centres[begin + i] = peaks[i].centre;
  }
  PointRDM* points = cloud.points.data();
  const auto width = static_cast<std::uint32_t>(cloud.width);
  for (std::size_t begin = 0; begin < along_slits_.size();) {
    const std::uint32_t slit = tasks_[along_slits_[begin]].cell / width;
    std::size_t end = begin + 1;
    while (end < along_slits_.size() && tasks_[along_slits_[end]].cell / width == slit) ++end;
    if (config_.across_stripe) acrossSlit<T>(image, params, begin, end, centres.data());
    dropStrays(begin, end, centres.data());
    for (std::size_t k = begin; k < end; ++k) {
      const Task& t = tasks_[along_slits_[k]];
      const double centre = centres[along_slits_[k]];
      if (std::isfinite(centre) && finish(image, t, centre, &points[t.cell])) ++stats.valid;
    }
    begin = end;
  }
}

void Extractor::dropStrays(std::size_t begin, std::size_t end, double* centres) const {
  if (config_.stray_run == 0) return;
  thread_local std::vector<detail::SlitSample> samples;
  samples.resize(end - begin);
  for (std::size_t k = begin; k < end; ++k) {
    const Task& t = tasks_[along_slits_[k]];
    samples[k - begin] = {t.row, centres[along_slits_[k]] - t.u};
  }
  if (detail::dropStrayRuns(samples, config_.stray_run, config_.stray_step) == 0) return;
  for (std::size_t k = begin; k < end; ++k)
    if (!std::isfinite(samples[k - begin].dk))
      centres[along_slits_[k]] = std::numeric_limits<double>::quiet_NaN();
}

template <typename T>
void Extractor::acrossSlit(const cv::Mat& image, const ProfileParams& params, std::size_t begin,
                           std::size_t end, double* centres) const {
  AcrossStripe across;  // the row's tests, applied to the columns' profiles
  across.min_contrast = params.min_contrast;
  across.fit_threshold = params.fit_threshold;
  across.max_move = params.half_window;
  thread_local SlitColumns columns;
  columns.clear(across);
  for (std::size_t k = begin; k < end; ++k) {
    const Task& t = tasks_[along_slits_[k]];
    if (std::isfinite(centres[along_slits_[k]]))
      columns.plan(t.row, centres[along_slits_[k]], t.slope, t.across_half_rows);
  }
  columns.measure<T>(image);
  std::size_t planned = 0;
  for (std::size_t k = begin; k < end; ++k)
    if (std::isfinite(centres[along_slits_[k]]))
      columns.centre<T>(image, planned++, &centres[along_slits_[k]]);
}

int Extractor::halfWindow() const {
  return std::max(3, static_cast<int>(std::lround(1.25 * reference_.profile_width)));
}

ProfileParams Extractor::profileParams(int depth) const {
  const double full = config_.full_scale > 0      ? config_.full_scale
                      : reference_.full_scale > 0 ? reference_.full_scale
                                                  : (depth == CV_8U ? 255.0 : 65535.0);
  ProfileParams params;
  params.estimator = config_.estimator;
  params.min_contrast = config_.min_contrast * full;
  params.saturation = full;
  params.max_saturated = config_.max_saturated;
  params.min_width = config_.min_width;
  params.max_width = config_.max_width_factor * reference_.profile_width;
  params.half_window = halfWindow();
  params.window_sigma = reference_.profile_width / 2.3548;  // FWHM to sigma
  return params;
}

ExtractionStats Extractor::extract(const cv::Mat& image, pcl::PointCloud<PointRDM>& cloud) const {
  reference_.checkImage(image, "image");
  const ProfileParams params = profileParams(image.depth());
  cloud.width = static_cast<std::uint32_t>(reference_.maxSlitLength());
  cloud.height = static_cast<std::uint32_t>(reference_.slits.size());
  cloud.is_dense = false;
  cloud.points = blank_;
  ExtractionStats stats;
  stats.reference_points = tasks_.size();
  if (image.depth() == CV_8U)
    measureAll<uint8_t>(image, params, cloud, stats);
  else
    measureAll<uint16_t>(image, params, cloud, stats);
  return stats;
}

pcl::PointCloud<PointRDM>::Ptr Extractor::extract(const cv::Mat& image, std::uint64_t stamp_us,
                                                  std::uint32_t seq) const {
  auto cloud = pcl::make_shared<pcl::PointCloud<PointRDM>>();
  extract(image, *cloud);
  cloud->header.stamp = stamp_us;
  cloud->header.seq = seq;
  cloud->header.frame_id = config_.frame_id;
  return cloud;
}

}  // namespace multislit
