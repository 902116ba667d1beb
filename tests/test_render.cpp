// Headless rendering: sizes, colours at the particles' projected positions, background elsewhere, labels.
#include "pmfrag/render/charts.hpp"
#include "pmfrag/render/frames.hpp"
#include "test_helpers.hpp"

#include <gtest/gtest.h>
#include <vtkImageData.h>
#include <vtkNew.h>
#include <vtkPNGReader.h>
#include <vtkSmartPointer.h>

#include <cstdlib>
#include <limits>

#if defined(__SANITIZE_ADDRESS__)
// Under AddressSanitizer, no leak check at the exit of this process: LSan's tracer stops every thread to scan
// the heap, and beside the GL driver's worker threads (Mesa llvmpipe) it now and then crashed ("Tracer caught
// signal 11", CI of 2026-12-03, two tests of nine, after they had passed). Every other test keeps the check.
extern "C" const char* __lsan_default_options() { return "detect_leaks=0"; }
#endif

using namespace pmfrag;

namespace {
struct Image {
  int w = 0, h = 0;
  vtkSmartPointer<vtkImageData> data;
  // (x, y) with y from the bottom, as VTK stores images
  std::array<int, 3> at(int x, int y) const {
    auto* p = static_cast<unsigned char*>(data->GetScalarPointer(x, y, 0));
    return {p[0], p[1], p[2]};
  }
};
Image read_png(const std::string& path) {
  vtkNew<vtkPNGReader> r;
  r->SetFileName(path.c_str());
  r->Update();
  Image im;
  im.data = r->GetOutput();
  int dims[3];
  im.data->GetDimensions(dims);
  im.w = dims[0], im.h = dims[1];
  return im;
}
bool white(const std::array<int, 3>& c) { return c[0] > 250 && c[1] > 250 && c[2] > 250; }
// The 2 x 2 cm square around the origin, discs of radius 0.08 cm: where the pixel tests expect things.
render::View unit_view() {
  render::View view;
  view.xmin = view.ymin = -1.0;
  view.xmax = view.ymax = 1.0;
  view.radius = 0.08;
  return view;
}
}  // namespace

TEST(Render, ParticlesAppearWhereProjectedInTheirColours) {
  const char* display = std::getenv("DISPLAY");  // ctest clears it: rendering must not need a display
  ASSERT_TRUE(display == nullptr || *display == '\0');
  const auto dir = test::temp_dir("render");
  render::HeadlessWindow window(300, 300);
  const render::View view = unit_view();
  render::FieldSpec field;
  field.categorical = true;
  field.title = "fragment";
  render::FramePicture a;
  a.xyz = {-0.5, 0.0, 0.0, 0.0, 0.0, 0.0, 0.5, 0.0, 0.0};
  a.value = {0, 1, 2};
  a.time = 1.024e-2;
  render::FramePicture b = a;
  b.xyz[1] = 0.5;  // first particle moved up
  const std::string pa = (dir / "a.png").string(), pb = (dir / "b.png").string();
  render::render_png(window, view, field, {a}, "", 300, 300, pa);
  render::render_png(window, view, field, {b}, "", 300, 300, pb);
  const Image ia = read_png(pa), ib = read_png(pb);
  ASSERT_EQ(ia.w, 390);
  ASSERT_EQ(ia.h, 300);
  // Parallel projection: scale = 1.2 x 1 + radius world units per half height, the view shifted up by 4 % of
  // it; the colour bar takes a column of max(90, w/4) = 90 px on the right: the panel is 300 x 300.
  const double scale = 1.2 + 0.08;
  auto px = [&](double x) { return static_cast<int>(std::lround(150 + x / scale * 150)); };
  auto py = [&](double y) { return static_cast<int>(std::lround(150 + (y - 0.04 * scale) / scale * 150)); };
  const int okabe[3][3] = {{230, 159, 0}, {86, 180, 233}, {0, 158, 115}};
  for (int k = 0; k < 3; ++k) {
    const auto c = ia.at(px(a.xyz[3 * k]), py(0.0));
    for (int ch = 0; ch < 3; ++ch) EXPECT_NEAR(c[ch], okabe[k][ch], 3) << "particle " << k << " channel " << ch;
  }
  EXPECT_TRUE(white(ia.at(px(0.0), py(-0.6))));  // between particles: background
  EXPECT_TRUE(white(ia.at(px(-0.5), py(0.5))));
  // Moved particle: now at (-0.5, 0.5) in b, background at its old place.
  EXPECT_FALSE(white(ib.at(px(-0.5), py(0.5))));
  EXPECT_TRUE(white(ib.at(px(-0.5), py(0.0))));
  // Time label (top left) and colour bar (right) drew something.
  auto ink = [](const Image& im, int x0, int x1, int y0, int y1) {
    int n = 0;
    for (int x = x0; x < x1; ++x)
      for (int y = y0; y < y1; ++y) n += !white(im.at(x, y));
    return n;
  };
  EXPECT_GT(ink(ia, 0, 120, 270, 300), 20) << "time label";
  EXPECT_GT(ink(ia, 300, 390, 30, 270), 200) << "colour bar";
  EXPECT_GT(ink(ia, 0, 60, 0, 30), 10) << "scale bar";
  std::filesystem::remove_all(dir);
}

