#include "pmfrag/render/frames.hpp"

#include "png.hpp"
#include "ramp.hpp"

#include <vtkActor.h>
#include <vtkActor2D.h>
#include <vtkCellArray.h>
#include <vtkCellData.h>
#include <vtkUnsignedCharArray.h>
#include <vtkDoubleArray.h>
#include <vtkGenericOpenGLRenderWindow.h>
#include <vtkLookupTable.h>
#include <vtkNew.h>
#include <vtkPointData.h>
#include <vtkPointGaussianMapper.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkPolyDataMapper.h>
#include <vtkProperty.h>
#include <vtkRenderer.h>
#include <vtkRendererCollection.h>
#include <vtkScalarBarActor.h>
#include <vtkTextActor.h>
#include <vtkTextProperty.h>
#include <vtkCamera.h>
#include <vtkCoordinate.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <stdexcept>

namespace pmfrag::render {

namespace {

// Each splat drawn as a flat disc with a darker rim, so touching particles stay distinct (and flat colours
// keep PNGs small).
const char* disc_shader =
    "//VTK::Color::Impl\n"
    "float rr = dot(offsetVCVSOutput.xy, offsetVCVSOutput.xy);\n"
    "if (rr > 1.0) { discard; }\n"
    "if (rr > 0.64) { ambientColor *= 0.6; diffuseColor *= 0.6; }\n";

// 3-D: each splat shaded as the sphere it stands for (a light from the upper left, behind the viewer, and a
// highlight), so the body's faces, edges and the cut read as surfaces rather than flat discs.
const char* sphere_shader =
    "//VTK::Color::Impl\n"
    "float rr = dot(offsetVCVSOutput.xy, offsetVCVSOutput.xy);\n"
    "if (rr > 1.0) { discard; }\n"
    "vec3 nrm = vec3(offsetVCVSOutput.xy, sqrt(1.0 - rr));\n"
    "vec3 lit = normalize(vec3(-0.45, 0.55, 0.70));\n"
    "float lambert = max(dot(nrm, lit), 0.0);\n"
    "float shine = pow(max(dot(nrm, normalize(lit + vec3(0.0, 0.0, 1.0))), 0.0), 48.0);\n"
    "ambientColor = ambientColor * (0.28 + 0.72 * lambert) + vec3(0.28 * shine);\n"
    "diffuseColor = vec3(0.0);\n";

vtkNew<vtkLookupTable> make_lut(const FieldSpec& f) {
  vtkNew<vtkLookupTable> lut;
  if (f.categorical) {
    lut->SetNumberOfTableValues(8);
    const auto& palette = detail::category_palette;
    for (int k = 0; k < 8; ++k) lut->SetTableValue(k, palette[k][0], palette[k][1], palette[k][2], 1.0);
    lut->SetTableRange(0, 7);
    lut->SetNanColor(detail::no_category[0], detail::no_category[1], detail::no_category[2], 1.0);
  } else {
    const auto& anchors = detail::ramp_anchors;
    lut->SetNumberOfTableValues(256);
    for (int k = 0; k < 256; ++k) {
      const double t = k / 255.0 * 4.0;
      const int a = std::min(3, static_cast<int>(t));
      const double w = t - a;
      lut->SetTableValue(k, anchors[a][0] * (1 - w) + anchors[a + 1][0] * w, anchors[a][1] * (1 - w) + anchors[a + 1][1] * w,
                         anchors[a][2] * (1 - w) + anchors[a + 1][2] * w, 1.0);
    }
    lut->SetTableRange(f.min, f.max > f.min ? f.max : f.min + 1.0);
  }
  lut->Build();
  return lut;
}

std::string time_text(double t) {
  char b[64];
  if (t == 0.0)
    std::snprintf(b, sizeof b, "T = 0 s");
  else
    std::snprintf(b, sizeof b, "T = %.4g s", t);
  return b;
}

// Bonds and vectors as one set of coloured lines. In 2-D they are lifted towards the camera so that they draw
// over the discs (which lie at z = 0) instead of fighting them for depth.
vtkSmartPointer<vtkActor> segment_actor(const FramePicture& pic, const View& view) {
  const std::size_t m = pic.segment_kinds.size();
  if (pic.segments.size() != 6 * m) throw std::invalid_argument("render: 6 coordinates per segment expected");
  const double lift = view.three_d ? 0.0 : 1.0;
  vtkNew<vtkPoints> pts;
  pts->SetDataTypeToDouble();
  pts->SetNumberOfPoints(static_cast<vtkIdType>(2 * m));
  vtkNew<vtkCellArray> lines;
  vtkNew<vtkUnsignedCharArray> rgb;
  rgb->SetNumberOfComponents(3);
  rgb->SetNumberOfTuples(static_cast<vtkIdType>(m));
  for (std::size_t k = 0; k < m; ++k) {
    const double* e = &pic.segments[6 * k];
    const auto a = static_cast<vtkIdType>(2 * k);
    pts->SetPoint(a, e[0], e[1], e[2] + lift);
    pts->SetPoint(a + 1, e[3], e[4], e[5] + lift);
    const vtkIdType ids[2] = {a, a + 1};
    lines->InsertNextCell(2, ids);
    const unsigned char grey[3] = {90, 90, 90}, red[3] = {213, 30, 30}, black[3] = {0, 0, 0};
    const unsigned char* c = pic.segment_kinds[k] == SegmentKind::intact_bond   ? grey
                             : pic.segment_kinds[k] == SegmentKind::broken_bond ? red
                                                                                : black;
    rgb->SetTypedTuple(static_cast<vtkIdType>(k), c);
  }
  vtkNew<vtkPolyData> poly;
  poly->SetPoints(pts);
  poly->SetLines(lines);
  poly->GetCellData()->SetScalars(rgb);
  vtkNew<vtkPolyDataMapper> mapper;
  mapper->SetInputData(poly);
  mapper->SetColorModeToDirectScalars();
  mapper->SetScalarModeToUseCellData();
  auto actor = vtkSmartPointer<vtkActor>::New();
  actor->SetMapper(mapper);
  actor->GetProperty()->SetLineWidth(1.0f);
  actor->GetProperty()->LightingOff();
  return actor;
}

}  // namespace

View view_of(const std::vector<double>& position, int dim, double r0) {
  View view;
  view.three_d = dim == 3;
  view.radius = 0.45 * r0;
  double lo[3] = {1e300, 1e300, 1e300}, hi[3] = {-1e300, -1e300, -1e300};
  const std::size_t d = static_cast<std::size_t>(dim);
  for (std::size_t i = 0; i + d <= position.size(); i += d)
    for (std::size_t a = 0; a < d; ++a) lo[a] = std::min(lo[a], position[i + a]), hi[a] = std::max(hi[a], position[i + a]);
  view.xmin = lo[0], view.xmax = hi[0], view.ymin = lo[1], view.ymax = hi[1];
  if (view.three_d) view.zmin = lo[2], view.zmax = hi[2];
  return view;
}

View enclose(const View& a, const View& b) {
  View v = a;
  v.xmin = std::min(a.xmin, b.xmin), v.xmax = std::max(a.xmax, b.xmax);
  v.ymin = std::min(a.ymin, b.ymin), v.ymax = std::max(a.ymax, b.ymax);
  v.zmin = std::min(a.zmin, b.zmin), v.zmax = std::max(a.zmax, b.zmax);
  return v;
}

CameraPose camera_pose(const View& view, double aspect) {
  CameraPose pose;
  const double cx = 0.5 * (view.xmin + view.xmax), cy = 0.5 * (view.ymin + view.ymax);
  if (view.three_d) {
    // Perspective from the front-right, above: the whole box in view.
    const double cz = 0.5 * (view.zmin + view.zmax);
    const double radius = 0.5 * std::sqrt(std::pow(view.xmax - view.xmin, 2) + std::pow(view.ymax - view.ymin, 2) +
                                          std::pow(view.zmax - view.zmin, 2));
    const double dir[3] = {0.55, -0.62, 0.56};  // unit length
    // The view angle is vertical: a panel narrower than tall needs the camera further back.
    const double dist = 1.15 * radius / std::sin(0.5 * pose.view_angle_deg * 3.14159265358979 / 180.0) / std::min(1.0, aspect);
    for (int a = 0; a < 3; ++a) pose.focal_point[a] = (a == 0 ? cx : a == 1 ? cy : cz);
    for (int a = 0; a < 3; ++a) pose.position[a] = pose.focal_point[a] + dist * dir[a];
    pose.view_up[0] = 0, pose.view_up[1] = 0, pose.view_up[2] = 1;
    pose.near = 0.1 * dist, pose.far = 3.0 * dist;
    return pose;
  }
  // The initial body with a margin; a wider one at the top leaves room for the time label above a stretched body.
  const double hw = 0.5 * (view.xmax - view.xmin), hh = 0.5 * (view.ymax - view.ymin);
  pose.parallel = true;
  pose.parallel_scale = 1.2 * std::max(hh, hw / aspect) + view.radius;
  const double fy = cy + 0.04 * pose.parallel_scale;
  pose.focal_point[0] = cx, pose.focal_point[1] = fy, pose.focal_point[2] = 0.0;
  pose.position[0] = cx, pose.position[1] = fy, pose.position[2] = 100.0;
  pose.view_up[0] = 0, pose.view_up[1] = 1, pose.view_up[2] = 0;
  pose.near = 1.0, pose.far = 200.0;
  return pose;
}

double splat_radius_pixels(const View& view, int panel_w, int panel_h) {
  const CameraPose pose = camera_pose(view, static_cast<double>(panel_w) / panel_h);
  double half_height = pose.parallel_scale;  // world units from the panel's centre to its top edge
  if (!pose.parallel) {
    double dist = 0.0;
    for (int a = 0; a < 3; ++a) dist += std::pow(pose.position[a] - pose.focal_point[a], 2);
    half_height = std::sqrt(dist) * std::tan(0.5 * pose.view_angle_deg * 3.14159265358979 / 180.0);
  }
  return view.radius / half_height * 0.5 * panel_h;
}

void render_png(HeadlessWindow& hw, const View& view, const FieldSpec& field, const std::vector<FramePicture>& pics,
                const std::string& title, int panel_w, int panel_h, const std::string& png_path, int compression,
                PngQueue* queue) {
  // A 3-D lattice whose splats span a few pixels turns into moire with one sample per pixel: it is drawn at
  // twice the size and averaged down. Larger splats do not need it, and it quadruples the rasterizer's work.
  const bool fine_lattice = view.three_d && splat_radius_pixels(view, panel_w, panel_h) < 5.0;
  const int supersample =
      fine_lattice && 2 * panel_w * static_cast<int>(pics.size()) <= 8192 && 2 * panel_h <= 8192 ? 2 : 1;
  panel_w *= supersample, panel_h *= supersample;
  vtkGenericOpenGLRenderWindow* win = hw.window();
  const int count = static_cast<int>(pics.size());
  // A title line is 1/14 of the panel; further lines (the overrides that ran) take 3/5 of one each.
  const int title_line_h = std::max(40, panel_h / 14);
  const int title_lines = 1 + static_cast<int>(std::count(title.begin(), title.end(), '\n'));
  const int title_h = title.empty() ? 0 : title_line_h + (title_lines - 1) * title_line_h * 3 / 5;
  const int legend_w = std::max(90, panel_w / 4);  // the colour bar gets its own column
  const int width = panel_w * count + legend_w, height = panel_h + title_h;
  const double panels_right = static_cast<double>(panel_w * count) / width;
  win->SetSize(width, height);
  // Renderers from a previous call are removed: the window is reused for a whole sequence.
  win->GetRenderers()->RemoveAllItems();
  auto lut = make_lut(field);
  const double top = static_cast<double>(panel_h) / height;

  std::vector<vtkSmartPointer<vtkRenderer>> keep;
  for (int k = 0; k < count; ++k) {
    const FramePicture& pic = pics[static_cast<std::size_t>(k)];
    const vtkIdType n = static_cast<vtkIdType>(pic.value.size());
    vtkNew<vtkPoints> pts;
    pts->SetDataTypeToDouble();
    pts->SetNumberOfPoints(n);
    for (vtkIdType i = 0; i < n; ++i)
      pts->SetPoint(i, pic.xyz[3 * static_cast<std::size_t>(i)], pic.xyz[3 * static_cast<std::size_t>(i) + 1],
                    pic.xyz[3 * static_cast<std::size_t>(i) + 2]);
    vtkNew<vtkDoubleArray> val;
    val->SetName("value");
    val->SetNumberOfTuples(n);
    for (vtkIdType i = 0; i < n; ++i) {
      const double v = pic.value[static_cast<std::size_t>(i)];
      val->SetValue(i, field.categorical ? std::fmod(v, 8.0) : v);
    }
    vtkNew<vtkPolyData> poly;
    poly->SetPoints(pts);
    poly->GetPointData()->SetScalars(val);
    const bool depth_cue = view.three_d;
    if (depth_cue) {
      // Depth cue: the particles dim with their distance from the camera, by up to 40 % across the body, so
      // near faces stand out from far ones and the crack's far face reads as far.
      const CameraPose pose = camera_pose(view, static_cast<double>(panel_w) / panel_h);
      std::vector<double> dist(static_cast<std::size_t>(n));
      double dmin = 1e300, dmax = -1e300;
      for (std::size_t i = 0; i < dist.size(); ++i) {
        double d2 = 0.0;
        for (int a = 0; a < 3; ++a) d2 += std::pow(pic.xyz[3 * i + static_cast<std::size_t>(a)] - pose.position[a], 2);
        dist[i] = std::sqrt(d2), dmin = std::min(dmin, dist[i]), dmax = std::max(dmax, dist[i]);
      }
      vtkNew<vtkUnsignedCharArray> rgb;
      rgb->SetNumberOfComponents(3);
      rgb->SetNumberOfTuples(n);
      for (vtkIdType i = 0; i < n; ++i) {
        double c[3];
        lut->GetColor(val->GetValue(i), c);
        const double dim = 1.0 - 0.4 * (dist[static_cast<std::size_t>(i)] - dmin) / std::max(1e-30, dmax - dmin);
        for (int a = 0; a < 3; ++a) rgb->SetComponent(i, a, std::round(255.0 * c[a] * dim));
      }
      poly->GetPointData()->SetScalars(rgb);
    }
    vtkNew<vtkPointGaussianMapper> mapper;
    mapper->SetInputData(poly);
    mapper->SetScaleFactor(view.radius);
    mapper->SetSplatShaderCode(view.three_d ? sphere_shader : disc_shader);
    mapper->SetTriangleScale(1.0f);  // the disc has radius 1: the default 3 sends 9x the fragments, all discarded
    mapper->SetLookupTable(lut);
    mapper->SetScalarRange(lut->GetTableRange());
    mapper->ScalarVisibilityOn();
    if (depth_cue) mapper->SetColorModeToDirectScalars();
    mapper->EmissiveOff();
    vtkNew<vtkActor> actor;
    actor->SetMapper(mapper);
    actor->GetProperty()->SetAmbient(1.0);
    actor->GetProperty()->SetDiffuse(0.0);

    vtkSmartPointer<vtkRenderer> ren = vtkSmartPointer<vtkRenderer>::New();
    ren->SetViewport(panels_right * k / count, 0.0, panels_right * (k + 1) / count, top);
    ren->SetBackground(1.0, 1.0, 1.0);
    ren->AddActor(actor);
    if (!pic.segments.empty()) ren->AddActor(segment_actor(pic, view));

    const double cx = 0.5 * (view.xmin + view.xmax), cy = 0.5 * (view.ymin + view.ymax);
    const double aspect = static_cast<double>(panel_w) / panel_h;
    const CameraPose pose = camera_pose(view, aspect);
    vtkCamera* cam = ren->GetActiveCamera();
    cam->SetParallelProjection(pose.parallel);
    if (pose.parallel) cam->SetParallelScale(pose.parallel_scale);
    else cam->SetViewAngle(pose.view_angle_deg);
    cam->SetFocalPoint(pose.focal_point);
    cam->SetPosition(pose.position);
    cam->SetViewUp(pose.view_up);
    cam->SetClippingRange(pose.near, pose.far);

    // Time label and caption.
    vtkNew<vtkTextActor> label;
    label->SetInput((time_text(pic.time) + (pic.caption.empty() ? "" : "   " + pic.caption)).c_str());
    label->GetTextProperty()->SetFontSize(std::max(14, panel_h / 36));
    label->GetTextProperty()->SetColor(0.1, 0.1, 0.1);
    label->GetPositionCoordinate()->SetCoordinateSystemToViewport();  // relative to this panel
    label->GetPositionCoordinate()->SetValue(12 * supersample, panel_h - std::max(14, panel_h / 36) - 14 * supersample);
    ren->AddActor2D(label);

    // Scale bar: 1 cm in world units, at the lower left of a 2-D view; in 3-D along x, at the height of the
    // box's floor (so perspective scales it like the body there).
    const double scale = cam->GetParallelScale();
    const double x0 = view.three_d ? cx - 0.5 : cx - scale * aspect * 0.92;
    // In 3-D it lies on the floor in front of the box, clear of the body's silhouette (an eighth of the box's
    // depth, and at least 1 cm, before its front edge).
    const double y0 = view.three_d ? view.ymin - std::max(1.0, 0.125 * (view.ymax - view.ymin))
                                   : cy + 0.04 * scale - scale * 0.94;
    const double z0 = view.three_d ? view.zmin : 1.0;
    vtkNew<vtkPoints> sp;
    sp->InsertNextPoint(x0, y0, z0);
    sp->InsertNextPoint(x0 + 1.0, y0, z0);
    vtkNew<vtkCellArray> line;
    const vtkIdType ids[2] = {0, 1};
    line->InsertNextCell(2, ids);
    vtkNew<vtkPolyData> bar;
    bar->SetPoints(sp);
    bar->SetLines(line);
    vtkNew<vtkPolyDataMapper> bar_mapper;
    bar_mapper->SetInputData(bar);
    vtkNew<vtkActor> bar_actor;
    bar_actor->SetMapper(bar_mapper);
    bar_actor->GetProperty()->SetColor(0.1, 0.1, 0.1);
    bar_actor->GetProperty()->SetLineWidth(std::max(2.0, panel_h / 300.0));
    ren->AddActor(bar_actor);
    vtkNew<vtkTextActor> bar_text;
    bar_text->SetInput(view.three_d ? "1 cm  " : "1 cm");
    bar_text->GetTextProperty()->SetFontSize(std::max(12, panel_h / 45));
    bar_text->GetTextProperty()->SetColor(0.1, 0.1, 0.1);
    bar_text->GetPositionCoordinate()->SetCoordinateSystemToWorld();
    if (view.three_d) {
      // The bar runs down and right on the screen: its label ends where the bar starts, clear of it.
      bar_text->GetTextProperty()->SetJustificationToRight();
      bar_text->GetTextProperty()->SetVerticalJustificationToCentered();
      bar_text->GetPositionCoordinate()->SetValue(x0, y0, z0);
    } else {
      bar_text->GetPositionCoordinate()->SetValue(x0, y0 + 0.12, z0);
    }
    ren->AddActor2D(bar_text);

    win->AddRenderer(ren);
    keep.push_back(ren);
  }
  {  // the colour bar, in its own column right of the panels
    vtkSmartPointer<vtkRenderer> ren = vtkSmartPointer<vtkRenderer>::New();
    ren->SetViewport(panels_right, 0.0, 1.0, top);
    ren->SetBackground(1.0, 1.0, 1.0);
    vtkNew<vtkScalarBarActor> sb;
    sb->SetLookupTable(lut);
    sb->SetTitle(field.title.c_str());
    sb->SetNumberOfLabels(field.categorical ? 8 : 5);
    sb->SetLabelFormat(field.categorical ? "%.0f" : "%.3g");
    sb->SetOrientationToVertical();
    sb->SetPosition(0.08, 0.08);
    sb->SetWidth(0.8);
    sb->SetHeight(0.84);
    sb->SetBarRatio(0.3);
    sb->GetTitleTextProperty()->SetColor(0.1, 0.1, 0.1);
    sb->GetLabelTextProperty()->SetColor(0.1, 0.1, 0.1);
    sb->GetTitleTextProperty()->SetFontSize(std::max(12, panel_h / 45));
    sb->GetLabelTextProperty()->SetFontSize(std::max(11, panel_h / 55));
    sb->GetTitleTextProperty()->ItalicOff();
    sb->GetLabelTextProperty()->ItalicOff();
    sb->UnconstrainedFontSizeOn();
    ren->AddActor2D(sb);
    win->AddRenderer(ren);
    keep.push_back(ren);
  }
  if (title_h > 0) {
    vtkSmartPointer<vtkRenderer> ren = vtkSmartPointer<vtkRenderer>::New();
    ren->SetViewport(0.0, top, 1.0, 1.0);
    ren->SetBackground(1.0, 1.0, 1.0);
    vtkNew<vtkTextActor> t;
    t->SetInput(title.c_str());
    t->GetTextProperty()->SetFontSize(title_line_h / 2);
    t->GetTextProperty()->SetColor(0.1, 0.1, 0.1);
    t->GetTextProperty()->BoldOn();
    t->GetPositionCoordinate()->SetCoordinateSystemToViewport();
    t->GetPositionCoordinate()->SetValue(14 * supersample, title_line_h / 4);
    ren->AddActor2D(t);
    win->AddRenderer(ren);
    keep.push_back(ren);
    // A title wider than the figure (one narrow panel, long overrides) is set smaller rather than clipped.
    double size[2] = {0.0, 0.0};
    t->GetSize(ren, size);
    const double room = width - 28.0 * supersample;
    if (size[0] > room)
      t->GetTextProperty()->SetFontSize(std::max(8, static_cast<int>(title_line_h / 2 * room / size[0])));
  }
  win->Render();

  detail::write_window_png(win, png_path, compression, queue, supersample);
}

}  // namespace pmfrag::render
