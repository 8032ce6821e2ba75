// What the figures of the commands (plot.cpp, walk_figures.cpp) draw alike: ink, grid and text.
#pragma once

#include <opencv2/core.hpp>

#include <string>

namespace multislit::apps {

inline const cv::Scalar kInk(40, 40, 40);      ///< text and axes (BGR)
inline const cv::Scalar kGrid(228, 228, 228);  ///< grid lines (BGR)

/// `s` in OpenCV's simplex font, anti-aliased, its baseline starting at `at`.
void drawText(cv::Mat& img, const std::string& s, cv::Point at, double scale = 0.5,
              const cv::Scalar& colour = kInk);

/// drawText() centred on `at`.x.
void drawCentredText(cv::Mat& img, const std::string& s, cv::Point at, double scale = 0.5);

}  // namespace multislit::apps
