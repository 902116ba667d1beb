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
#include <vtkSmartPointer.h>
#include <vtkUnsignedCharArray.h>
#include <vtkUnstructuredGrid.h>
#include <vtkXMLUnstructuredGridWriter.h>

#include <cmath>
#include <algorithm>
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
vtkSmartPointer<Array> named(const char* name, int components, vtkIdType tuples) {
  auto a = vtkSmartPointer<Array>::New();
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

// One frame's VTK grid, built once and refilled for every frame: the cells (a vertex per particle, a line per
// bond) never change, and reusing the arrays spares allocating and first-touching some 300 B per particle per
// frame, which at millions of particles was a third of the export's time.
class FrameGrid {
 public:
  FrameGrid(const Static& st, const std::set<std::string>& fields, Compression compression) : st_(st) {
    auto want = [&](const char* name) { return fields.empty() || fields.count(name); };
    const vtkIdType n = static_cast<vtkIdType>(st.n), m = static_cast<vtkIdType>(st.bonds.size());
    points_->SetDataTypeToDouble();
    points_->SetNumberOfPoints(n);
    grid_->SetPoints(points_);
    grid_->Allocate(n + m);
    for (vtkIdType i = 0; i < n; ++i) grid_->InsertNextCell(VTK_VERTEX, 1, &i);
    for (const auto& b : st.bonds) {
      const vtkIdType ids[2] = {b[0], b[1]};
      grid_->InsertNextCell(VTK_LINE, 2, ids);
    }
    // Point arrays in the order the files have always listed them: counts as integers, the rest as doubles.
    auto* pd = grid_->GetPointData();
    for (const char* name : {"id", "phase", "displacement", "velocity", "speed", "kinetic_energy", "damage",
                             "fragment_id", "fragment_size"}) {
      if (!want(name)) continue;
      const std::string s = name;
      if (s == "id" || s == "phase" || s == "fragment_id" || s == "fragment_size") {
        ints_.emplace_back(name, named<vtkIntArray>(name, 1, n));
        pd->AddArray(ints_.back().second);
      } else {
        doubles_.emplace_back(name, named<vtkDoubleArray>(name, s == "displacement" || s == "velocity" ? 3 : 1, n));
        pd->AddArray(doubles_.back().second);
      }
    }
    auto* cd = grid_->GetCellData();
    if (want("cell_kind")) {  // 0 = particle, 1 = bond
      kind_ = named<vtkUnsignedCharArray>("cell_kind", 1, n + m);
      for (vtkIdType c = 0; c < n + m; ++c) kind_->SetValue(c, c < n ? 0 : 1);
      cd->AddArray(kind_);
    }
    if (want("stretch")) stretch_ = named<vtkDoubleArray>("stretch", 1, n + m), cd->AddArray(stretch_);
    if (want("broken")) broken_ = named<vtkUnsignedCharArray>("broken", 1, n + m), cd->AddArray(broken_);
    if (want("bond_force")) force_ = named<vtkDoubleArray>("bond_force", 1, n + m), cd->AddArray(force_);
    for (vtkDataArray* a : {static_cast<vtkDataArray*>(stretch_), static_cast<vtkDataArray*>(broken_),
                            static_cast<vtkDataArray*>(force_)})
      if (a)
        for (vtkIdType c = 0; c < n; ++c) a->SetComponent(c, 0, 0.0);  // particles' cells carry no bond value

    writer_->SetInputData(grid_);
    writer_->SetDataModeToAppended();
    writer_->EncodeAppendedDataOff();
    switch (compression) {
      case Compression::lz4: writer_->SetCompressorTypeToLZ4(); break;
      case Compression::zlib:
        writer_->SetCompressorTypeToZLib();
        writer_->SetCompressionLevel(1);  // the zlib level dominates export time; level 1 is within ~10 % of level 6's size
        break;
      case Compression::none: writer_->SetCompressorTypeToNone(); break;
    }
  }

  void write(const fs::path& file, const TrajectoryFrame& f, const TrajectoryFrame& first, const FrameLabels& lab,
             const std::vector<std::uint8_t>& broken) {
    const std::size_t n = st_.n, d = static_cast<std::size_t>(st_.dim);
    double* xyz = static_cast<double*>(points_->GetVoidPointer(0));
    for (std::size_t i = 0; i < n; ++i)
      for (std::size_t c = 0; c < 3; ++c) xyz[3 * i + c] = c < d ? f.position[i * d + c] : 0.0;
    points_->Modified();

    const FieldFrame at{f, first, lab, st_.species, st_.mass, st_.dim};
    for (auto& [name, a] : ints_) {
      const std::vector<double> v = particle_field(name, at);
      int* out = a->GetPointer(0);
      for (std::size_t i = 0; i < n; ++i) out[i] = static_cast<int>(v[i]);
      a->Modified();
    }
    for (auto& [name, a] : doubles_) {
      double* out = a->GetPointer(0);
      if (a->GetNumberOfComponents() == 3) {  // displacement (cm) or velocity (cm/s), z = 0 in 2-D
        const bool velocity = name == "velocity";
        for (std::size_t i = 0; i < n; ++i)
          for (std::size_t c = 0; c < 3; ++c)
            out[3 * i + c] = c >= d ? 0.0 : velocity ? f.velocity[i * d + c] : f.position[i * d + c] - first.position[i * d + c];
      } else {  // speed (cm/s), kinetic_energy (erg), damage
        const std::vector<double> v = particle_field(name, at);
        std::copy(v.begin(), v.end(), out);
      }
      a->Modified();
    }
    if (stretch_ || broken_ || force_) {
      for (std::size_t k = 0; k < st_.bonds.size(); ++k) {
        const std::size_t i = static_cast<std::size_t>(st_.bonds[k][0]), j = static_cast<std::size_t>(st_.bonds[k][1]);
        double r2 = 0;
        for (std::size_t c = 0; c < d; ++c) r2 += (f.position[i * d + c] - f.position[j * d + c]) * (f.position[i * d + c] - f.position[j * d + c]);
        const double r = std::sqrt(r2);
        const vtkIdType c = static_cast<vtkIdType>(n + k);
        if (stretch_) stretch_->SetValue(c, r / st_.r0);
        if (broken_) broken_->SetValue(c, broken[k]);
        if (force_) {
          const PairLaw& law = st_.laws[static_cast<std::size_t>(
              st_.pair_law[static_cast<std::size_t>(st_.species[i]) * st_.nphase + static_cast<std::size_t>(st_.species[j])])];
          force_->SetValue(c, broken[k] ? 0.0 : law.force(r));  // dyne, > 0 repulsive
        }
      }
      for (vtkDataArray* a : {static_cast<vtkDataArray*>(stretch_), static_cast<vtkDataArray*>(broken_),
                              static_cast<vtkDataArray*>(force_)})
        if (a) a->Modified();
    }
    if (kind_) kind_->Modified();  // drops the range the last write cached, so every file is written alike
    grid_->Modified();
    write_file_atomically_by_name(file, [&](const fs::path& tmp) {
      writer_->SetFileName(tmp.c_str());
      return writer_->Write() == 1 && writer_->GetErrorCode() == 0;
    });
  }

 private:
  const Static& st_;
  vtkNew<vtkUnstructuredGrid> grid_;
  vtkNew<vtkPoints> points_;
  std::vector<std::pair<std::string, vtkSmartPointer<vtkIntArray>>> ints_;
  std::vector<std::pair<std::string, vtkSmartPointer<vtkDoubleArray>>> doubles_;
  vtkSmartPointer<vtkDoubleArray> stretch_, force_;
  vtkSmartPointer<vtkUnsignedCharArray> broken_, kind_;
  vtkNew<vtkXMLUnstructuredGridWriter> writer_;
};

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
  std::set<std::string> fields = opt.fields;
  if (!rd.has_velocity()) {  // the run's output.fields left velocities out
    static const std::set<std::string> need{"velocity", "speed", "kinetic_energy"};
    for (const auto& name : fields)
      if (need.count(name))
        throw std::invalid_argument("--fields: '" + name + "' needs velocities, and the frames of " + run_dir + " hold none "
                                    "(its scene's output.fields left them out)");
    if (fields.empty())
      for (const auto& name : export_fields())
        if (!need.count(name)) fields.insert(name);
  }
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
  make_folder(dir / "vtk");
  std::vector<std::pair<double, std::string>> written;
  FrameGrid grid(st, fields, opt.compression);
  TrajectoryFrame f, first;
  const long frames = rd.frames();
  for (long k = 0; k < frames; ++k) {
    if (!states.covers(k)) {  // a record cut short: no bond state for the frames after it
      res.partial = true;
      add_note(res.note, states.damage() + "; exported frames before it");
      break;
    }
    try {
      rd.frame(k, f);
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
    grid.write(dir / "vtk" / name, f, first, lab, states.broken());
    written.emplace_back(f.time, std::string("vtk/") + name);
    ++res.frames_written;
  }
  write_pvd(dir / "particles.pvd", written, res.partial ? res.note : std::string());
  return res;
}

}  // namespace pmfrag::analysis
