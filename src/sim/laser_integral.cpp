#include "laser_integral.h"

#include "parallel_rows.h"

#include <algorithm>
#include <cmath>

namespace multislit {
namespace {

// The sheet over one pixel, linear in the pixel's position (du, dv) in [-1/2, 1/2]^2: its offset
// offset + gu du + gv dv [rad], the position along the slit t + tu du + tv dv, the radiance at
// the sheet's centre and the surface's factor on the sheet's width.
struct LinearSheet {
  double offset, gu, gv, t, tu, tv, radiance, width;

  double offsetSpread() const { return 0.5 * (std::abs(gu) + std::abs(gv)); }
  double tSpread() const { return 0.5 * (std::abs(tu) + std::abs(tv)); }
};

// Whether the sheet is linear over pixel (r, c), into `sheet`: the pixel and its four neighbours
// on the same surface and slit, each lit or beyond the slit's end (|t| > t_max: no light there,
// the surface goes on), the offset without curvature. Its radiance is the centre's, or its lit
// neighbours' mean where the centre lies beyond the end; 0 when none of the five is lit.
bool linearSheet(const CentreSamples& centre, int r, int c, double t_max, double sigma,
                 LinearSheet& sheet) {
  if (r < 1 || c < 1 || r >= centre.height - 1 || c >= centre.width - 1) return false;
  const Shader::Sample& m = centre.at(r, c);
  const Shader::Sample &left = centre.at(r, c - 1), &right = centre.at(r, c + 1),
                       &up = centre.at(r - 1, c), &down = centre.at(r + 1, c);
  double lit_sum = 0;
  int lit = 0;
  for (const Shader::Sample* q : {&left, &right, &up, &down, &m}) {
    if (q->object != m.object || q->slit != m.slit) return false;
    if (q->radiance > 0)
      lit_sum += q->radiance, ++lit;
    else if (!(std::abs(q->t) > t_max))
      return false;  // a shadow, or a surface facing away
  }
  if (!(std::abs(left.offset + right.offset - 2 * m.offset) < 0.02 * sigma &&
        std::abs(up.offset + down.offset - 2 * m.offset) < 0.02 * sigma))
    return false;
  sheet.offset = m.offset;
  sheet.gu = 0.5 * (right.offset - left.offset);
  sheet.gv = 0.5 * (down.offset - up.offset);
  sheet.t = m.t;
  sheet.tu = 0.5 * (static_cast<double>(right.t) - left.t);
  sheet.tv = 0.5 * (static_cast<double>(down.t) - up.t);
  sheet.radiance = m.radiance > 0 ? m.radiance : lit > 0 ? lit_sum / lit : 0.0;
  sheet.width = m.width;
  return true;
}

// The mean of the sheet's profile (sigma `profile`) over the part of the pixel within the slit
// (|t| <= t_max), at n x n positions of the linear model.
double meanWithinSlit(const LinearSheet& sheet, double t_max, double profile, int n) {
  const double k = -0.5 / (profile * profile);
  double sum = 0;
  for (int j = 0; j < n; ++j) {
    const double dv = (j + 0.5) / n - 0.5;
    for (int i = 0; i < n; ++i) {
      const double du = (i + 0.5) / n - 0.5;
      if (std::abs(sheet.t + sheet.tu * du + sheet.tv * dv) > t_max) continue;
      const double offset = sheet.offset + sheet.gu * du + sheet.gv * dv;
      sum += std::exp(k * offset * offset);
    }
  }
  return sum / (n * n);
}

// The laser's light on pixel (r, c), near a sheet.
double pixelLaser(const Shader& shader, const CentreSamples& centre, int r, int c, double reach) {
  const int n = shader.render.supersample;
  const double t_max = shader.geometry.slitTMax();
  const Shader::Sample& m = centre.at(r, c);
  LinearSheet sheet{};
  if (linearSheet(centre, r, c, t_max, shader.sigma, sheet)) {
    const double profile = shader.sigma * sheet.width;
    // The offset nearest the sheet on the pixel, and the end of the slit.
    if (std::abs(sheet.offset) - sheet.offsetSpread() > kSheetSigmas * profile ||
        std::abs(sheet.t) - sheet.tSpread() > t_max)
      return 0;
    if (std::abs(sheet.t) + sheet.tSpread() <= t_max)
      return sheet.radiance * pixelMeanOfGaussian(sheet.offset, sheet.gu, sheet.gv, profile);
    if (sheet.radiance > 0) return sheet.radiance * meanWithinSlit(sheet, t_max, profile, n);
  }
  return tracedPixelMean(shader, m, c, r, reach, n);
}

}  // namespace

double tracedPixelMean(const Shader& shader, const Shader::Sample& centre, int c, int r,
                       double reach, int n) {
  double sum = 0;
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i)
      sum += shader.laser(shader.trace(c - 0.5 + (i + 0.5) / n, r - 0.5 + (j + 0.5) / n, reach,
                                       centre.object, centre.albedo));
  return sum / (n * n);
}

double sheetReach(const Scene& scene, double sigma, double pixel) {
  double widest = scene.stripeWidth(0);
  for (std::size_t k = 0; k < scene.objects.size(); ++k)
    widest = std::max(widest, scene.stripeWidth(static_cast<int>(k) + 1));
  return kSheetSigmas * sigma * widest + 2 * pixel;
}

void integrateLaser(const Shader& shader, const CentreSamples& centre, double reach,
                    cv::Mat& laser) {
  laser.create(centre.height, centre.width, CV_32F);  // every pixel is written
  parallelRows(centre.height, [&](const cv::Range& rows) {
    for (int r = rows.start; r < rows.end; ++r) {
      float* out = laser.ptr<float>(r);
      const uchar* near = centre.near.ptr<uchar>(r);
      for (int c = 0; c < centre.width; ++c)
        out[c] = near[c] ? static_cast<float>(pixelLaser(shader, centre, r, c, reach)) : 0.0f;
    }
  });
}

}  // namespace multislit
