// Line charts for studies (accuracy against wall time, quantities over (p,q)): VTK's 2-D charts drawn into
// the headless window, written as PNG. Axes carry their units in the labels; a legend names each curve.
#pragma once

#include "pmfrag/render/headless.hpp"

#include <string>
#include <vector>

namespace pmfrag::render {

struct Series {
  std::string name;
  std::vector<double> x, y;
  bool markers = false;  ///< points only, no line between them (counts, separate cases)
  int colour = -1;       ///< index into the palette (-1: the series' own position), to pair data with its fit
};

struct ChartSpec {
  std::string title, x_label, y_label;
  bool log_x = false, log_y = false;
  std::vector<Series> series;
  bool integer_y = false;  ///< a count: ticks at whole numbers only (linear y)
};

/// Renders `chart` at w x h pixels into `png_path` (written to a temporary name and renamed). Points with a
/// non-positive coordinate on a log axis are left out.
void render_chart_png(HeadlessWindow& window, const ChartSpec& chart, int w, int h, const std::string& png_path);

/// A value over an integer grid (e.g. E over (p,q), the paper's Fig. 3): cell (x0 + i, y0 + j) holds
/// values[j * nx + i]; NaN cells (no value, e.g. q <= p) are drawn white.
struct HeatmapSpec {
  std::string title, x_label, y_label, value_label;
  int x0 = 0, y0 = 0, nx = 0, ny = 0;
  std::vector<double> values;
};

/// Renders `map` at w x h pixels into `png_path`, with a colour legend. Throws std::invalid_argument if the
/// values do not fill the grid.
void render_heatmap_png(HeadlessWindow& window, const HeatmapSpec& map, int w, int h, const std::string& png_path);

}  // namespace pmfrag::render