TEST(Render, BondsAndVectorsDrawOverTheParticlesInTheirColours) {
  const auto dir = test::temp_dir("overlay");
  render::HeadlessWindow window(300, 300);
  const render::View view = unit_view();
  render::FieldSpec field;
  field.categorical = true;
  render::FramePicture pic;
  pic.xyz = {-0.5, 0.0, 0.0, 0.5, 0.0, 0.0, 0.0, -0.5, 0.0};
  pic.value = {0, 0, 0};
  const std::string plain = (dir / "plain.png").string(), lines = (dir / "lines.png").string();
  render::render_png(window, view, field, {pic}, "", 300, 300, plain);
  // An intact bond between particles 0 and 1 (along y = 0), a broken one from 1 to 2, and particle 2's
  // displacement vector straight down.
  pic.segments = {-0.5, 0.0, 0.0, 0.5, 0.0, 0.0, 0.5, 0.0, 0.0, 0.0, -0.5, 0.0, 0.0, -0.5, 0.0, 0.0, -0.9, 0.0};
  pic.segment_kinds = {render::SegmentKind::intact_bond, render::SegmentKind::broken_bond, render::SegmentKind::vector};
  render::render_png(window, view, field, {pic}, "", 300, 300, lines);
  const Image a = read_png(plain), b = read_png(lines);
  const double scale = 1.2 + 0.08;
  auto px = [&](double x) { return static_cast<int>(std::lround(150 + x / scale * 150)); };
  auto py = [&](double y) { return static_cast<int>(std::lround(150 + (y - 0.04 * scale) / scale * 150)); };
  // Search a few pixels across each line's expected position for its colour (lines are one pixel wide).
  auto near = [&](const Image& im, int x, int y, std::array<int, 3> want) {
    for (int dx = -2; dx <= 2; ++dx)
      for (int dy = -2; dy <= 2; ++dy) {
        const auto c = im.at(x + dx, y + dy);
        if (std::abs(c[0] - want[0]) < 40 && std::abs(c[1] - want[1]) < 40 && std::abs(c[2] - want[2]) < 40) return true;
      }
    return false;
  };
  EXPECT_TRUE(white(a.at(px(0.0), py(0.0))));  // no overlay: background between the particles
  EXPECT_TRUE(near(b, px(0.0), py(0.0), {90, 90, 90})) << "intact bond, grey";
  EXPECT_TRUE(near(b, px(0.25), py(-0.25), {213, 30, 30})) << "broken bond, red";
  EXPECT_TRUE(near(b, px(0.0), py(-0.75), {0, 0, 0})) << "vector, black";
  EXPECT_FALSE(near(a, px(0.0), py(-0.75), {0, 0, 0}));
  std::filesystem::remove_all(dir);
}

