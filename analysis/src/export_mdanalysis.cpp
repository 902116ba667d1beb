#include "pmfrag/analysis/export_mdanalysis.hpp"

#include "pmfrag/analysis/fragments.hpp"
#include "pmfrag/io/atomic_file.hpp"
#include "pmfrag/io/h5md.hpp"

#include <hdf5.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <stdexcept>
#include <vector>

namespace pmfrag::analysis {

namespace fs = std::filesystem;

namespace {

// Scale factors from the trajectory's CGS units to MDAnalysis' own (Angstrom, ps): stored in them, values are
// not scaled again on reading, so each is rounded to 32 bits once only.
constexpr double angstrom_per_cm = 1e8;
constexpr double angstrom_ps_per_cm_s = 1e-4;

// Every HDF5 call is checked; the first failure names the file and what was being written.
struct Writer {
  std::string file;
  hid_t check(hid_t id, const std::string& what) const {
    if (id < 0) throw std::runtime_error(file + ": cannot write " + what);
    return id;
  }
  void check(herr_t status, const std::string& what) const {
    if (status < 0) throw std::runtime_error(file + ": cannot write " + what);
  }
  hid_t group(hid_t parent, const char* name) const {
    return check(H5Gcreate2(parent, name, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), name);
  }
  void text(hid_t obj, const char* name, const std::vector<std::string>& values, bool scalar = true) const {
    hid_t type = H5Tcopy(H5T_C_S1);
    H5Tset_size(type, H5T_VARIABLE);
    H5Tset_cset(type, H5T_CSET_UTF8);
    hsize_t n[1] = {values.size()};
    hid_t space = scalar ? H5Screate(H5S_SCALAR) : H5Screate_simple(1, n, nullptr);
    std::vector<const char*> ptrs;
    for (const auto& v : values) ptrs.push_back(v.c_str());
    hid_t a = check(H5Acreate2(obj, name, type, space, H5P_DEFAULT, H5P_DEFAULT), name);
    check(H5Awrite(a, type, ptrs.data()), name);
    H5Aclose(a), H5Sclose(space), H5Tclose(type);
  }
  void ints(hid_t obj, const char* name, const std::vector<int>& v) const {
    hsize_t n[1] = {v.size()};
    hid_t space = H5Screate_simple(1, n, nullptr);
    hid_t a = check(H5Acreate2(obj, name, H5T_NATIVE_INT, space, H5P_DEFAULT, H5P_DEFAULT), name);
    check(H5Awrite(a, H5T_NATIVE_INT, v.data()), name);
    H5Aclose(a), H5Sclose(space);
  }
  template <class T>
  void array(hid_t parent, const char* name, hid_t mem, hid_t stored, const std::vector<T>& v) const {
    hsize_t n[1] = {v.size()};
    hid_t space = H5Screate_simple(1, n, nullptr);
    hid_t d = check(H5Dcreate2(parent, name, stored, space, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), name);
    check(H5Dwrite(d, mem, H5S_ALL, H5S_ALL, H5P_DEFAULT, v.data()), name);
    H5Dclose(d), H5Sclose(space);
  }
};

// One time-dependent H5MD element (step, time, value N x 3), grown a frame at a time.
struct Element {
  hid_t group = -1, step = -1, time = -1, value = -1;
  hsize_t n = 0;
  void create(const Writer& w, hid_t parent, const char* name, hsize_t particles, const char* unit) {
    n = particles;
    group = w.group(parent, name);
    const hsize_t zero1[1] = {0}, unlimited1[1] = {H5S_UNLIMITED}, chunk1[1] = {256};
    const hsize_t zero3[3] = {0, particles, 3}, unlimited3[3] = {H5S_UNLIMITED, particles, 3},
                  chunk3[3] = {1, particles, 3};
    auto make = [&](const char* what, int rank, const hsize_t* dims, const hsize_t* max, const hsize_t* chunk,
                    hid_t type) {
      hid_t space = H5Screate_simple(rank, dims, max);
      hid_t plist = H5Pcreate(H5P_DATASET_CREATE);
      H5Pset_chunk(plist, rank, chunk);
      hid_t d = w.check(H5Dcreate2(group, what, type, space, H5P_DEFAULT, plist, H5P_DEFAULT),
                        std::string(name) + "/" + what);
      H5Pclose(plist), H5Sclose(space);
      return d;
    };
    step = make("step", 1, zero1, unlimited1, chunk1, H5T_STD_I64LE);
    time = make("time", 1, zero1, unlimited1, chunk1, H5T_IEEE_F64LE);
    value = make("value", 3, zero3, unlimited3, chunk3, H5T_IEEE_F64LE);
    w.text(time, "unit", {"s"});
    w.text(value, "unit", {unit});
  }
  void append(const Writer& w, hsize_t k, long s, double t, const std::vector<double>& xyz, const char* what) {
    auto one = [&](hid_t d, int rank, const hsize_t* size, const hsize_t* at, const hsize_t* count, hid_t mem,
                   const void* data) {
      w.check(H5Dset_extent(d, size), what);
      hid_t file_space = H5Dget_space(d);
      H5Sselect_hyperslab(file_space, H5S_SELECT_SET, at, nullptr, count, nullptr);
      hid_t mem_space = H5Screate_simple(rank, count, nullptr);
      w.check(H5Dwrite(d, mem, mem_space, file_space, H5P_DEFAULT, data), what);
      H5Sclose(mem_space), H5Sclose(file_space);
    };
    const hsize_t size1[1] = {k + 1}, at1[1] = {k}, count1[1] = {1};
    const hsize_t size3[3] = {k + 1, n, 3}, at3[3] = {k, 0, 0}, count3[3] = {1, n, 3};
    const long long s64 = s;
    one(step, 1, size1, at1, count1, H5T_NATIVE_LLONG, &s64);
    one(time, 1, size1, at1, count1, H5T_NATIVE_DOUBLE, &t);
    one(value, 3, size3, at3, count3, H5T_NATIVE_DOUBLE, xyz.data());
  }
  void close() {
    for (hid_t* id : {&value, &time, &step})
      if (*id >= 0) H5Dclose(*id), *id = -1;
    if (group >= 0) H5Gclose(group), group = -1;
  }
};

// N x dim values in `from` -> N x 3 in `to`, scaled, z = 0 in 2-D.
void to_xyz(const std::vector<double>& from, int dim, double scale, std::vector<double>& to) {
  const std::size_t n = from.size() / static_cast<std::size_t>(dim);
  to.assign(3 * n, 0.0);
  for (std::size_t i = 0; i < n; ++i)
    for (int c = 0; c < dim; ++c) to[3 * i + c] = from[dim * i + c] * scale;
}

}  // namespace

MdanalysisExportResult export_mdanalysis(const std::string& run_dir, const MdanalysisExportOptions& opt) {
  if (opt.every < 1) throw std::invalid_argument("--every: must be at least 1");
  const fs::path dir(run_dir);
  const H5mdReader rd((dir / "trajectory.h5").string());
  MdanalysisExportResult res;
  res.note = trajectory_caveats(rd);
  res.partial = !res.note.empty();
  const fs::path out_dir = dir / "mdanalysis", target = out_dir / "trajectory.h5md", part = out_dir / "trajectory.h5md.part";
  make_folder(out_dir);
  res.path = target.string();
  const Writer w{target.string()};
  const hsize_t n = rd.particles();
  hid_t file = H5Fcreate(part.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT);
  if (file < 0)
    throw std::runtime_error(part.string() + ": cannot create: " + std::strerror(errno ? errno : EIO));
  Element position, velocity;
  hid_t particles = -1, group = -1;
  try {
    hid_t h5md = w.group(file, "h5md");
    w.ints(h5md, "version", {1, 1});
    hid_t author = w.group(h5md, "author"), creator = w.group(h5md, "creator");
    w.text(author, "name", {"pmfrag user"});
    w.text(creator, "name", {"pmfrag"});
    w.text(creator, "version", {"0.1.0"});
    H5Gclose(author), H5Gclose(creator), H5Gclose(h5md);

    particles = w.group(file, "particles");
    group = w.group(particles, "trajectory");
    hid_t box = w.group(group, "box");
    w.ints(box, "dimension", {3});
    w.text(box, "boundary", {"none", "none", "none"}, false);
    H5Gclose(box);
    w.array(group, "species", H5T_NATIVE_INT, H5T_STD_I32LE, rd.species());
    {
      hid_t mass_space = H5Screate_simple(1, &n, nullptr);
      const std::vector<double> mass = rd.mass();
      hid_t d = w.check(H5Dcreate2(group, "mass", H5T_IEEE_F64LE, mass_space, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), "mass");
      w.check(H5Dwrite(d, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, mass.data()), "mass");
      w.text(d, "unit", {"g"});
      H5Dclose(d), H5Sclose(mass_space);
    }
    position.create(w, group, "position", n, "Angstrom");
    if (rd.has_velocity()) velocity.create(w, group, "velocity", n, "Angstrom ps-1");

    TrajectoryFrame f;
    std::vector<double> xyz;
    const long frames = rd.frames();
    hsize_t k_out = 0;
    for (long k = 0; k < frames; ++k) {
      if (k % opt.every != 0 && k != frames - 1) continue;
      try {
        rd.frame(k, f);
      } catch (const std::exception& e) {
        res.partial = true;
        add_note(res.note, "frame " + std::to_string(k) + " unreadable (" + e.what() + "); wrote the frames before it");
        break;
      }
      ++res.frames_read;
      to_xyz(f.position, rd.dim(), angstrom_per_cm, xyz);
      position.append(w, k_out, f.step, f.time, xyz, "position");
      if (rd.has_velocity()) {
        to_xyz(f.velocity, rd.dim(), angstrom_ps_per_cm_s, xyz);
        velocity.append(w, k_out, f.step, f.time, xyz, "velocity");
      }
      ++k_out;
    }
    res.frames_written = static_cast<long>(k_out);
    position.close(), velocity.close();
    H5Gclose(group), group = -1;
    H5Gclose(particles), particles = -1;

    hid_t params = w.group(file, "parameters");
    w.text(params, "source", {(dir / "trajectory.h5").string()});
    w.text(params, "units",
           {"positions Angstrom = cm x 1e8; velocities Angstrom ps-1 = cm/s x 1e-4; time s; mass g" +
            std::string(rd.dim() == 2 ? "; a 2-D run: z = 0" : "")});
    if (res.partial) w.text(params, "partial", {res.note});
    H5Gclose(params);
    if (H5Fflush(file, H5F_SCOPE_GLOBAL) < 0) throw std::runtime_error(part.string() + ": cannot write (flush failed)");
    if (H5Fclose(file) < 0) {
      file = -1;
      throw std::runtime_error(part.string() + ": cannot write (close failed)");
    }
    file = -1;
    std::error_code ec;
    fs::rename(part, target, ec);
    if (ec) throw std::runtime_error(target.string() + ": cannot rename from " + part.filename().string() + ": " + ec.message());
  } catch (...) {
    position.close(), velocity.close();
    if (group >= 0) H5Gclose(group);
    if (particles >= 0) H5Gclose(particles);
    if (file >= 0) H5Fclose(file);
    std::error_code ec;
    fs::remove(part, ec);  // whole or absent: a previous file at `target` stays as it was
    throw;
  }
  return res;
}

}  // namespace pmfrag::analysis
