#include "pmfrag/io/h5md.hpp"

#include "pmfrag/io/atomic_file.hpp"

#include <hdf5.h>
#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <cmath>
#include <sstream>
#include <cerrno>
#include <stdexcept>

namespace pmfrag {

namespace {

// HDF5 installs an atexit hook that closes what is still open. After a write failed (a full disk) it
// crashed there closing the broken file (HDF5 1.10: a segmentation fault after the error was printed), so
// the library is told not to: every file is closed explicitly, and the system releases what remains.
// Its error stack is not printed either: our messages name the file and the cause (one line each).
// `pmfrag --verbose` turns it back on (show_library_diagnostics).
bool hdf5_stack_shown = false;

herr_t print_hdf5_stack(hid_t stack, void* stream) { return H5Eprint2(stack, static_cast<FILE*>(stream)); }

// HDF5 keeps this setting per thread in thread-safe builds, so each entry point sets it again.
void hdf5_stack_as_asked() {
  if (hdf5_stack_shown)
    H5Eset_auto2(H5E_DEFAULT, print_hdf5_stack, stderr);
  else
    H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
}

[[maybe_unused]] const bool hdf5_quiet = [] {
  H5dont_atexit();
  hdf5_stack_as_asked();
  return true;
}();

void check(herr_t status, const char* what) {
  if (status < 0) throw std::runtime_error(std::string("HDF5: ") + what + " failed");
}
hid_t checked(hid_t id, const char* what) {
  if (id < 0) throw std::runtime_error(std::string("HDF5: ") + what + " failed");
  return id;
}

hid_t make_group(hid_t parent, const char* name) { return checked(H5Gcreate2(parent, name, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), name); }

// Text attributes are variable-length UTF-8, as the H5MD reference writers store them: h5py reads them as
// str, and MDAnalysis' unit parser compares them with its own names (fixed-length bytes it reads as b'...').
hid_t utf8_text_type() {
  hid_t type = H5Tcopy(H5T_C_S1);
  H5Tset_size(type, H5T_VARIABLE);
  H5Tset_cset(type, H5T_CSET_UTF8);
  return type;
}

void string_attribute(hid_t obj, const char* name, const std::string& value) {
  hid_t type = utf8_text_type();
  hid_t space = H5Screate(H5S_SCALAR);
  hid_t a = checked(H5Acreate2(obj, name, type, space, H5P_DEFAULT, H5P_DEFAULT), name);
  const char* text = value.c_str();
  check(H5Awrite(a, type, &text), name);
  H5Aclose(a), H5Sclose(space), H5Tclose(type);
}

void int_array_attribute(hid_t obj, const char* name, const std::vector<int>& v) {
  hsize_t dims[1] = {v.size()};
  hid_t space = H5Screate_simple(1, dims, nullptr);
  hid_t a = checked(H5Acreate2(obj, name, H5T_NATIVE_INT, space, H5P_DEFAULT, H5P_DEFAULT), name);
  check(H5Awrite(a, H5T_NATIVE_INT, v.data()), name);
  H5Aclose(a), H5Sclose(space);
}

void string_dataset(hid_t parent, const char* name, const std::string& value) {
  hid_t type = H5Tcopy(H5T_C_S1);
  H5Tset_size(type, value.empty() ? 1 : value.size());
  hid_t space = H5Screate(H5S_SCALAR);
  hid_t d = checked(H5Dcreate2(parent, name, type, space, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), name);
  check(H5Dwrite(d, type, H5S_ALL, H5S_ALL, H5P_DEFAULT, value.c_str()), name);
  H5Dclose(d), H5Sclose(space), H5Tclose(type);
}

template <class T>
hid_t native();
template <>
hid_t native<double>() { return H5T_NATIVE_DOUBLE; }
template <>
hid_t native<int>() { return H5T_NATIVE_INT; }
template <>
hid_t native<long>() { return H5T_NATIVE_LONG; }

template <class T>
void array_dataset(hid_t parent, const char* name, const T* data, std::vector<hsize_t> dims) {
  hid_t space = H5Screate_simple(static_cast<int>(dims.size()), dims.data(), nullptr);
  hid_t d = checked(H5Dcreate2(parent, name, native<T>(), space, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), name);
  if (data) check(H5Dwrite(d, native<T>(), H5S_ALL, H5S_ALL, H5P_DEFAULT, data), name);
  H5Dclose(d), H5Sclose(space);
}

template <class T>
void array_dataset(hid_t parent, const char* name, const std::vector<T>& v, std::vector<hsize_t> dims) {
  array_dataset(parent, name, v.empty() ? nullptr : v.data(), std::move(dims));
}

void scalar_dataset(hid_t parent, const char* name, double value) { array_dataset<double>(parent, name, {value}, {}); }

// An H5MD time-dependent element: step, time, value, each growing along the first axis.
constexpr hsize_t frame_chunk_rows = 65536;  ///< particles per chunk of a frame (1 MiB of 2-D doubles)

struct Series {
  hid_t group = -1, step = -1, time = -1, value = -1, type = -1;
  std::vector<hsize_t> shape;  // per-frame shape of value