TEST(Render, HeatmapColoursCellsByValueAndLeavesEmptyCellsWhite) {
  const auto dir = test::temp_dir("heatmap");
  render::HeadlessWindow window(400, 400);
  // 2 x 2 grid: low, high / empty, middle. The lowest value maps to the ramp's dark purple end, the highest
  // to its yellow end.
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const render::HeatmapSpec map{"t", "p", "q", "E", 1, 1, 2, 2, {0.0, 10.0, nan, 5.0}};
  const std::string png = (dir / "map.png").string();
  render::render_heatmap_png(window, map, 400, 400, png);
  const Image im = read_png(png);
  ASSERT_EQ(im.w, 400);
  auto count = [&](std::array<int, 3> want) {
    int n = 0;
    for (int x = 0; x < im.w; ++x)
      for (int y = 0; y < im.h; ++y) {
        const auto c = im.at(x, y);
        n += std::abs(c[0] - want[0]) < 12 && std::abs(c[1] - want[1]) < 12 && std::abs(c[2] - want[2]) < 12;
      }
    return n;
  };
  // Each cell is roughly a quarter of the plot area (well over 3000 px at this size); the colour legend adds
  // a strip of each colour too.
  EXPECT_GT(count({68, 1, 84}), 3000) << "lowest value: dark purple";
  EXPECT_GT(count({253, 231, 37}), 3000) << "highest value: yellow";
  EXPECT_GT(count({33, 145, 140}), 3000) << "middle value: teal";
  EXPECT_THROW(render::render_heatmap_png(window, {"t", "p", "q", "E", 1, 1, 2, 2, {1.0}}, 400, 400, png),
               std::invalid_argument);
  std::filesystem::remove_all(dir);
}

TEST(Render, ChartDrawsEachCurveInItsColour) {
  const auto dir = test::temp_dir("chart");
  render::HeadlessWindow window(400, 300);
  for (bool log : {false, true}) {
    const render::ChartSpec chart{"t", "x [s]", "y", log, log,
                                  {{"a", {1, 10, 100}, {1e-1, 1e-2, 1e-3}}, {"b", {1, 10, 100}, {1e-3, 1e-2, 1e-1}}}};
    const std::string png = (dir / (log ? "log.png" : "lin.png")).string();
    render::render_chart_png(window, chart, 400, 300, png);
    const Image im = read_png(png);
    ASSERT_EQ(im.w, 400);
    int blue = 0, vermillion = 0;  // Okabe-Ito (0,114,178) and (213,94,0)
    for (int x = 0; x < im.w; ++x)
      for (int y = 0; y < im.h; ++y) {
        const auto c = im.at(x, y);
        blue += std::abs(c[0] - 0) < 30 && std::abs(c[1] - 114) < 30 && std::abs(c[2] - 178) < 30;
        vermillion += std::abs(c[0] - 213) < 30 && std::abs(c[1] - 94) < 30 && std::abs(c[2] - 0) < 30;
      }
    EXPECT_GT(blue, 300) << (log ? "log" : "linear") << " axes: curve a";
    EXPECT_GT(vermillion, 300) << (log ? "log" : "linear") << " axes: curve b";
  }
  std::filesystem::remove_all(dir);
}

TEST(Render, MatchesTheCommittedReferenceImage) {
  // A fixed 5 x 5 patch, three fragments, a title and a time label, rendered with Mesa's software rasterizer
  // (reproducible), compared with tests/data/reference_frame.png. PMFRAG_UPDATE_REFERENCE=1 rewrites the
  // reference after an intended change of the pictures (look at it before committing).
  setenv("LIBGL_ALWAYS_SOFTWARE", "1", 1);
  const auto dir = test::temp_dir("reference");
  render::HeadlessWindow window(240, 240);
  render::View view;
  view.xmin = view.ymin = 0.0;
  view.xmax = view.ymax = 0.8;
  view.radius = 0.09;
  render::FieldSpec field;
  field.categorical = true;
  field.title = "fragment";
  render::FramePicture pic;
  for (int i = 0; i < 5; ++i)
    for (int j = 0; j < 5; ++j) {
      pic.xyz.insert(pic.xyz.end(), {0.2 * i + 0.1 * (j % 2), 0.2 * j, 0.0});
      pic.value.push_back(i < 2 ? 0 : (j < 3 ? 1 : 2));
    }
  pic.time = 1.5e-3;
  const std::string png = (dir / "frame.png").string();
  render::render_png(window, view, field, {pic}, "reference patch", 240, 240, png);
  const std::string reference = std::string(PMFRAG_SOURCE_DIR) + "/tests/data/reference_frame.png";
  if (std::getenv("PMFRAG_UPDATE_REFERENCE")) {
    std::filesystem::copy_file(png, reference, std::filesystem::copy_options::overwrite_existing);
    GTEST_SKIP() << "reference rewritten: " << reference;
  }
  ASSERT_TRUE(std::filesystem::exists(reference)) << reference;
  const Image got = read_png(png), want = read_png(reference);
  ASSERT_EQ(got.w, want.w);
  ASSERT_EQ(got.h, want.h);
  long differ = 0;
  for (int x = 0; x < got.w; ++x)
    for (int y = 0; y < got.h; ++y) {
      const auto a = got.at(x, y), b = want.at(x, y);
      int worst = 0;
      for (int c = 0; c < 3; ++c) worst = std::max(worst, std::abs(a[c] - b[c]));
      differ += worst > 16;
    }
  EXPECT_LT(differ, got.w * got.h / 100) << differ << " of " << got.w * got.h << " pixels differ by more than 16 levels";
  std::filesystem::remove_all(dir);
}

