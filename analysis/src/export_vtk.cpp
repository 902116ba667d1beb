#include "pmfrag/analysis/export_vtk.hpp"

#include "pmfrag/analysis/particle_fields.hpp"
#include "pmfrag/io/atomic_file.hpp"
#include "pmfrag/io/h5md.hpp"

#include <vtkCellArray.h>
#include <vtkCellData.h>
#include <vtkDoubleArray.h>
#include <vtkIntArray.h>
#include <vtkNew.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkUnsignedCharArray.h>
#include <vtkUnstructuredGrid.h>
#include <vtkXMLUnstructuredGridWriter.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <stdexcept>

namespace pmfrag::analysis {

namespace fs = std::filesystem;

const std::set<std::string>& export_fields() {
  static const std::set<std::string> all{"id",          "phase",         "displacement", "velocity",
                                         "speed",       "kinetic_energy", "damage",      "fragment_id",
                                         "fragment_size", "cell_kind",    "stretch",     "broken",
                                         "bond_force"};
  return all;
}

namespace {

template <class Array>
vtkNew<Array> named(const char* name, int components, vtkIdType tuples) {
  vtkNew<Array> a;
  a->SetName(name);
  a->SetNumberOfComponents(components);
  a->SetNumberOfTuples(tuples);
  return a;
}

struct Static {
  std::size_t n = 0;
  int dim = 2;
  double r0 = 0.2;
  std::vector<std::array<int, 2>> bonds;
  std::vector<int> species;
  std::vector<double> mass;
  std::vector<PairLaw> laws;
  std::vector<int> pair_law;
  std::size_t nphase = 1;
};

void write_frame(const fs::path& file, const Static& st, const TrajectoryFrame& f, const TrajectoryFrame& first,
                 const FrameLabels& lab, const std::vector<std::uint8_t>& broken, const std::set<std::string>& fields,
                 Compression compression) {
  auto want = [&](const char* name) { return fields.empty() || fields.count(name); };
  const vtkIdType n = static_cast<vtkIdType>(st.n), m = static_cast<vtkIdType>(st.bonds.size());
  const std::size_t d = static_cast<std::size_t>(st.dim);
  vtkNew<vtkUnstructuredGrid> grid;
  vtkNew<vtkPoints> points;
  points->SetDataTypeToDouble();
  points->SetNumberOfPoints(n);
  for (std::size_t i = 0; i < st.n; ++i)
    points->SetPoint(static_cast<vtkIdType>(i), f.position[i * d], f.position[i * d + 1], d == 3 ? f.position[i * d + 2] : 0.0);
  grid->SetPoints(points);
  grid->Allocate(n + m);
  for (vtkIdType i = 0; i < n; ++i) grid->InsertNextCell(VTK_VERTEX, 1, &i);
  for (const auto& b : st.bonds) {
    const vtkIdType ids[2] = {b[0], b[1]};
    grid->InsertNextCell(VTK_LINE, 2, ids);
  }

  auto* pd = grid->GetPointData();
  const FieldFrame at{f, first, lab, st.species, st.mass, st.dim};
  // Counts as integers, the rest as doubles: each from particle_field (the values render colours by).
  auto counts = [&](const char* name) {
    if (!want(name)) return;
    const std::vector<double> v = particle_field(name, at);
    auto a = named<vtkIntArray>(name, 1, n);
    for (vtkIdType i = 0; i < n; ++i) a->SetValue(i, static_cast<int>(v[static_cast<std::size_t>(i)]));
    pd->AddArray(a);
  };
  counts("id");
  counts("phase");
  auto vec = [&](const char* name, auto&& get) {
    if (!want(name)) return;
    auto a = named<vtkDoubleArray>(name, 3, n);
    for (std::size_t i = 0; i < st.n; ++i) {
      double v[3] = {0, 0, 0};
      for (std::size_t c = 0; c < d; ++c) v[c] = get(i * d + c);
      a->SetTypedTuple(static_cast<vtkIdType>(i), v);
    }
    pd->AddArray(a);
  };
  vec("displacement", [&](std::size_t k) { return f.position[k] - first.position[k]; });  // cm
  vec("velocity", [&](std::size_t k) { return f.velocity[k]; });                          // cm/s
  auto scalar = [&](const char* name) {
    if (!want(name)) return;
    const std::vector<double> v = particle_field(name, at);
    auto a = named<vtkDoubleArray>(name, 1, n);
    for (std::size_t i = 0; i < st.n; ++i) a->SetValue(static_cast<vtkIdType>(i), v[i]);
    pd->AddArray(a);
  };
  scalar("speed");           // cm/s
  scalar("kinetic_energy");  // erg
  scalar("damage");
  counts("fragment_id");
  counts("fragment_size");

  auto* cd = grid->GetCellData();
  if (want("cell_kind")) {  // 0 = particle, 1 = bond
    auto a = named<vtkUnsignedCharArray>("cell_kind", 1, n + m);
    for (vtkIdType c = 0; c < n + m; ++c) a->SetValue(c, c < n ? 0 : 1);
    cd->AddArray(a);
  }
  const bool stretch = want("stretch"), brk = want("broken"), force = want("bond_force");
  if (stretch || brk || force) {
    auto s = named<vtkDoubleArray>("stretch", 1, n + m);
    auto b = named<vtkUnsignedCharArray>("broken", 1, n + m);
    auto fo = named<vtkDoubleArray>("bond_force", 1, n + m);
    for (vtkIdType c = 0; c < n; ++c) s->SetValue(c, 0.0), b->SetValue(c, 0), fo->SetValue(c, 0.0);
    for (std::size_t k = 0; k < st.bonds.size(); ++k) {
      const std::size_t i = static_cast<std::size_t>(st.bonds[k][0]), j = static_cast<std::size_t>(st.bonds[k][1]);
      double r2 = 0;
      for (std::size_t c = 0; c < d; ++c) r2 += (f.position[i * d + c] - f.position[j * d + c]) * (f.position[i * d + c] - f.position[j * d + c]);
      const double r = std::sqrt(r2);
      const PairLaw& law = st.laws[static_cast<std::size_t>(
          st.pair_law[static_cast<std::size_t>(st.species[i]) * st.nphase + static_cast<std::size_t>(st.species[j])])];
      const vtkIdType c = n + static_cast<vtkIdType>(k);
      s->SetValue(c, r / st.r0);
      b->SetValue(c, broken[k]);
      fo->SetValue(c, broken[k] ? 0.0 : law.force(r));  // dyne, > 0 repulsive
    }
    if (stretch) cd->AddArray(s);
    if (brk) cd->AddArray(b);
    if (force) cd->AddArray(fo);
  }

  vtkNew<vtkXMLUnstructuredGridWriter> w;
  w->SetInputData(grid);
  w->SetDataModeToAppended();
  w->EncodeAppendedDataOff();
  switch (compression) {
    case Compression::lz4: w->SetCompressorTypeToLZ4(); break;
    case Compression::zlib:
      w->SetCompressorTypeToZLib();
      w->SetCompressionLevel(1);  // the zlib level dominates export time; level 1 is within ~10 % of level 6's size
      break;
    case Compression::none: w->SetCompressorTypeToNone(); break;
  }
  write_file_atomically_by_name(file, [&](const fs::path& tmp) {
    w->SetFileName(tmp.c_str());
    return w->Write() == 1 && w->GetErrorCode() == 0;
  });
}

void write_pvd(const fs::path& path, const std::vector<std::pair<double, std::string>>& frames, const std::string& partial) {
  write_file_atomically(path, [&](std::ostream& o) {
    o.precision(17);
    o << "<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"0.1\" byte_order=\"LittleEndian\">\n"
         "  <Collection>\n";
    // A partial export says so where ParaView users look (the file itself), not only on the terminal.
    if (!partial.empty()) {
      std::string safe = partial;
      for (std::size_t at; (at = safe.find("--")) != std::string::npos;) safe.replace(at, 2, "- -");
      o << "    <!-- PARTIAL: " << safe << " -->\n";
    }
    for (const auto& [t, file] : frames) o << "    <DataSet timestep=\"" << t << "\" part=\"0\" file=\"" << file << "\"/>\n";
    o << "  </Collection>\n</VTKFile>\n";
  });
}

}  // namespace

ExportResult export_vtk(const std::string& run_dir, const ExportOptions& opt) {
  for (const auto& name : opt.fields)
    if (!export_fields().count(name)) throw std::invalid_argument("--fields: unknown field '" + name + "'");
  if (opt.every < 1) throw std::invalid_argument("--every: must be at least 1");
  const fs::path dir(run_dir);
  H5mdReader rd((dir / "trajectory.h5").string());
  ExportResult res;
  res.note = trajectory_caveats(rd);
  res.partial = !res.note.empty();
  Static st;
  st.n = rd.particles();
  st.dim = rd.dim();
  st.r0 = rd.parameter("r0");
  st.bonds = rd.bonds();
  st.species = rd.species();
  st.mass = rd.mass();
  st.laws = rd.laws();
  st.pair_law = rd.phase_pair_law();
  st.nphase = static_cast<std::size_t>(std::lround(std::sqrt(static_cast<double>(st.pair_law.size()))));
  BondStates states = BondStates::open(rd, opt.criterion);
  FragmentTracker tracker(st.n, st.bonds, st.mass);
  fs::create_directories(dir / "vtk");
  std::vector<std::pair<double, std::string>> written;
  TrajectoryFrame first;
  const long frames = rd.frames();
  for (long k = 0; k < frames; ++k) {
    if (!states.covers(k)) {  // a record cut short: no bond state for the frames after it
      res.partial = true;
      add_note(res.note, states.damage() + "; exported frames before it");
      break;
    }
    TrajectoryFrame f;
    try {
      f = rd.frame(k);
    } catch (const std::exception& e) {
      res.partial = true;
      add_note(res.note, "frame " + std::to_string(k) + " unreadable (" + e.what() + "); exported frames before it");
      break;
    }
    if (k == 0) first = f;
    states.advance(k, f.position);  // every frame: the distance reading is history-dependent
    const FrameLabels lab = tracker.label(states.broken());
    ++res.frames_read;
    if (k % opt.every != 0 && k != frames - 1) continue;
    char name[32];
    std::snprintf(name, sizeof name, "frame_%05ld.vtu", k);
    write_frame(dir / "vtk" / name, st, f, first, lab, states.broken(), opt.fields, opt.compression);
    written.emplace_back(f.time, std::string("vtk/") + name);
    ++res.frames_written;
  }
  write_pvd(dir / "particles.pvd", written, res.partial ? res.note : std::string());
  return res;
}

}  // namespace pmfrag::analysis