  Series() = default;
  // `stored`: the value's type on disk, if not `value_type` (HDF5 converts on write); `gzip`: deflate level.
  Series(hid_t parent, const char* name, std::vector<hsize_t> frame_shape, hid_t value_type, hid_t stored = -1,
         int gzip = 0)
      : type(value_type), shape(std::move(frame_shape)) {
    group = make_group(parent, name);
    step = grow(group, "step", H5T_NATIVE_LONG, {});
    time = grow(group, "time", H5T_NATIVE_DOUBLE, {});
    value = grow(group, "value", stored >= 0 ? stored : type, shape, gzip);
    string_attribute(time, "unit", "s");
  }
  // Reopens an existing element and cuts it to `keep` frames.
  static Series reopen(hid_t parent, const char* name, hid_t value_type, hsize_t keep) {
    Series s;
    s.type = value_type;
    s.group = checked(H5Gopen2(parent, name, H5P_DEFAULT), name);
    s.step = checked(H5Dopen2(s.group, "step", H5P_DEFAULT), "step");
    s.time = checked(H5Dopen2(s.group, "time", H5P_DEFAULT), "time");
    s.value = checked(H5Dopen2(s.group, "value", H5P_DEFAULT), "value");
    hid_t space = H5Dget_space(s.value);
    const int rank = H5Sget_simple_extent_ndims(space);
    std::vector<hsize_t> dims(static_cast<std::size_t>(rank));
    H5Sget_simple_extent_dims(space, dims.data(), nullptr);
    H5Sclose(space);
    s.shape.assign(dims.begin() + 1, dims.end());
    for (hid_t d : {s.step, s.time, s.value}) {
      std::vector<hsize_t> cut = dims;
      if (d != s.value) cut.resize(1);
      cut[0] = keep;
      check(H5Dset_extent(d, cut.data()), "truncate");
    }
    return s;
  }
  // A frame's rows go in chunks of at most frame_chunk_rows particles: HDF5 runs a chunk's filters (the
  // checksum, deflate) on a buffer of the whole chunk, so with a chunk per frame it held a copy of every frame
  // while writing it (16 B a particle in 2-D); and the frame's velocities can be computed a chunk at a time.
  static hid_t grow(hid_t g, const char* name, hid_t t, const std::vector<hsize_t>& frame, int gzip = 0) {
    std::vector<hsize_t> dims{0}, maxd{H5S_UNLIMITED}, chunk{frame.empty() ? hsize_t(256) : hsize_t(1)};
    for (auto s : frame) dims.push_back(s), maxd.push_back(s), chunk.push_back(s);
    if (chunk.size() > 1) chunk[1] = std::max<hsize_t>(1, std::min(chunk[1], frame_chunk_rows));
    hid_t space = H5Screate_simple(static_cast<int>(dims.size()), dims.data(), maxd.data());
    hid_t plist = H5Pcreate(H5P_DATASET_CREATE);
    H5Pset_chunk(plist, static_cast<int>(chunk.size()), chunk.data());
    // Per-frame chunks are written once: a checksum lets a reader tell an altered frame from a good one.
    // (Series of scalars share chunks of 256 that are rewritten in place, so they stay unfiltered.)
    if (!frame.empty()) H5Pset_fletcher32(plist);
    if (gzip > 0) {
      // The shuffle groups the values' bytes by significance, which is what lets deflate find runs in floats.
      if (H5Zfilter_avail(H5Z_FILTER_DEFLATE) <= 0)
        throw std::runtime_error("output.gzip: this HDF5 library has no deflate filter");
      H5Pset_shuffle(plist);
      H5Pset_deflate(plist, static_cast<unsigned>(gzip));
    }
    hid_t d = checked(H5Dcreate2(g, name, t, space, H5P_DEFAULT, plist, H5P_DEFAULT), name);
    H5Pclose(plist), H5Sclose(space);
    return d;
  }
  static void append(hid_t d, hsize_t index, const std::vector<hsize_t>& frame, hid_t t, const void* data) {
    std::vector<hsize_t> dims{index + 1}, start{index}, count{1};
    for (auto s : frame) dims.push_back(s), start.push_back(0), count.push_back(s);
    check(H5Dset_extent(d, dims.data()), "extend");
    hid_t fspace = H5Dget_space(d);
    H5Sselect_hyperslab(fspace, H5S_SELECT_SET, start.data(), nullptr, count.data(), nullptr);
    hid_t mspace = H5Screate_simple(static_cast<int>(count.size()), count.data(), nullptr);
    check(H5Dwrite(d, t, mspace, fspace, H5P_DEFAULT, data), "write frame");
    H5Sclose(mspace), H5Sclose(fspace);
  }
  void append(hsize_t index, long s, double t, const void* data) {
    append(step, index, {}, H5T_NATIVE_LONG, &s);
    append(time, index, {}, H5T_NATIVE_DOUBLE, &t);
    append(value, index, shape, type, data);
  }
  // The same for an N x dim frame of doubles whose rows come from `rows` a chunk at a time (one chunk's buffer).
  void append_rows(hsize_t index, long s, double t, const H5mdWriter::FrameRows& rows) {
    append(step, index, {}, H5T_NATIVE_LONG, &s);
    append(time, index, {}, H5T_NATIVE_DOUBLE, &t);
    const hsize_t n = shape.at(0), dim = shape.at(1);
    std::vector<hsize_t> dims{index + 1, n, dim};
    check(H5Dset_extent(value, dims.data()), "extend");
    std::vector<double> buffer(static_cast<std::size_t>(std::min(n, frame_chunk_rows) * dim));
    for (hsize_t first = 0; first < n; first += frame_chunk_rows) {
      const hsize_t count = std::min(frame_chunk_rows, n - first);
      rows(static_cast<std::size_t>(first), static_cast<std::size_t>(count), buffer.data());
      const hsize_t start[3] = {index, first, 0}, cnt[3] = {1, count, dim};
      hid_t fspace = H5Dget_space(value);
      H5Sselect_hyperslab(fspace, H5S_SELECT_SET, start, nullptr, cnt, nullptr);
      hid_t mspace = H5Screate_simple(3, cnt, nullptr);
      const herr_t ok = H5Dwrite(value, H5T_NATIVE_DOUBLE, mspace, fspace, H5P_DEFAULT, buffer.data());
      H5Sclose(mspace), H5Sclose(fspace);
      check(ok, "write frame");
    }
  }
  void close() {
    if (group < 0) return;
    H5Dclose(step), H5Dclose(time), H5Dclose(value), H5Gclose(group);
    group = -1;
  }
};

// The bond record: one row per event, in columns that grow together. Rows are few against particles (events
// are sparse), so they go in chunks of many rows, rewritten in place as they fill (unfiltered, like the
// scalar series).
constexpr hsize_t event_chunk = 1024;
const char* const event_columns[] = {"step", "time", "bond", "re_formed"};

hid_t grow_rows(hid_t g, const char* name, hid_t t) {
  hsize_t dims[1] = {0}, maxd[1] = {H5S_UNLIMITED}, chunk[1] = {event_chunk};
  hid_t space = H5Screate_simple(1, dims, maxd);
  hid_t plist = H5Pcreate(H5P_DATASET_CREATE);
  H5Pset_chunk(plist, 1, chunk);
  hid_t d = checked(H5Dcreate2(g, name, t, space, H5P_DEFAULT, plist, H5P_DEFAULT), name);
  H5Pclose(plist), H5Sclose(space);
  return d;
}

void append_rows(hid_t d, hsize_t at, hsize_t count, hid_t t, const void* data) {
  hsize_t dims[1] = {at + count}, start[1] = {at}, n[1] = {count};
  check(H5Dset_extent(d, dims), "extend bond record");
  hid_t fspace = H5Dget_space(d);
  H5Sselect_hyperslab(fspace, H5S_SELECT_SET, start, nullptr, n, nullptr);
  hid_t mspace = H5Screate_simple(1, n, nullptr);
  check(H5Dwrite(d, t, mspace, fspace, H5P_DEFAULT, data), "write bond record");
  H5Sclose(mspace), H5Sclose(fspace);
}

void write_law(hid_t g, const PairLaw& law, double mass) {
  scalar_dataset(g, "p", law.p);
  scalar_dataset(g, "q", law.q);
  scalar_dataset(g, "G", law.G);
  scalar_dataset(g, "H", law.H);
  scalar_dataset(g, "mass", mass);
}

}  // namespace

// The time series under /observables, all in erg except the pair count.
const char* const observable_names[] = {"kinetic_energy", "potential_energy", "total_energy", "boundary_work",
                                        "bond_break_energy", "energy_balance", "pairs_beyond_cutoff"};

namespace {
// A trajectory open for writing has a sidecar, PATH.writing, removed once HDF5 has closed the file. One left
// behind says the writer died (SIGKILL, power loss) between flushes: HDF5 may have put some metadata of the
// next frame on disk and not the rest, so appending to that file can fail frames later. --resume then rebuilds.
std::string writing_marker(const std::string& path) { return path + ".writing"; }
void put_writing_marker(const std::string& path) {
  const std::string marker = writing_marker(path);
  std::FILE* f = std::fopen(marker.c_str(), "w");
  if (!f || std::fclose(f) != 0) throw std::runtime_error(marker + ": cannot write: " + std::strerror(errno != 0 ? errno : EIO));
}
}  // namespace

struct H5mdWriter::Impl {
  hid_t file = -1;
  std::string part, path;  ///< the temporary name until the first frame is written, and the final one
  hid_t particles = -1;
  hid_t record = -1;                        ///< /connectivity/broken_bonds
  hid_t columns[4] = {-1, -1, -1, -1};      ///< its step, time, bond, re_formed
  Series rows_at_frame;                     ///< per frame: rows of the record up to that frame's step
  Series position, velocity;
  std::map<std::string, Series> observables;
  hid_t obs_group = -1;
  /// Runs `body`, which writes; an HDF5 call that fails there becomes one line naming the file and the system's
  /// cause. HDF5 does not pass on why a write failed; the errno of its last system call says (cleared first).
  template <class F>
  void writing(F&& body) const {
    errno = 0;
    try {
      body();
    } catch (const std::runtime_error&) {
      const int err = errno;
      if (err == 0) throw;  // not a system error: HDF5's own message is the best there is
      throw std::runtime_error((part.empty() ? path : part) + ": cannot write: " + std::strerror(err));
    }
  }
};

H5mdWriter::H5mdWriter(const std::string& path, const System& sys, const Scene& scene, const RunParameters& run)
    : impl_(std::make_unique<Impl>()) {
  auto& m = *impl_;
  // Created under a temporary name and renamed once its metadata and first frame are on disk (write_frame): a
  // trajectory.h5 that exists holds at least one whole frame, even if the run is killed at once.
  const std::string part = path + ".part";
  m.part = part, m.path = path;
  put_writing_marker(path);
  errno = 0;
  m.file = H5Fcreate(part.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT);
  if (m.file < 0) {
    const int err = errno != 0 ? errno : EIO;
    std::remove(writing_marker(path).c_str());
    throw std::runtime_error(part + ": cannot create the trajectory: " + std::strerror(err));
  }
  try {
    m.writing([&] { create(sys, scene, run); });
  } catch (const std::runtime_error& e) {
    std::remove(part.c_str());  // the destructor does not run for a constructor that throws
    std::remove(writing_marker(path).c_str());
    throw std::runtime_error(std::string(e.what()) + " (no frame was written)");
  }
}

void H5mdWriter::create(const System& sys, const Scene& scene, const RunParameters& run) {
  auto& m = *impl_;
  const hsize_t n = sys.size(), dim = static_cast<hsize_t>(sys.dim);

  hid_t h5md = make_group(m.file, "h5md");
  int_array_attribute(h5md, "version", {1, 1});
  hid_t author = make_group(h5md, "author");
  string_attribute(author, "name", "pmfrag user");
  hid_t creator = make_group(h5md, "creator");
  string_attribute(creator, "name", "pmfrag");
  string_attribute(creator, "version", "0.1.0");
  H5Gclose(author), H5Gclose(creator), H5Gclose(h5md);

  hid_t parts = make_group(m.file, "particles");
  m.particles = make_group(parts, "all");
  H5Gclose(parts);
  hid_t box = make_group(m.particles, "box");
  int_array_attribute(box, "dimension", {sys.dim});
  {
    // boundary: "none" per dimension (the body is free in space)
    hid_t type = utf8_text_type();
    hsize_t d[1] = {dim};
    hid_t space = H5Screate_simple(1, d, nullptr);
    hid_t a = checked(H5Acreate2(box, "boundary", type, space, H5P_DEFAULT, H5P_DEFAULT), "boundary");
    const std::vector<const char*> none(dim, "none");
    check(H5Awrite(a, type, none.data()), "boundary");
    H5Aclose(a), H5Sclose(space), H5Tclose(type);
  }
  H5Gclose(box);
  // Frames in single precision are stored as IEEE 32-bit floats; every reader asks for doubles and HDF5
  // converts, so nothing downstream changes.
  const hid_t stored = scene.output.single_precision ? H5T_IEEE_F32LE : H5T_IEEE_F64LE;
  const int gzip = scene.output.gzip_level;
  m.position = Series(m.particles, "position", {n, dim}, H5T_NATIVE_DOUBLE, stored, gzip);
  string_attribute(m.position.value, "unit", "cm");
  if (scene.output.velocity) {  // output.fields may leave it out
    m.velocity = Series(m.particles, "velocity", {n, dim}, H5T_NATIVE_DOUBLE, stored, gzip);
    string_attribute(m.velocity.value, "unit", "cm s-1");
  }
  std::vector<int> ids(n);
  std::vector<double> mass(n);
  for (std::size_t i = 0; i < n; ++i) ids[i] = static_cast<int>(i), mass[i] = sys.phase_mass[static_cast<std::size_t>(sys.phase[i])];
  array_dataset(m.particles, "species", sys.phase, {n});
  array_dataset(m.particles, "id", ids, {n});
  array_dataset(m.particles, "mass", mass, {n});
  array_dataset(m.particles, "body", sys.body, {n});
  if (sys.held.size() == n) array_dataset(m.particles, "held", sys.held, {n});
  array_dataset(m.particles, "site", sys.site, {n});

  hid_t conn = make_group(m.file, "connectivity");
  std::vector<int> flat;
  for (const auto& b : sys.bonds) flat.push_back(b[0]), flat.push_back(b[1]);
  array_dataset(conn, "bonds", flat, {sys.bonds.size(), 2});
  {
    hid_t d = H5Dopen2(conn, "bonds", H5P_DEFAULT);
    string_attribute(d, "particles_group", "/particles/all");
    H5Dclose(d);
  }
  {
    const std::string model = scene.pair ? (scene.pair->model == PairModel::bonded ? "bonded" : "cutoff") : "none";
    m.record = make_group(conn, "broken_bonds");
    string_attribute(m.record, "model", model);
    string_attribute(m.record, "description",
                     model == "cutoff" ? "each time a bond of /connectivity/bonds leaves D (re_formed = 0) or comes back "
                                         "within D (re_formed = 1), at the first step showing it"
                                       : "each bond of /connectivity/bonds that broke (longer than D, for good), at the "
                                         "first step showing it");
    m.columns[0] = grow_rows(m.record, "step", H5T_NATIVE_LONG);
    m.columns[1] = grow_rows(m.record, "time", H5T_NATIVE_DOUBLE);
    string_attribute(m.columns[1], "unit", "s");
    m.columns[2] = grow_rows(m.record, "bond", H5T_NATIVE_LONG);
    m.columns[3] = grow_rows(m.record, "re_formed", H5T_NATIVE_INT8);
    m.rows_at_frame = Series(m.record, "rows_at_frame", {}, H5T_NATIVE_LONG);
  }
  H5Gclose(conn);

  m.obs_group = make_group(m.file, "observables");
  for (const char* name : observable_names) {
    m.observables.emplace(name, Series(m.obs_group, name, {}, H5T_NATIVE_DOUBLE));
    if (std::string(name) != "pairs_beyond_cutoff") string_attribute(m.observables[name].value, "unit", "erg");
  }

  hid_t par = make_group(m.file, "parameters");
  string_dataset(par, "scene", scene.recorded_text());
  string_dataset(par, "scene_file", scene.file);
  {
    std::string joined;
    for (const auto& o : scene.overrides) joined += o + "\n";
    string_dataset(par, "overrides", joined);
  }
  scalar_dataset(par, "dt", run.dt);
  scalar_dataset(par, "dt_limit", run.dt_limit);
  scalar_dataset(par, "end", run.end);
  scalar_dataset(par, "frame_every_steps", static_cast<double>(run.frame_every));
  scalar_dataset(par, "dt_adaptive", run.adaptive ? 1.0 : 0.0);
  scalar_dataset(par, "r0", sys.r0);
  scalar_dataset(par, "cutoff", sys.cutoff);
  scalar_dataset(par, "r_min", sys.r_min);
  scalar_dataset(par, "dimension", sys.dim);
  string_dataset(par, "pair_model", scene.pair ? (scene.pair->model == PairModel::bonded ? "bonded" : "cutoff") : "none");
  {
    // Every law and which phase pair uses it, so readers can evaluate bond forces (export, analysis).
    std::vector<double> laws;
    for (const auto& l : sys.laws) laws.insert(laws.end(), {double(l.p), double(l.q), l.G, l.H});
    array_dataset(par, "laws", laws, {sys.laws.size(), 4});
    const hsize_t np = sys.phase_names.size();
    array_dataset(par, "phase_pair_law", sys.phase_pair_law, {np, np});
  }
  if (sys.phase_names.size() == 1) {
    write_law(par, sys.laws.front(), sys.phase_mass.front());
  } else {
    hid_t phases = make_group(par, "phases");
    for (std::size_t k = 0; k < sys.phase_names.size(); ++k) {
      hid_t g = make_group(phases, sys.phase_names[k].c_str());
      write_law(g, sys.law(static_cast<int>(k), static_cast<int>(k)), sys.phase_mass[k]);
      H5Gclose(g);
    }
    H5Gclose(phases);
  }
  H5Gclose(par);
  check(H5Fflush(m.file, H5F_SCOPE_GLOBAL), "flush");
}

H5mdWriter::H5mdWriter(const std::string& path, long keep_frames, long keep_events) : impl_(std::make_unique<Impl>()) {
  auto& m = *impl_;
  hdf5_stack_as_asked();  // a missing record is reported below, in one line
  m.path = path;
  put_writing_marker(path);
  m.file = H5Fopen(path.c_str(), H5F_ACC_RDWR, H5P_DEFAULT);
  if (m.file < 0) throw std::runtime_error(path + ": cannot reopen trajectory to resume");
  const hsize_t keep = static_cast<hsize_t>(keep_frames);
  m.record = H5Gopen2(m.file, "/connectivity/broken_bonds", H5P_DEFAULT);
  if (m.record < 0)
    throw std::runtime_error(path + ": has no /connectivity/broken_bonds (written by an older pmfrag): cannot resume; "
                             "run the scene again with --force");
  for (int c = 0; c < 4; ++c) {
    m.columns[c] = checked(H5Dopen2(m.record, event_columns[c], H5P_DEFAULT), event_columns[c]);
    hsize_t dims[1] = {static_cast<hsize_t>(keep_events)};
    check(H5Dset_extent(m.columns[c], dims), "truncate bond record");
  }
  m.rows_at_frame = Series::reopen(m.record, "rows_at_frame", H5T_NATIVE_LONG, keep);
  events_ = keep_events;
  if (H5Lexists(m.file, "/parameters/incomplete", H5P_DEFAULT) > 0)  // resumed: no longer short of its end
    H5Ldelete(m.file, "/parameters/incomplete", H5P_DEFAULT);
  m.particles = checked(H5Gopen2(m.file, "/particles/all", H5P_DEFAULT), "particles");
  m.position = Series::reopen(m.particles, "position", H5T_NATIVE_DOUBLE, keep);
  if (H5Lexists(m.particles, "velocity", H5P_DEFAULT) > 0)
    m.velocity = Series::reopen(m.particles, "velocity", H5T_NATIVE_DOUBLE, keep);
  m.obs_group = checked(H5Gopen2(m.file, "/observables", H5P_DEFAULT), "observables");
  for (const char* name : observable_names) m.observables.emplace(name, Series::reopen(m.obs_group, name, H5T_NATIVE_DOUBLE, keep));
  frames_ = keep_frames;
  H5Fflush(m.file, H5F_SCOPE_GLOBAL);
}

H5mdWriter::~H5mdWriter() {
  try {
    close();
    if (impl_ && !impl_->part.empty()) std::remove(impl_->part.c_str());  // no frame was written: nothing to keep
  } catch (...) {
  }
}

void H5mdWriter::write_frame(long step, double time, const std::vector<double>& position,
                             const std::vector<double>& velocity, const Observables& obs) {
  write_frame(step, time, position.data(), velocity.data(), obs);
}

bool H5mdWriter::writes_velocity() const { return impl_->velocity.group >= 0; }

void H5mdWriter::write_frame(long step, double time, const double* position, const double* velocity,
                             const Observables& obs) {
  if (impl_->velocity.group >= 0 && !velocity)
    throw std::logic_error(impl_->path + ": a frame without the velocities this trajectory stores");
  const std::size_t dim = impl_->velocity.group >= 0 ? static_cast<std::size_t>(impl_->velocity.shape.at(1)) : 0;
  write_frame(step, time, position, FrameRows([&](std::size_t first, std::size_t count, double* out) {
                std::copy(velocity + first * dim, velocity + (first + count) * dim, out);
              }),
              obs);
}

void H5mdWriter::write_frame(long step, double time, const double* position, const FrameRows& velocity,
                             const Observables& obs) {
  auto& m = *impl_;
  if (m.velocity.group >= 0 && !velocity)
    throw std::logic_error(m.path + ": a frame without the velocities this trajectory stores");
  m.writing([&] { append_frame(step, time, position, velocity, obs); });
  flush();
  ++frames_;  // counted once it is on disk: a failed frame is not among the frames() that are whole
  if (!m.part.empty()) {  // the first frame is whole: the trajectory may appear under its name
    if (std::rename(m.part.c_str(), m.path.c_str()) != 0)
      throw std::runtime_error(m.path + ": cannot rename from " + m.part + ": " + std::strerror(errno));
    m.part.clear();
  }
}

void H5mdWriter::append_frame(long step, double time, const double* position, const FrameRows& velocity,
                              const Observables& obs) {
  auto& m = *impl_;
  const hsize_t k = static_cast<hsize_t>(frames_);
  m.position.append(k, step, time, position);
  if (m.velocity.group >= 0) m.velocity.append_rows(k, step, time, velocity);
  const double total = obs.kinetic + obs.potential;
  const double beyond = static_cast<double>(obs.pairs_beyond_cutoff);
  const double balance = obs.balance();
  m.observables["kinetic_energy"].append(k, step, time, &obs.kinetic);
  m.observables["potential_energy"].append(k, step, time, &obs.potential);
  m.observables["total_energy"].append(k, step, time, &total);
  m.observables["boundary_work"].append(k, step, time, &obs.boundary_work);
  m.observables["bond_break_energy"].append(k, step, time, &obs.bond_break_energy);
  m.observables["energy_balance"].append(k, step, time, &balance);
  m.observables["pairs_beyond_cutoff"].append(k, step, time, &beyond);
  m.rows_at_frame.append(k, step, time, &events_);
}

void H5mdWriter::append_bond_events(const std::vector<BondEvent>& events) {
  if (events.empty()) return;
  auto& m = *impl_;
  const hsize_t n = events.size(), at = static_cast<hsize_t>(events_);
  std::vector<long> step(n), bond(n);
  std::vector<double> time(n);
  std::vector<std::int8_t> re_formed(n);
  for (std::size_t k = 0; k < n; ++k)
    step[k] = events[k].step, time[k] = events[k].time, bond[k] = events[k].bond, re_formed[k] = events[k].re_formed;
  m.writing([&] {
    append_rows(m.columns[0], at, n, H5T_NATIVE_LONG, step.data());
    append_rows(m.columns[1], at, n, H5T_NATIVE_DOUBLE, time.data());
    append_rows(m.columns[2], at, n, H5T_NATIVE_LONG, bond.data());
    append_rows(m.columns[3], at, n, H5T_NATIVE_INT8, re_formed.data());
  });
  events_ += static_cast<long>(n);
}

void H5mdWriter::flush() {
  impl_->writing([&] {
    if (H5Fflush(impl_->file, H5F_SCOPE_GLOBAL) < 0) {
      if (errno == 0) errno = EIO;
      throw std::runtime_error("flush");
    }
  });
}

void H5mdWriter::mark_incomplete(const std::string& why) {
  hid_t par = checked(H5Gopen2(impl_->file, "/parameters", H5P_DEFAULT), "parameters");
  if (H5Lexists(par, "incomplete", H5P_DEFAULT) > 0) H5Ldelete(par, "incomplete", H5P_DEFAULT);
  string_dataset(par, "incomplete", why);
  H5Gclose(par);
  flush();
}

void H5mdWriter::close() {
  if (!impl_ || impl_->file < 0) return;
  auto& m = *impl_;
  m.position.close();
  m.velocity.close();
  for (auto& [name, s] : m.observables) s.close();
  m.rows_at_frame.close();
  for (hid_t& c : m.columns)
    if (c >= 0) H5Dclose(c), c = -1;
  if (m.record >= 0) H5Gclose(m.record);
  H5Gclose(m.obs_group);
  H5Gclose(m.particles);
  const bool closed = H5Fclose(m.file) >= 0;
  m.file = -1;
  if (closed) std::remove(writing_marker(m.path).c_str());  // whole on disk: it may be appended to
}

// ---- reader ----

namespace {
std::vector<hsize_t> dims_of(hid_t d) {
  hid_t space = H5Dget_space(d);
  const int rank = H5Sget_simple_extent_ndims(space);
  std::vector<hsize_t> dims(static_cast<std::size_t>(rank));
  H5Sget_simple_extent_dims(space, dims.data(), nullptr);
  H5Sclose(space);
  return dims;
}
template <class T>
std::vector<T> read_all(hid_t file, const std::string& path) {
  hid_t d = H5Dopen2(file, path.c_str(), H5P_DEFAULT);
  if (d < 0) throw std::runtime_error("trajectory has no " + path);
  hsize_t count = 1;
  for (auto s : dims_of(d)) count *= s;
  std::vector<T> v(count);
  if (count) check(H5Dread(d, native<T>(), H5S_ALL, H5S_ALL, H5P_DEFAULT, v.data()), path.c_str());
  H5Dclose(d);
  return v;
}
}  // namespace

namespace {
// The end-of-file address an HDF5 superblock records (versions 0-3, 8-byte offsets), or 0 if unreadable.
std::uint64_t stored_eof(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  unsigned char b[64] = {};
  in.read(reinterpret_cast<char*>(b), sizeof b);
  if (in.gcount() < 48 || std::memcmp(b, "\x89HDF\r\n\x1a\n", 8) != 0) return 0;
  const int version = b[8];
  std::size_t at = 0;
  if (version == 0 && b[13] == 8) at = 40;
  else if (version == 1 && b[13] == 8) at = 44;
  else if ((version == 2 || version == 3) && b[9] == 8) at = 28;
  else return 0;
  std::uint64_t v = 0;
  for (int k = 7; k >= 0; --k) v = v << 8 | b[at + static_cast<std::size_t>(k)];
  return v;
}

// Whether frame `index` of a frame-chunked dataset (all the chunks of its rows), or entry `index` of a series,
// lies before `limit`.
bool chunk_before(hid_t file, const char* path, hsize_t index, std::uint64_t limit) {
  hid_t d = H5Dopen2(file, path, H5P_DEFAULT);
  if (d < 0) return false;
  hid_t dcpl = H5Dget_create_plist(d);
  hsize_t chunk[4] = {1, 1, 1, 1};
  const int rank = H5Pget_chunk(dcpl, 4, chunk);
  H5Pclose(dcpl);
  const auto dims = dims_of(d);
  const hsize_t rows = rank > 1 ? dims.at(1) : 1, step = rank > 1 ? chunk[1] : 1;
  bool ok = rank > 0;
  for (hsize_t first = 0; ok && first < rows; first += step) {
    hsize_t offset[4] = {0, 0, 0, 0};
    offset[0] = index / chunk[0] * chunk[0];
    if (rank > 1) offset[1] = first;
    unsigned mask = 0;
    haddr_t addr = HADDR_UNDEF;
    hsize_t size = 0;
    ok = H5Dget_chunk_info_by_coord(d, offset, &mask, &addr, &size) >= 0 && addr != HADDR_UNDEF &&
         addr + size <= limit;
  }
  H5Dclose(d);
  return ok;
}
}  // namespace

H5mdReader::H5mdReader(const std::string& path) : path_(path) {
  hdf5_stack_as_asked();  // we report missing objects ourselves
  file_ = H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  std::uint64_t limit = 0;
  if (file_ < 0) {
    // Cut short? HDF5 refuses a file shorter than the end its superblock records; pad a copy with zeros
    // to that length and read only what lies before the cut.
    namespace fs = std::filesystem;
    std::error_code ec;
    const std::uint64_t size = fs::file_size(path, ec), eof = ec ? 0 : stored_eof(path);
    if (eof > size && size > 0) {
      padded_copy_ = (fs::temp_directory_path() /
                      ("pmfrag_padded_" + std::to_string(::getpid()) + "_" + fs::path(path).filename().string()))
                         .string();
      fs::copy_file(path, padded_copy_, fs::copy_options::overwrite_existing, ec);
      if (!ec) fs::resize_file(padded_copy_, eof, ec);
      if (!ec) file_ = H5Fopen(padded_copy_.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
      limit = size;
      damage_ = "truncated: " + std::to_string(size) + " of " + std::to_string(eof) + " bytes";
    }
    if (file_ < 0) {
      if (!padded_copy_.empty()) fs::remove(padded_copy_, ec);
      throw std::runtime_error(path + ": cannot open as HDF5" + (damage_.empty() ? "" : " (" + damage_ + ")"));
    }
  }
  hid_t d = H5Dopen2(file_, "/particles/all/position/value", H5P_DEFAULT);
  if (d < 0) throw std::runtime_error(path + ": not an H5MD trajectory (no /particles/all/position)");
  const auto dims = dims_of(d);
  H5Dclose(d);
  frames_ = static_cast<long>(dims[0]);
  has_velocity_ = H5Lexists(file_, "/particles/all/velocity", H5P_DEFAULT) > 0;
  n_ = dims[1];
  dim_ = static_cast<int>(dims[2]);
  // The step/time series can be shorter than value if a run was killed mid-frame: trust the shortest.
  hid_t t = H5Dopen2(file_, "/particles/all/position/time", H5P_DEFAULT);
  if (t >= 0) frames_ = std::min(frames_, static_cast<long>(dims_of(t)[0])), H5Dclose(t);
  if (limit > 0) {
    long ok = 0;
    while (ok < frames_) {
      const hsize_t k = static_cast<hsize_t>(ok);
      if (!chunk_before(file_, "/particles/all/position/value", k, limit) ||
          (has_velocity_ && !chunk_before(file_, "/particles/all/velocity/value", k, limit)) ||
          !chunk_before(file_, "/particles/all/position/time", k, limit) ||
          !chunk_before(file_, "/particles/all/position/step", k, limit))
        break;
      ++ok;
    }
    damage_ += "; " + std::to_string(ok) + " of " + std::to_string(frames_) + " frames lie before the cut";
    frames_ = ok;
  }
  limit_ = limit;
}

H5mdReader::~H5mdReader() {
  if (file_ >= 0) H5Fclose(file_);
  if (!padded_copy_.empty()) {
    std::error_code ec;
    std::filesystem::remove(padded_copy_, ec);
  }
}

TrajectoryFrame H5mdReader::frame(long index) const {
  TrajectoryFrame f;
  frame(index, f);
  return f;
}

void H5mdReader::frame(long index, TrajectoryFrame& f) const {
  if (index < 0 || index >= frames_) throw std::out_of_range("frame index");
  auto read_slab = [&](const char* path, std::vector<double>& out) {
    hid_t d = H5Dopen2(file_, path, H5P_DEFAULT);
    hid_t fspace = H5Dget_space(d);
    hsize_t start[3] = {static_cast<hsize_t>(index), 0, 0}, count[3] = {1, n_, static_cast<hsize_t>(dim_)};
    H5Sselect_hyperslab(fspace, H5S_SELECT_SET, start, nullptr, count, nullptr);
    hid_t mspace = H5Screate_simple(3, count, nullptr);
    out.resize(n_ * static_cast<std::size_t>(dim_));
    check(H5Dread(d, H5T_NATIVE_DOUBLE, mspace, fspace, H5P_DEFAULT, out.data()), path);
    H5Sclose(mspace), H5Sclose(fspace), H5Dclose(d);
  };
  read_slab("/particles/all/position/value", f.position);
  if (has_velocity_)
    read_slab("/particles/all/velocity/value", f.velocity);
  else
    f.velocity.clear();
  const auto steps = read_all<long>(file_, "/particles/all/position/step");
  const auto times = read_all<double>(file_, "/particles/all/position/time");
  f.step = steps[static_cast<std::size_t>(index)];
  f.time = times[static_cast<std::size_t>(index)];
}

std::vector<double> H5mdReader::times() const {
  auto t = read_all<double>(file_, "/particles/all/position/time");
  t.resize(static_cast<std::size_t>(frames_));
  return t;
}

std::vector<std::array<int, 2>> H5mdReader::bonds() const {
  const auto flat = read_all<int>(file_, "/connectivity/bonds");
  std::vector<std::array<int, 2>> b(flat.size() / 2);
  for (std::size_t k = 0; k < b.size(); ++k) b[k] = {flat[2 * k], flat[2 * k + 1]};
  return b;
}
bool H5mdReader::has_bond_record() const {
  return H5Lexists(file_, "/connectivity", H5P_DEFAULT) > 0 &&
         H5Lexists(file_, "/connectivity/broken_bonds", H5P_DEFAULT) > 0;
}

namespace {
// Leading entries [0, n) of a chunked 1-D dataset whose chunks lie wholly before `limit` (a truncated file).
hsize_t entries_before(hid_t file, const char* path, hsize_t n, std::uint64_t limit) {
  hid_t d = H5Dopen2(file, path, H5P_DEFAULT);
  if (d < 0) return 0;
  hid_t dcpl = H5Dget_create_plist(d);
  hsize_t chunk[1] = {1};
  H5Pget_chunk(dcpl, 1, chunk);
  H5Pclose(dcpl);
  H5Dclose(d);
  for (hsize_t at = 0; at < n; at += chunk[0])
    if (!chunk_before(file, path, at, limit)) return at;
  return n;
}

std::string string_attribute_of(hid_t obj, const char* name) {
  if (H5Aexists(obj, name) <= 0) return "";
  hid_t a = H5Aopen(obj, name, H5P_DEFAULT);
  hid_t type = H5Aget_type(a);
  std::string out;
  if (H5Tis_variable_str(type) > 0) {
    char* text = nullptr;
    // HDF5 converts no character set into another: the memory type takes the file's (ASCII or UTF-8)
    hid_t mem = H5Tcopy(H5T_C_S1);
    H5Tset_size(mem, H5T_VARIABLE);
    H5Tset_cset(mem, H5Tget_cset(type));
    if (H5Aread(a, mem, &text) >= 0 && text) out = text;
    if (text) H5free_memory(text);
    H5Tclose(mem);
  } else {
    out.assign(H5Tget_size(type), '\0');
    H5Aread(a, type, out.data());
    while (!out.empty() && out.back() == '\0') out.pop_back();
  }
  H5Tclose(type), H5Aclose(a);
  return out;
}
}  // namespace

BondRecord H5mdReader::bond_record() const {
  if (!has_bond_record()) throw std::runtime_error(path_ + ": has no /connectivity/broken_bonds");
  BondRecord r;
  {
    hid_t g = H5Gopen2(file_, "/connectivity/broken_bonds", H5P_DEFAULT);
    r.model = string_attribute_of(g, "model");
    H5Gclose(g);
  }
  const std::string base = "/connectivity/broken_bonds/";
  const auto step = read_all<long>(file_, base + "step");
  const auto time = read_all<double>(file_, base + "time");
  const auto bond = read_all<long>(file_, base + "bond");
  const auto re_formed = read_all<int>(file_, base + "re_formed");
  auto rows = read_all<long>(file_, base + "rows_at_frame/value");
  hsize_t n = std::min({step.size(), time.size(), bond.size(), re_formed.size()});
  hsize_t frames = std::min<hsize_t>(rows.size(), static_cast<hsize_t>(frames_));
  frames = std::min<hsize_t>(frames, read_all<long>(file_, base + "rows_at_frame/step").size());
  if (limit_ > 0) {
    for (const char* c : event_columns) n = entries_before(file_, (base + c).c_str(), n, limit_);
    frames = entries_before(file_, (base + "rows_at_frame/value").c_str(), frames, limit_);
  }
  rows.resize(frames);
  // a frame counts only if every row it needs was read
  std::size_t whole = 0;
  while (whole < rows.size() && rows[whole] >= 0 && static_cast<hsize_t>(rows[whole]) <= n &&
         (whole == 0 || rows[whole] >= rows[whole - 1]))
    ++whole;
  if (whole < static_cast<std::size_t>(frames_))
    r.damage = "bond record covers frames 0.." + std::to_string(static_cast<long>(whole) - 1) + " of " +
               std::to_string(frames_) + (limit_ > 0 ? " (file cut short)" : " (record cut short: a killed run?)");
  rows.resize(whole);
  r.rows_at_frame = rows;
  const long used = rows.empty() ? 0 : rows.back();
  const long nbonds = static_cast<long>(read_all<int>(file_, "/connectivity/bonds").size() / 2);
  std::vector<std::uint8_t> broken(static_cast<std::size_t>(nbonds), 0);
  const bool cutoff = r.model == "cutoff";
  r.events.resize(static_cast<std::size_t>(used));
  for (long k = 0; k < used; ++k) {
    const std::size_t u = static_cast<std::size_t>(k);
    const auto bad = [&](const std::string& what) {
      return std::runtime_error(path_ + ": " + base + what + " (row " + std::to_string(k) + ")");
    };
    if (bond[u] < 0 || bond[u] >= nbonds)
      throw bad("bond names bond " + std::to_string(bond[u]) + ", but /connectivity/bonds has " + std::to_string(nbonds) +
                " rows");
    if (k > 0 && step[u] < step[u - 1]) throw bad("step goes back from " + std::to_string(step[u - 1]) + " to " + std::to_string(step[u]));
    const bool again = re_formed[u] != 0;
    std::uint8_t& b = broken[static_cast<std::size_t>(bond[u])];
    if ((again && (!cutoff || !b)) || (!again && b))
      throw bad("re_formed: bond " + std::to_string(bond[u]) + (again ? " re-forms without having broken"
                                                                      : " breaks again without having re-formed") +
                (cutoff ? "" : " (a bonded run's bonds break once)"));
    b = !again;
    r.events[u] = BondEvent{step[u], time[u], bond[u], again};
  }
  return r;
}

std::vector<int> H5mdReader::species() const { return read_all<int>(file_, "/particles/all/species"); }
std::vector<double> H5mdReader::mass() const { return read_all<double>(file_, "/particles/all/mass"); }
std::vector<int> H5mdReader::body() const { return read_all<int>(file_, "/particles/all/body"); }
std::vector<int> H5mdReader::held() const {
  if (H5Lexists(file_, "/particles/all/held", H5P_DEFAULT) <= 0) return std::vector<int>(n_, 0);
  return read_all<int>(file_, "/particles/all/held");
}
std::vector<double> H5mdReader::observable(const std::string& name) const {
  auto v = read_all<double>(file_, "/observables/" + name + "/value");
  if (static_cast<long>(v.size()) > frames_) v.resize(static_cast<std::size_t>(frames_));
  return v;
}
double H5mdReader::parameter(const std::string& name) const { return read_all<double>(file_, "/parameters/" + name).at(0); }
std::vector<PairLaw> H5mdReader::laws() const {
  const auto flat = read_all<double>(file_, "/parameters/laws");
  std::vector<PairLaw> out;
  for (std::size_t k = 0; k + 3 < flat.size(); k += 4)
    out.push_back(PairLaw{static_cast<int>(flat[k]), static_cast<int>(flat[k + 1]), flat[k + 2], flat[k + 3]});
  return out;
}
std::vector<int> H5mdReader::phase_pair_law() const { return read_all<int>(file_, "/parameters/phase_pair_law"); }
namespace {
std::string read_string(hid_t file, const char* path) {
  hid_t d = H5Dopen2(file, path, H5P_DEFAULT);
  if (d < 0) throw std::runtime_error(std::string("trajectory has no ") + path);
  hid_t type = H5Dget_type(d);
  std::string s(H5Tget_size(type), '\0');
  check(H5Dread(d, type, H5S_ALL, H5S_ALL, H5P_DEFAULT, s.data()), path);
  H5Tclose(type), H5Dclose(d);
  while (!s.empty() && s.back() == '\0') s.pop_back();
  return s;
}
}  // namespace

std::string H5mdReader::scene_text() const { return read_string(file_, "/parameters/scene"); }

std::vector<std::string> H5mdReader::overrides() const {
  if (H5Lexists(file_, "/parameters/overrides", H5P_DEFAULT) <= 0) return {};
  std::vector<std::string> out;
  std::stringstream lines(read_string(file_, "/parameters/overrides"));
  for (std::string line; std::getline(lines, line);)
    if (!line.empty()) out.push_back(line);
  return out;
}
std::string H5mdReader::incomplete() const {
  return H5Lexists(file_, "/parameters/incomplete", H5P_DEFAULT) > 0 ? read_string(file_, "/parameters/incomplete") : "";
}

// The layout of a checkpoint's "effects": 3 adds the neighbour list's build (PairBase::save_list); 2 lists
// only the bonds not intact (PairBase::save); before it, every bond's state was written.
constexpr long checkpoint_effects_layout = 3;

void write_checkpoint(const std::string& path, const Checkpoint& c) {
  if (c.velocity.size() != c.position.size()) throw std::logic_error(path + ": checkpoint velocities and positions differ in count");
  write_checkpoint(path, c, c.position.data(), c.velocity.data(), c.position.size());
}

void write_checkpoint(const std::string& path, const Checkpoint& c, const double* position, const double* velocity,
                      std::size_t values) {
  // Whole or not at all: a checkpoint that fails to write (a full disk) leaves the previous one, which --resume
  // still needs. HDF5 does not pass on why; the errno of its last system call says.
  write_file_atomically_by_name(path, [&](const std::filesystem::path& tmp) {
    errno = 0;
    hid_t f = H5Fcreate(tmp.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT);
    if (f < 0) return false;
    bool ok = true;
    try {
      array_dataset<long>(f, "step", {c.step}, {});
      array_dataset<long>(f, "frames", {c.frames}, {});
      array_dataset<long>(f, "bond_events", {c.bond_events}, {});
      array_dataset(f, "time_dt_level_calm", std::vector<double>{c.time, c.dt, double(c.level), double(c.calm)}, {4});
      array_dataset(f, "position", values ? position : nullptr, {values});
      array_dataset(f, "velocity", values ? velocity : nullptr, {values});
      array_dataset(f, "effects", c.effects, {c.effects.size()});
      array_dataset<long>(f, "effects_layout", {checkpoint_effects_layout}, {});
    } catch (const std::runtime_error&) {
      ok = false;
    }
    const int err = errno;
    ok = H5Fclose(f) >= 0 && ok;
    if (!ok && err != 0) errno = err;
    return ok;
  });
}

Checkpoint read_checkpoint(const std::string& path) {
  hdf5_stack_as_asked();
  hid_t f = H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  if (f < 0) throw std::runtime_error(path + ": cannot open checkpoint");
  Checkpoint c;
  try {
    c.step = read_all<long>(f, "step").at(0);
    c.frames = read_all<long>(f, "frames").at(0);
    if (H5Lexists(f, "bond_events", H5P_DEFAULT) <= 0)
      throw std::runtime_error(path + ": written by an older pmfrag (no bond record): cannot resume; run the scene "
                               "again with --force");
    c.bond_events = read_all<long>(f, "bond_events").at(0);
    const auto td = read_all<double>(f, "time_dt_level_calm");
    c.time = td.at(0), c.dt = td.at(1), c.level = static_cast<int>(td.at(2)), c.calm = static_cast<int>(td.at(3));
    c.position = read_all<double>(f, "position");
    c.velocity = read_all<double>(f, "velocity");
    if (H5Lexists(f, "effects_layout", H5P_DEFAULT) <= 0 ||
        read_all<long>(f, "effects_layout").at(0) != checkpoint_effects_layout)
      throw std::runtime_error(path + ": written by another pmfrag (its bond record is laid out otherwise): cannot "
                               "resume; run the scene again with --force");
    c.effects = read_all<double>(f, "effects");
  } catch (...) {
    H5Fclose(f);
    throw;
  }
  H5Fclose(f);
  return c;
}

bool trajectory_opens_for_append(const std::string& path) {
  if (std::filesystem::exists(writing_marker(path))) return false;
  const hid_t f = H5Fopen(path.c_str(), H5F_ACC_RDWR, H5P_DEFAULT);
  if (f < 0) return false;
  H5Fclose(f);
  return true;
}

void rebuild_trajectory(const std::string& path, const System& sys, const Scene& scene, const RunParameters& run,
                        long keep_frames, long keep_events) {
  const std::string rebuilt = path + ".rebuilt";
  try {
    const H5mdReader cut(path);
    const auto short_of = [&](const std::string& what) {
      return TrajectoryShortOfCheckpoint(path + ": cut short (" + (cut.damage().empty() ? "not closed" : cut.damage()) +
                                         "), and " + what);
    };
    if (cut.frames() < keep_frames)
      throw short_of("it holds " + std::to_string(cut.frames()) + " whole frames of the " +
                     std::to_string(keep_frames) + " the checkpoint counts");
    const BondRecord record = cut.bond_record();
    if (static_cast<long>(record.rows_at_frame.size()) < keep_frames ||
        static_cast<long>(record.events.size()) < keep_events)
      throw short_of("its bond record lacks rows the checkpoint counts");
    std::map<std::string, std::vector<double>> series;
    for (const char* name : observable_names) {
      series[name] = cut.observable(name);
      if (static_cast<long>(series[name].size()) < keep_frames) throw short_of(std::string("its ") + name + " is short");
    }
    // A frame the reader cannot read back (a checksum that fails) ends what is whole.
    const auto read_frame = [&](long k, TrajectoryFrame& f) {
      try {
        cut.frame(k, f);
      } catch (const std::runtime_error& e) {
        throw short_of("frame " + std::to_string(k) + " of the " + std::to_string(keep_frames) +
                       " the checkpoint counts does not read back (" + e.what() + ")");
      }
    };
    TrajectoryFrame f;
    if (keep_frames > 0) read_frame(keep_frames - 1, f);  // the likeliest to be damaged: before any is copied
    H5mdWriter out(rebuilt, sys, scene, run);
    long row = 0;
    const auto events_up_to = [&](long end) {
      out.append_bond_events(std::vector<BondEvent>(record.events.begin() + row, record.events.begin() + end));
      row = end;
    };
    for (long k = 0; k < keep_frames; ++k) {
      read_frame(k, f);
      events_up_to(record.rows_at_frame[static_cast<std::size_t>(k)]);
      const auto at = [&](const char* name) { return series[name][static_cast<std::size_t>(k)]; };
      Observables obs;
      obs.kinetic = at("kinetic_energy"), obs.potential = at("potential_energy");
      obs.boundary_work = at("boundary_work"), obs.bond_break_energy = at("bond_break_energy");
      obs.pairs_beyond_cutoff = std::lround(at("pairs_beyond_cutoff"));
      out.write_frame(f.step, f.time, f.position.data(), f.velocity.empty() ? nullptr : f.velocity.data(), obs);
    }
    events_up_to(keep_events);
    out.flush();
    out.close();
  } catch (...) {
    std::remove(rebuilt.c_str());  // half a copy is no use; the cut file is as it was
    throw;
  }
  if (std::rename(rebuilt.c_str(), path.c_str()) != 0)
    throw std::runtime_error(path + ": cannot replace with " + rebuilt + ": " + std::strerror(errno));
}

void show_library_diagnostics(bool shown) {
  hdf5_stack_shown = shown;
  hdf5_stack_as_asked();
}

}  // namespace pmfrag