TEST(Render, ThreeDimensionalViewShowsTheBoxInPerspective) {
  const auto dir = test::temp_dir("render3d");
  render::HeadlessWindow window(300, 300);
  render::View view;
  view.three_d = true;
  view.xmin = view.ymin = view.zmin = 0.0;
  view.xmax = view.ymax = 2.0;
  view.zmax = 1.0;
  view.radius = 0.1;
  render::FieldSpec field;
  field.title = "value";
  render::FramePicture pic;
  for (int i = 0; i <= 10; ++i)
    for (int j = 0; j <= 10; ++j)
      for (int k = 0; k <= 5; ++k) {
        pic.xyz.insert(pic.xyz.end(), {0.2 * i, 0.2 * j, 0.2 * k});
        pic.value.push_back(0.2 * k);  // colour by height: the top is yellow, the bottom dark
      }
  field.max = 1.0;
  const std::string png = (dir / "cube.png").string();
  render::render_png(window, view, field, {pic}, "", 300, 300, png);
  const Image im = read_png(png);
  ASSERT_EQ(im.h, 300);
  // The box fills the middle of the panel and is not clipped: the panel's border rows and columns stay white.
  EXPECT_FALSE(white(im.at(150, 150)));
  int ink_border = 0;
  for (int t = 0; t < 300; ++t) ink_border += !white(im.at(t, 1)) + !white(im.at(1, t)) + !white(im.at(298, t));
  EXPECT_LT(ink_border, 60) << "the body touches the panel's edges";
  std::filesystem::remove_all(dir);
}

TEST(Render, ParticlesOfNoCategoryArePaleGrey) {
  // Targets held in place carry NaN in a categorical field (pmfrag render): drawn pale grey, which no
  // fragment colour is, so a wall never passes for a fragment.
  const auto dir = test::temp_dir("render_nan");
  render::HeadlessWindow window(200, 200);
  render::View view;
  view.xmin = view.ymin = 0.0;
  view.xmax = view.ymax = 1.0;
  view.radius = 0.2;
  render::FieldSpec field;
  field.categorical = true;
  field.title = "fragment";
  render::FramePicture pic;
  pic.xyz = {0.25, 0.5, 0.0, 0.75, 0.5, 0.0};
  pic.value = {std::numeric_limits<double>::quiet_NaN(), 0.0};
  const std::string png = (dir / "nan.png").string();
  render::render_png(window, view, field, {pic}, "", 200, 200, png);
  const Image im = read_png(png);
  int pale = 0, orange = 0;
  for (int x = 0; x < 200; ++x)  // the panel, not the colour bar beside it
    for (int y = 0; y < im.h; ++y) {
      const auto c = im.at(x, y);
      pale += c[0] == c[1] && c[1] == c[2] && c[0] > 200 && c[0] < 240;
      orange += c[0] > 200 && c[1] > 120 && c[1] < 180 && c[2] < 60;
    }
  EXPECT_GT(pale, 200) << "the NaN particle is not pale grey";
  EXPECT_GT(orange, 200) << "fragment 0 lost its colour";
  std::filesystem::remove_all(dir);
}

