// The laser light integrated over each pixel (private to the simulator): the second step of a
// render, after the pixel centres.
#pragma once

#include "pixel_centres.h"
#include "shader.h"

#include "multislit/sim/scene.h"

#include <opencv2/core/mat.hpp>

namespace multislit {

/// Beyond this many of its sigmas from its centre a sheet adds < 4e-5 of its peak.
inline constexpr double kSheetSigmas = 4.5;

/// How far from a sheet's centre [rad] light is traced: kSheetSigmas for the widest sheet on any
/// surface of `scene` (sheets of width `sigma` [rad] before the surface's factor), and two
/// pixels (of `pixel` [rad]) more.
double sheetReach(const Scene& scene, double sigma, double pixel);

/// The laser's light on pixel (c, r) traced at n x n positions of it, within `reach` [rad] of a
/// sheet; `centre` is the pixel centre's sample, whose surface and albedo the rays that meet the
/// same surface take (the floor's grain is many pixels wide).
double tracedPixelMean(const Shader& shader, const Shader::Sample& centre, int c, int r,
                       double reach, int n);

/// The laser's light on each pixel into `laser` (CV_32F, made by create()): 0 where
/// `centre.near` is not set. Where the sheet's offset and the position along the slit are
/// linear over the pixel (one surface and slit on it and its four neighbours, lit except beyond
/// the slit's end), the sheet's Gaussian profile is integrated exactly, or at
/// render.supersample^2 positions of the linear model where the slit's end crosses the pixel;
/// elsewhere (edges, shadows) that many rays are traced, light within `reach` [rad] of a sheet.
void integrateLaser(const Shader& shader, const CentreSamples& centre, double reach,
                    cv::Mat& laser);

}  // namespace multislit
