#include "pmfrag/render/charts.hpp"

#include "png.hpp"

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
#include <vtkStringArray.h>
#include <vtkTable.h>
#include <vtkTextProperty.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <string>

namespace pmfrag::render {

void render_chart_png(HeadlessWindow& window, const ChartSpec& spec, int w, int h, const std::string& png_path) {
  // Okabe-Ito: distinguishable with the common colour-vision deficiencies, as in the particle frames.
  static constexpr std::array<std::array<unsigned char, 3>, 7> palette{{{0, 114, 178},
                                                                        {213, 94, 0},
                                                                        {0, 158, 115},
                                                                        {204, 121, 167},
                                                                        {230, 159, 0},
                                                                        {86, 180, 233},
                                                                        {0, 0, 0}}};
  vtkGenericOpenGLRenderWindow* win = window.window();
  win->SetSize(w, h);
  vtkNew<vtkContextView> view;
  view->SetRenderWindow(win);
  view->GetRenderer()->SetBackground(1.0, 1.0, 1.0);
  vtkNew<vtkChartXY> chart;
  view->GetScene()->AddItem(chart);
  chart->SetTitle(spec.title);
  chart->GetTitleProperties()->SetFontSize(18);
  chart->SetShowLegend(true);
  chart->GetLegend()->GetLabelProperties()->SetFontSize(14);
  vtkAxis* x = chart->GetAxis(vtkAxis::BOTTOM);
  vtkAxis* y = chart->GetAxis(vtkAxis::LEFT);
  x->SetTitle(spec.x_label);
  y->SetTitle(spec.y_label);
  for (vtkAxis* a : {x, y}) {
    a->GetTitleProperties()->SetFontSize(16);
    a->GetLabelProperties()->SetFontSize(14);
  }
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
    if (xs->GetNumberOfTuples() < 2) continue;  // a curve needs two points
    table->AddColumn(xs);
    table->AddColumn(ys);
    keep.push_back(table);
    vtkPlot* plot = chart->AddPlot(vtkChart::LINE);
    plot->SetInputData(table, 0, 1);
    const auto& c = palette[s % palette.size()];
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
    if (!logs[a] || !(hi[a] >= lo[a])) continue;
    const double from = std::floor(lo[a]), to = std::ceil(hi[a]);
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
  win->Render();
  detail::write_window_png(win, png_path, 4);
  view->GetRenderer()->RemoveAllViewProps();
  win->RemoveRenderer(view->GetRenderer());
}

void render_heatmap_png(HeadlessWindow& window, const HeatmapSpec& map, int w, int h, const std::string& png_path) {
  if (map.nx < 1 || map.ny < 1 || map.values.size() != static_cast<std::size_t>(map.nx) * static_cast<std::size_t>(map.ny))
    throw std::invalid_argument("heat map: " + std::to_string(map.values.size()) + " values for a " +
                                std::to_string(map.nx) + " x " + std::to_string(map.ny) + " grid");
  vtkGenericOpenGLRenderWindow* win = window.window();
  win->SetSize(w, h);
  vtkNew<vtkContextView> view;
  view->SetRenderWindow(win);
  view->GetRenderer()->SetBackground(1.0, 1.0, 1.0);
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
  // The same viridis-like ramp as the particle frames; empty cells white.
  vtkNew<vtkColorTransferFunction> ramp;
  const double anchors[5][3] = {{0.267, 0.005, 0.329}, {0.231, 0.322, 0.545}, {0.129, 0.569, 0.549},
                                {0.369, 0.788, 0.384}, {0.993, 0.906, 0.144}};
  for (int k = 0; k < 5; ++k) ramp->AddRGBPoint(lo + (hi - lo) * k / 4.0, anchors[k][0], anchors[k][1], anchors[k][2]);
  ramp->SetNanColor(1.0, 1.0, 1.0);
  chart->SetTransferFunction(ramp);
  chart->SetTitle(map.title);
  chart->GetTitleProperties()->SetFontSize(18);
  chart->GetAxis(vtkAxis::BOTTOM)->SetTitle(map.x_label);
  chart->GetAxis(vtkAxis::LEFT)->SetTitle(map.y_label);
  for (int a : {vtkAxis::BOTTOM, vtkAxis::LEFT}) {
    vtkAxis* ax = chart->GetAxis(a);
    ax->GetTitleProperties()->SetFontSize(16);
    ax->GetLabelProperties()->SetFontSize(14);
    ax->SetBehavior(vtkAxis::FIXED);
  }
  chart->GetAxis(vtkAxis::BOTTOM)->SetRange(map.x0 - 0.5, map.x0 + map.nx - 0.5);
  chart->GetAxis(vtkAxis::LEFT)->SetRange(map.y0 - 0.5, map.y0 + map.ny - 0.5);
  if (auto* legend = vtkColorLegend::SafeDownCast(chart->GetLegend())) {
    legend->SetTitle(map.value_label);
    legend->GetLabelProperties()->SetFontSize(14);
  }
  win->Render();
  detail::write_window_png(win, png_path, 4);
  view->GetRenderer()->RemoveAllViewProps();
  win->RemoveRenderer(view->GetRenderer());
}

}  // namespace pmfrag::render