TEST(Render, ThreeDimensionalParticlesAreShadedSpheresDimmedWithDistance) {
  // Two particles of one colour, one at the near corner of the box and one at the far corner: each is lit as a
  // sphere (its upper-left side brighter than its lower-right), and the far one is darker as a whole.
  const auto dir = test::temp_dir("render_spheres");
  render::HeadlessWindow window(400, 400);
  render::View view;
  view.three_d = true;
  view.xmin = view.ymin = view.zmin = 0.0;
  view.xmax = view.ymax = view.zmax = 4.0;
  view.radius = 0.6;
  render::FieldSpec field;
  field.categorical = true;
  field.title = "fragment";
  render::FramePicture pic;
  pic.xyz = {4.0, 0.0, 4.0, 0.0, 4.0, 0.0};  // near (the camera looks from +x, -y, +z), far
  pic.value = {0.0, 0.0};
  const std::string png = (dir / "spheres.png").string();
  render::render_png(window, view, field, {pic}, "", 400, 400, png);
  const Image im = read_png(png);
  // Each sphere's pixels, found as the non-white pixels of the panel nearer to its projected centre.
  struct Blob {
    double sum = 0, n = 0, x = 0, y = 0;
    std::vector<std::array<int, 3>> px;  // x, y, brightness
  } blob[2];
  for (int x = 0; x < 400; ++x)
    for (int y = 0; y < im.h; ++y) {
      const auto c = im.at(x, y);
      if (white(c) || c[0] < c[2]) continue;  // background, text
      const int b = c[0] + c[1] + c[2];
      Blob& s = blob[x + y < 400 ? 1 : 0];  // the near particle projects lower right, the far one upper left
      s.sum += b, s.n += 1, s.x += x, s.y += y;
      s.px.push_back({x, y, b});
    }
  ASSERT_GT(blob[0].n, 50);
  ASSERT_GT(blob[1].n, 20);
  EXPECT_LT(blob[1].sum / blob[1].n, 0.9 * blob[0].sum / blob[0].n) << "the far particle is not dimmer";
  const Blob& near = blob[0];
  const double cx = near.x / near.n, cy = near.y / near.n;
  double upper_left = 0, lower_right = 0, nu = 0, nl = 0;
  for (const auto& p : near.px) {
    if (p[0] < cx && p[1] > cy) upper_left += p[2], ++nu;  // y counts from the bottom
    if (p[0] > cx && p[1] < cy) lower_right += p[2], ++nl;
  }
  EXPECT_GT(upper_left / nu, 1.2 * lower_right / nl) << "the sphere is flat, not lit from the upper left";
  std::filesystem::remove_all(dir);
}

TEST(Render, AViewFollowsTheParticlesAndEnclosesTwoFrames) {
  const std::vector<double> before = {0.0, 0.0, 1.0, 1.0}, after = {10.0, 0.0, 11.0, 2.0};  // 2-D, moved by 10 cm
  const render::View a = render::view_of(before, 2, 0.2), b = render::view_of(after, 2, 0.2);
  EXPECT_DOUBLE_EQ(b.xmin, 10.0);
  EXPECT_DOUBLE_EQ(b.ymax, 2.0);
  EXPECT_DOUBLE_EQ(b.radius, 0.45 * 0.2);
  EXPECT_NEAR(render::camera_pose(b, 1.0).focal_point[0] - render::camera_pose(a, 1.0).focal_point[0], 10.0, 1e-12);
  const render::View both = render::enclose(a, b);
  EXPECT_DOUBLE_EQ(both.xmin, 0.0);
  EXPECT_DOUBLE_EQ(both.xmax, 11.0);
  EXPECT_DOUBLE_EQ(both.ymax, 2.0);
}

TEST(Render, SplatRadiusInPixelsScalesWithTheParticleAndThePanel) {
  // 2-D: a 10 cm square box in a square panel of 500 px shows about 50 px per cm (less the margin).
  render::View flat = render::view_of({0.0, 0.0, 10.0, 10.0}, 2, 0.2);
  const double px = render::splat_radius_pixels(flat, 500, 500);
  EXPECT_GT(px, 0.7 * 0.09 * 50.0);  // the margin is 20 %
  EXPECT_LT(px, 0.09 * 50.0 * 1.0001);
  EXPECT_NEAR(render::splat_radius_pixels(flat, 1000, 1000), 2.0 * px, 1e-9 * px);
  // 3-D: halving the lattice spacing halves the splat; a coarse block is not a fine lattice, a fine one is.
  render::View block = render::view_of({0.0, 0.0, 0.0, 10.0, 10.0, 10.0}, 3, 0.2);
  ASSERT_TRUE(block.three_d);
  render::View finer = block;
  finer.radius *= 0.5;
  const double coarse_px = render::splat_radius_pixels(block, 1024, 1024);
  EXPECT_NEAR(render::splat_radius_pixels(finer, 1024, 1024), 0.5 * coarse_px, 1e-9 * coarse_px);
  EXPECT_GT(coarse_px, 0.0);
}
