#include "draw.h"

#include <opencv2/imgproc.hpp>

namespace multislit::apps {

void drawText(cv::Mat& img, const std::string& s, cv::Point at, double scale,
              const cv::Scalar& colour) {
  cv::putText(img, s, at, cv::FONT_HERSHEY_SIMPLEX, scale, colour, 1, cv::LINE_AA);
}

void drawCentredText(cv::Mat& img, const std::string& s, cv::Point at, double scale) {
  int base = 0;
  at.x -= cv::getTextSize(s, cv::FONT_HERSHEY_SIMPLEX, scale, 1, &base).width / 2;
  drawText(img, s, at, scale);
}

}  // namespace multislit::apps
