// Small figures drawn with OpenCV: bar charts and line plots as PNG.
#pragma once

#include <string>
#include <vector>

namespace multislit::apps {

struct Series {
  std::string label;
  std::vector<double> values;
  unsigned colour = 0x2060c0;  ///< 0xRRGGBB
};

/// Bars with their values written on top; y from 0.
void drawBarChart(const std::string& path, const std::string& title, const std::string& y_label,
                  const std::vector<std::string>& labels, const std::vector<double>& values,
                  const std::vector<double>& errors = {});

/// Lines over x = 0, 1, 2 ... (the frame number); y from 0.
void drawLinePlot(const std::string& path, const std::string& title, const std::string& x_label,
                  const std::string& y_label, const std::vector<Series>& series);

}  // namespace multislit::apps
