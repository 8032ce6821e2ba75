#include "plot.h"

#include "common.h"
#include "draw.h"

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace multislit::apps {
namespace {

constexpr int kWidth = 900, kHeight = 520, kLeft = 80, kRight = 30, kTop = 70, kBottom = 70;

cv::Scalar bgr(unsigned rgb) {
  return cv::Scalar(rgb & 0xff, (rgb >> 8) & 0xff, (rgb >> 16) & 0xff);
}

// A "nice" axis maximum and tick step for values up to `top`.
std::pair<double, double> axis(double top) {
  if (!(top > 0)) top = 1;
  const double raw = top / 5, mag = std::pow(10, std::floor(std::log10(raw)));
  const double step = raw / mag < 2 ? 2 * mag : raw / mag < 5 ? 5 * mag : 10 * mag;
  return {std::ceil(top / step) * step, step};
}

cv::Mat frame(const std::string& title, const std::string& y_label, double y_max, double step) {
  cv::Mat img(kHeight, kWidth, CV_8UC3, cv::Scalar(255, 255, 255));
  const int h = kHeight - kTop - kBottom;
  for (double y = 0; y <= y_max + 1e-9; y += step) {
    const int py = kTop + h - static_cast<int>(std::lround(h * y / y_max));
    cv::line(img, {kLeft, py}, {kWidth - kRight, py}, kGrid, 1);
    char label[32];
    std::snprintf(label, sizeof label, step < 0.1 ? "%.2f" : step < 1 ? "%.1f" : "%.0f", y);
    drawText(img, label, {8, py + 5});
  }
  cv::line(img, {kLeft, kTop}, {kLeft, kTop + h}, kInk, 1);
  cv::line(img, {kLeft, kTop + h}, {kWidth - kRight, kTop + h}, kInk, 1);
  drawCentredText(img, title, {kWidth / 2, 28}, 0.6);
  drawText(img, y_label, {8, kTop - 18}, 0.45);
  return img;
}

}  // namespace

void drawBarChart(const std::string& path, const std::string& title, const std::string& y_label,
                  const std::vector<std::string>& labels, const std::vector<double>& values,
                  const std::vector<double>& errors) {
  double top = 0;
  for (std::size_t i = 0; i < values.size(); ++i)
    top = std::max(top, values[i] + (i < errors.size() ? errors[i] : 0.0));
  // Named variables, not a structured binding: C++17 lambdas (py) cannot capture one (clang).
  const std::pair<double, double> y_axis = axis(1.15 * top);
  const double y_max = y_axis.first, step = y_axis.second;
  cv::Mat img = frame(title, y_label, y_max, step);
  const int h = kHeight - kTop - kBottom, w = kWidth - kLeft - kRight;
  const int n = static_cast<int>(values.size()), slot = n > 0 ? w / n : w;
  auto py = [&](double y) { return kTop + h - static_cast<int>(std::lround(h * y / y_max)); };
  for (int i = 0; i < n; ++i) {
    const int x0 = kLeft + i * slot + slot / 5, x1 = kLeft + (i + 1) * slot - slot / 5;
    const double v = values[static_cast<std::size_t>(i)];
    cv::rectangle(img, {x0, py(v)}, {x1, kTop + h}, bgr(0x3b75af), cv::FILLED);
    if (static_cast<std::size_t>(i) < errors.size()) {
      const double e = errors[static_cast<std::size_t>(i)];
      const int xc = (x0 + x1) / 2;
      cv::line(img, {xc, py(v - e)}, {xc, py(v + e)}, kInk, 1);
      cv::line(img, {xc - 6, py(v + e)}, {xc + 6, py(v + e)}, kInk, 1);
      cv::line(img, {xc - 6, py(v - e)}, {xc + 6, py(v - e)}, kInk, 1);
    }
    char value[32];
    std::snprintf(value, sizeof value, "%.3f", v);
    drawCentredText(img, value, {(x0 + x1) / 2, py(v) - 8}, 0.45);
    drawCentredText(img, labels[static_cast<std::size_t>(i)], {(x0 + x1) / 2, kTop + h + 25}, 0.5);
  }
  writeImage(path, img);
}

void drawLinePlot(const std::string& path, const std::string& title, const std::string& x_label,
                  const std::string& y_label, const std::vector<Series>& series) {
  double top = 0;
  std::size_t n = 0;
  for (const Series& s : series) {
    for (double v : s.values) top = std::max(top, v);
    n = std::max(n, s.values.size());
  }
  const std::pair<double, double> y_axis = axis(1.1 * top);
  const double y_max = y_axis.first, step = y_axis.second;
  cv::Mat img = frame(title, y_label, y_max, step);
  const int h = kHeight - kTop - kBottom, w = kWidth - kLeft - kRight;
  auto px = [&](std::size_t i) {
    return kLeft + static_cast<int>(std::lround(w * static_cast<double>(i) /
                                                std::max<double>(1, static_cast<double>(n - 1))));
  };
  auto py = [&](double y) { return kTop + h - static_cast<int>(std::lround(h * y / y_max)); };
  const auto [x_max, x_step] = axis(static_cast<double>(n > 0 ? n - 1 : 1));
  for (double x = 0; x <= static_cast<double>(n) - 1 + 1e-9 && x <= x_max; x += x_step) {
    char label[32];
    std::snprintf(label, sizeof label, "%.0f", x);
    drawCentredText(img, label, {px(static_cast<std::size_t>(x)), kTop + h + 20}, 0.45);
  }
  drawCentredText(img, x_label, {kLeft + w / 2, kTop + h + 50}, 0.5);
  int legend_y = kTop + 15;
  for (const Series& s : series) {
    for (std::size_t i = 1; i < s.values.size(); ++i)
      cv::line(img, {px(i - 1), py(s.values[i - 1])}, {px(i), py(s.values[i])}, bgr(s.colour), 2,
               cv::LINE_AA);
    if (!s.label.empty()) {
      cv::line(img, {kWidth - 230, legend_y - 5}, {kWidth - 200, legend_y - 5}, bgr(s.colour), 3);
      drawText(img, s.label, {kWidth - 192, legend_y});
      legend_y += 20;
    }
  }
  writeImage(path, img);
}

}  // namespace multislit::apps
