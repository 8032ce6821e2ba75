// The samples of every pixel centre (private to the simulator): the first step of a render.
#pragma once

#include "shader.h"

#include <opencv2/core/mat.hpp>

#include <vector>

namespace multislit {

/// The samples of the pixel centres, row-major, with the light that does not depend on the sheets.
struct CentreSamples {
  int width = 0, height = 0;
  std::vector<Shader::Sample> samples;
  cv::Mat ambient;  ///< ambient light and glare per pixel, CV_32F [FS]
  cv::Mat near;     ///< CV_8U: 1 where a sheet may light the pixel

  const Shader::Sample& at(int r, int c) const {
    return samples[static_cast<std::size_t>(r) * width + c];
  }
};

/// Every pixel centre into `centre`: its surface, ambient light and where the laser sheets are
/// (within `reach` [rad] of a sheet; `pixel` is one pixel's angle [rad]). RenderMethod::Culled
/// traces the objects only on the pixels their bounds cover and the floor elsewhere in closed
/// form; Exhaustive traces every ray against every object. Both give the same image to rounding
/// (render_methods_test). The floor's albedo is shader.floor_albedo's (required).
void traceCentres(const Shader& shader, double reach, double pixel, RenderMethod method,
                  CentreSamples& centre);

/// The floor the camera sees, within 5 m (the rays of every 8th pixel): where the floor's texture
/// is worth tabulating.
Eigen::AlignedBox2d floorInView(const Shader& shader);

}  // namespace multislit
