#include "pmfrag/render/charts.hpp"

#include "png.hpp"
#include "ramp.hpp"

#include <vtkAxis.h>
#include <vtkChartHistogram2D.h>
#include <vtkChartLegend.h>
#include <vtkColorLegend.h>
#include <vtkColorTransferFunction.h>
#include <vtkImageData.h>
#include <vtkChartXY.h>
#include <vtkContextScene.h>
#include <vtkContextView.h>
#include <vtkDoubleArray.h>
#include <vtkGenericOpenGLRenderWindow.h>
#include <vtkNew.h>
#include <vtkPen.h>
#include <vtkPlot.h>
#include <vtkPlotPoints.h>
#include <vtkRenderer.h>
#include <vtkSmartPointer.h>
#include <vtkStringArray.h>
#include <vtkTable.h>
#include <vtkTextProperty.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <string>

namespace pmfrag::render {

namespace {

// A white w x h 2-D scene on the headless window, for one chart.
vtkSmartPointer<vtkContextView> open_canvas(HeadlessWindow& window, int w, int h) {
  window.window()->SetSize(w, h);
  auto view = vtkSmartPointer<vtkContextView>::New();
  view->SetRenderWindow(window.window());
  view->GetRenderer()->SetBackground(1.0, 1.0, 1.0);
  return view;
}

void style_axis(vtkAxis* axis, const std::string& title) {
  axis->SetTitle(title);
  axis->GetTitleProperties()->SetFontSize(16);
  axis->GetLabelProperties()->SetFontSize(14);
}

// Renders the canvas into png_path and takes it off the window (the window serves the next chart).
void write_canvas(HeadlessWindow& window, vtkContextView* view, const std::string& png_path) {
  window.window()->Render();
  detail::write_window_png(window.window(), png_path, 4);
  view->GetRenderer()->RemoveAllViewProps();
  window.window()->RemoveRenderer(view->GetRenderer());
}

}  // namespace

void render_chart_png(HeadlessWindow& window, const ChartSpec& spec, int w, int h, const std::string& png_path) {
  // Okabe-Ito: distinguishable with the common colour-vision deficiencies, as in the particle frames.
  static constexpr std::array<std::array<unsigned char, 3>, 7> palette{{{0, 114, 178},
                                                                        {213, 94, 0},
                                                                        {0, 158, 115},
                                                                        {204, 121, 167},
                                                                        {230, 159, 0},
                                                                        {86, 180, 233},
                                                                        {0, 0, 0}}};
  const auto view = open_canvas(window, w, h);
  vtkNew<vtkChartXY> chart;
  view->GetScene()->AddItem(chart);
  chart->SetTitle(spec.title);
  chart->GetTitleProperties()->SetFontSize(18);
  chart->SetShowLegend(true);
  chart->GetLegend()->GetLabelProperties()->SetFontSize(14);
  vtkAxis* x = chart->GetAxis(vtkAxis::BOTTOM);
  vtkAxis* y = chart->GetAxis(vtkAxis::LEFT);
  style_axis(x, spec.x_label);
  style_axis(y, spec.y_label);
  // VTK 9.1's log axes draw no curves here (only the legend), so a log axis plots log10 of the values on a
  // linear axis with ticks at the decades, labelled with the values.
  auto coord = [](bool log, double v) { return log ? std::log10(v) : v; };
  double lo[2] = {INFINITY, INFINITY}, hi[2] = {-INFINITY, -INFINITY};
  std::vector<vtkSmartPointer<vtkTable>> keep;
  for (std::size_t s = 0; s < spec.series.size(); ++s) {
    const Series& ser = spec.series[s];
    auto table = vtkSmartPointer<vtkTable>::New();
    vtkNew<vtkDoubleArray> xs, ys;
    xs->SetName("x");
    ys->SetName(ser.name.c_str());
    for (std::size_t k = 0; k < ser.x.size() && k < ser.y.size(); ++k) {
      const double a = ser.x[k], b = ser.y[k];
      if (!std::isfinite(a) || !std::isfinite(b) || (spec.log_x && a <= 0) || (spec.log_y && b <= 0)) continue;
      const double u = coord(spec.log_x, a), v = coord(spec.log_y, b);
      xs->InsertNextValue(u);
      ys->InsertNextValue(v);
      lo[0] = std::min(lo[0], u), hi[0] = std::max(hi[0], u), lo[1] = std::min(lo[1], v), hi[1] = std::max(hi[1], v);
    }
    if (xs->GetNumberOfTuples() < (ser.markers ? 1 : 2)) continue;  // a curve needs two points
    table->AddColumn(xs);
    table->AddColumn(ys);
    keep.push_back(table);
    vtkPlot* plot = chart->AddPlot(ser.markers ? vtkChart::POINTS : vtkChart::LINE);
    plot->SetInputData(table, 0, 1);
    const auto& c = palette[static_cast<std::size_t>(ser.colour >= 0 ? ser.colour : static_cast<int>(s)) % palette.size()];
    plot->SetColor(c[0], c[1], c[2], 255);
    plot->SetWidth(2.5);
    if (auto* pts = vtkPlotPoints::SafeDownCast(plot)) {
      pts->SetMarkerStyle(vtkPlotPoints::CIRCLE);
      pts->SetMarkerSize(9.0);
    }
  }
  vtkAxis* axes[2] = {x, y};
  const bool logs[2] = {spec.log_x, spec.log_y};
  for (int a = 0; a < 2; ++a) {
    if (!(hi[a] >= lo[a])) continue;
    if (!logs[a]) {
      // Linear: a margin of 6 % so that no point sits on the frame (or under the title and legend, 12 % on y).
      const double span = hi[a] > lo[a] ? hi[a] - lo[a] : std::max(1.0, std::fabs(hi[a]));
      double from = lo[a] - 0.06 * span, to = hi[a] + (a == 1 ? 0.12 : 0.06) * span;
      if (a == 1 && spec.integer_y) {
        // whole-number ticks, about eight of them
        const double step = std::max(1.0, std::ceil((to - from) / 8.0));
        from = std::floor(from), to = std::ceil(to);
        vtkNew<vtkDoubleArray> ticks;
        vtkNew<vtkStringArray> labels;
        for (double t = std::ceil(from / step) * step; t <= to; t += step) {
          ticks->InsertNextValue(t);
          labels->InsertNextValue(std::to_string(static_cast<long>(t)));
        }
        axes[a]->SetCustomTickPositions(ticks, labels);
      }
      axes[a]->SetBehavior(vtkAxis::FIXED);
      axes[a]->SetRange(from, to);
      continue;
    }
    // whole decades, with room so that no point sits on the frame
    const double from = std::floor(lo[a] - 0.03), to = std::ceil(hi[a] + 0.03);
    vtkNew<vtkDoubleArray> ticks;
    vtkNew<vtkStringArray> labels;
    for (double d = from; d <= to + 0.5; d += 1.0) {
      ticks->InsertNextValue(d);
      char b[16];
      std::snprintf(b, sizeof b, "1e%d", static_cast<int>(d));
      labels->InsertNextValue(b);
    }
    axes[a]->SetCustomTickPositions(ticks, labels);
    axes[a]->SetBehavior(vtkAxis::FIXED);
    axes[a]->SetRange(from, to);
  }
  write_canvas(window, view, png_path);
}

void render_heatmap_png(HeadlessWindow& window, const HeatmapSpec& map, int w, int h, const std::string& png_path) {
  if (map.nx < 1 || map.ny < 1 || map.values.size() != static_cast<std::size_t>(map.nx) * static_cast<std::size_t>(map.ny))
    throw std::invalid_argument("heat map: " + std::to_string(map.values.size()) + " values for a " +
                                std::to_string(map.nx) + " x " + std::to_string(map.ny) + " grid");
  const auto view = open_canvas(window, w, h);
  vtkNew<vtkChartHistogram2D> chart;
  view->GetScene()->AddItem(chart);
  // Cell centres on the integers: the image's points are the cells.
  vtkNew<vtkImageData> image;
  image->SetExtent(0, map.nx - 1, 0, map.ny - 1, 0, 0);
  image->SetOrigin(map.x0, map.y0, 0.0);
  image->SetSpacing(1.0, 1.0, 1.0);
  image->AllocateScalars(VTK_DOUBLE, 1);
  double lo = INFINITY, hi = -INFINITY;
  for (int j = 0; j < map.ny; ++j)
    for (int i = 0; i < map.nx; ++i) {
      const double v = map.values[static_cast<std::size_t>(j) * static_cast<std::size_t>(map.nx) + static_cast<std::size_t>(i)];
      *static_cast<double*>(image->GetScalarPointer(i, j, 0)) = v;
      if (std::isfinite(v)) lo = std::min(lo, v), hi = std::max(hi, v);
    }
  if (!(hi >= lo)) lo = 0.0, hi = 1.0;
  chart->SetInputData(image);
  // The same ramp as the particle frames; empty cells white.
  vtkNew<vtkColorTransferFunction> ramp;
  const auto& anchors = detail::ramp_anchors;
  for (int k = 0; k < 5; ++k) ramp->AddRGBPoint(lo + (hi - lo) * k / 4.0, anchors[k][0], anchors[k][1], anchors[k][2]);
  ramp->SetNanColor(1.0, 1.0, 1.0);
  chart->SetTransferFunction(ramp);
  chart->SetTitle(map.title);
  chart->GetTitleProperties()->SetFontSize(18);
  style_axis(chart->GetAxis(vtkAxis::BOTTOM), map.x_label);
  style_axis(chart->GetAxis(vtkAxis::LEFT), map.y_label);
  chart->GetAxis(vtkAxis::BOTTOM)->SetBehavior(vtkAxis::FIXED);
  chart->GetAxis(vtkAxis::LEFT)->SetBehavior(vtkAxis::FIXED);
  chart->GetAxis(vtkAxis::BOTTOM)->SetRange(map.x0 - 0.5, map.x0 + map.nx - 0.5);
  chart->GetAxis(vtkAxis::LEFT)->SetRange(map.y0 - 0.5, map.y0 + map.ny - 0.5);
  if (auto* legend = vtkColorLegend::SafeDownCast(chart->GetLegend())) {
    legend->SetTitle(map.value_label);
    legend->GetLabelProperties()->SetFontSize(14);
  }
  write_canvas(window, view, png_path);
}

}  // namespace pmfrag::render
