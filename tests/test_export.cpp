// VTU/PVD export: read every file back with VTK's own reader and compare with the trajectory.
#include "pmfrag/analysis/export_vtk.hpp"
#include "pmfrag/io/h5md.hpp"
#include "pmfrag/run/run.hpp"
#include "test_helpers.hpp"

#include <gtest/gtest.h>
#include <vtkCellData.h>
#include <vtkDataArray.h>
#include <vtkNew.h>
#include <vtkPointData.h>
#include <vtkUnstructuredGrid.h>
#include <vtkXMLUnstructuredGridReader.h>

#include <fstream>
#include <regex>

using namespace pmfrag;

class Export : public ::testing::TestWithParam<analysis::Compression> {};

TEST_P(Export, RoundTripThroughVtkReaderAndPvd) {
  const auto dir = test::temp_dir("export");
  // A small notched (3,5) plate torn apart at 1000 cm/s: it breaks at 1.7e-4 s and splits by 2.3e-4 s, so
  // fragments, damage and broken bonds are all non-trivial in a short run.
  const char* scene_text = R"(
[[body]]
lattice = "triangular"
shape = { kind = "rect", min = [0, 0], max = [2, 2] }
slits = [ { from = [-0.1, 1.05], to = [0.7, 1.05] } ]
[[phase]]
p = 3
q = 5
[pair]
[[kinematic]]
select = { row = "top" }
velocity = [0, 1000]
[[kinematic]]
select = { row = "bottom" }
velocity = [0, -1000]
[time]
dt = 1e-7
end = 3e-4
[output]
every = 1e-5
)";
  const Scene sc = parse_scene(scene_text, "torn.toml");
  RunOptions ro;
  ro.out_dir = dir.string();
  ASSERT_TRUE(run_scene(sc, ro).completed);
  analysis::ExportOptions opt;
  opt.every = 2;
  opt.compression = GetParam();
  const auto res = analysis::export_vtk(dir.string(), opt);
  H5mdReader rd((dir / "trajectory.h5").string());
  const long frames = rd.frames();
  EXPECT_EQ(res.frames_read, frames);
  EXPECT_EQ(res.frames_written, (frames - 1) / 2 + 1 + ((frames - 1) % 2 ? 1 : 0));

  // The .pvd lists every written frame with its time.
  std::ifstream pvd(dir / "particles.pvd");
  const std::string text((std::istreambuf_iterator<char>(pvd)), std::istreambuf_iterator<char>());
  std::regex entry("timestep=\"([^\"]+)\" part=\"0\" file=\"vtk/frame_([0-9]+)\\.vtu\"");
  long listed = 0;
  for (auto it = std::sregex_iterator(text.begin(), text.end(), entry); it != std::sregex_iterator(); ++it) {
    const long k = std::stol((*it)[2]);
    EXPECT_DOUBLE_EQ(std::stod((*it)[1]), rd.frame(k).time);
    ++listed;
  }
  EXPECT_EQ(listed, res.frames_written);

  analysis::BondStates states = analysis::BondStates::open(rd, std::nullopt);
  const analysis::FragmentTracker tracker(rd.particles(), rd.bonds(), rd.mass());
  const auto first = rd.frame(0);
  const auto bonds = rd.bonds();
  long max_fragments = 0;
  for (long k = 0; k < frames; ++k) {
    const auto f = rd.frame(k);
    states.advance(k, f.position);
    const auto lab = tracker.label(states.broken());
    if (k % 2 != 0 && k != frames - 1) continue;
    char name[32];
    std::snprintf(name, sizeof name, "frame_%05ld.vtu", k);
    vtkNew<vtkXMLUnstructuredGridReader> reader;
    reader->SetFileName((dir / "vtk" / name).c_str());
    reader->Update();
    vtkUnstructuredGrid* g = reader->GetOutput();
    const vtkIdType n = static_cast<vtkIdType>(rd.particles()), m = static_cast<vtkIdType>(bonds.size());
    const double r0 = rd.parameter("r0");
    ASSERT_EQ(g->GetNumberOfPoints(), n);
    ASSERT_EQ(g->GetNumberOfCells(), n + m);
    auto* disp = g->GetPointData()->GetArray("displacement");
    auto* vel = g->GetPointData()->GetArray("velocity");
    auto* fid = g->GetPointData()->GetArray("fragment_id");
    auto* dmg = g->GetPointData()->GetArray("damage");
    auto* brk = g->GetCellData()->GetArray("broken");
    auto* str = g->GetCellData()->GetArray("stretch");
    ASSERT_TRUE(disp && vel && fid && dmg && brk && str);
    for (vtkIdType i = 0; i < n; ++i) {
      double p[3];
      g->GetPoint(i, p);
      const std::size_t u = static_cast<std::size_t>(i);
      ASSERT_EQ(p[0], f.position[2 * u]);
      ASSERT_EQ(p[1], f.position[2 * u + 1]);
      ASSERT_EQ(disp->GetComponent(i, 0), f.position[2 * u] - first.position[2 * u]);
      ASSERT_EQ(vel->GetComponent(i, 1), f.velocity[2 * u + 1]);
      ASSERT_EQ(fid->GetComponent(i, 0), lab.fragment_id[u]);
      ASSERT_EQ(dmg->GetComponent(i, 0), lab.damage[u]);
      max_fragments = std::max(max_fragments, static_cast<long>(fid->GetComponent(i, 0)) + 1);
    }
    for (vtkIdType b = 0; b < m; ++b) {
      ASSERT_EQ(brk->GetComponent(n + b, 0), states.broken()[static_cast<std::size_t>(b)]);
      const auto& bd = bonds[static_cast<std::size_t>(b)];
      const double r = std::hypot(f.position[2 * bd[0]] - f.position[2 * bd[1]], f.position[2 * bd[0] + 1] - f.position[2 * bd[1] + 1]);
      ASSERT_NEAR(str->GetComponent(n + b, 0), r / r0, 1e-12);
    }
  }
  EXPECT_GE(max_fragments, 2) << "the plate should have split by 3e-4 s";
  std::filesystem::remove_all(dir);
}

INSTANTIATE_TEST_SUITE_P(Compressors, Export,
                         ::testing::Values(analysis::Compression::lz4, analysis::Compression::zlib,
                                           analysis::Compression::none),
                         [](const auto& tp) {
                           switch (tp.param) {
                             case analysis::Compression::lz4: return std::string("lz4");
                             case analysis::Compression::zlib: return std::string("zlib");
                             default: return std::string("none");
                           }
                         });
