// Damaged trajectories: a file cut short and a frame whose bytes were altered. fragments and export must say
// so and process the frames before the damage, identical to those of the intact file.
#include "pmfrag/analysis/export_vtk.hpp"
#include "pmfrag/analysis/fragments.hpp"
#include "pmfrag/io/h5md.hpp"
#include "pmfrag/run/run.hpp"
#include "test_helpers.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <fstream>
#include <iterator>

using namespace pmfrag;
namespace fs = std::filesystem;

namespace {

std::string slurp(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

// A short (3,5) plate run: 21 frames.
fs::path intact_run() {
  static const fs::path dir = [] {
    const fs::path d = test::temp_dir("damaged_src");
    RunOptions ro;
    ro.out_dir = d.string();
    const RunResult r = run_scene(read_scene(test::case_path("slit_plate_3_5.toml"), {"time.end=2e-3", "time.dt=2e-7"}), ro);
    EXPECT_TRUE(r.completed);
    return d;
  }();
  return dir;
}

fs::path copy_run(const std::string& name) {
  const fs::path d = test::temp_dir(name);
  fs::copy(intact_run() / "trajectory.h5", d / "trajectory.h5");
  return d;
}

}  // namespace

TEST(Damaged, AlteredFrameFailsItsChecksumAndTheFramesBeforeItAreProcessed) {
  const fs::path d = copy_run("altered");
  H5mdReader good((intact_run() / "trajectory.h5").string());
  ASSERT_EQ(good.frames(), 21);
  // Find frame 7's positions in the file by their bytes (stored raw) and alter one byte in the middle.
  const auto f7 = good.frame(7).position;
  std::string bytes = slurp(d / "trajectory.h5");
  const std::string pattern(reinterpret_cast<const char*>(f7.data()), 64);
  const auto at = bytes.find(pattern);
  ASSERT_NE(at, std::string::npos);
  bytes[at + 40] = static_cast<char>(bytes[at + 40] ^ 0x10);
  std::ofstream(d / "trajectory.h5", std::ios::binary | std::ios::trunc) << bytes;

  H5mdReader bad((d / "trajectory.h5").string());
  EXPECT_EQ(bad.frames(), 21);  // the file itself opens; the frame does not read
  EXPECT_THROW((void)bad.frame(7), std::exception);
  EXPECT_EQ(bad.frame(6).position, good.frame(6).position);

  const auto rep = analysis::analyse_fragments((d / "trajectory.h5").string(), {});
  EXPECT_TRUE(rep.partial);
  EXPECT_EQ(rep.frames_read, 7);
  EXPECT_NE(rep.note.find("frame 7 unreadable"), std::string::npos) << rep.note;

  const auto ex = analysis::export_vtk(d.string(), {});
  EXPECT_TRUE(ex.partial);
  EXPECT_EQ(ex.frames_written, 7);
  const std::string pvd = slurp(d / "particles.pvd");
  EXPECT_NE(pvd.find("<!-- PARTIAL: "), std::string::npos) << pvd;
  std::size_t datasets = 0;
  for (auto p = pvd.find("<DataSet"); p != std::string::npos; p = pvd.find("<DataSet", p + 1)) ++datasets;
  EXPECT_EQ(datasets, 7u);
}

TEST(Damaged, TruncatedFileOffersTheFramesBeforeTheCut) {
  const fs::path d = copy_run("truncated");
  const auto full = fs::file_size(d / "trajectory.h5");
  fs::resize_file(d / "trajectory.h5", full * 6 / 10);
  H5mdReader good((intact_run() / "trajectory.h5").string());
  H5mdReader cut((d / "trajectory.h5").string());
  EXPECT_NE(cut.damage().find("truncated"), std::string::npos) << cut.damage();
  EXPECT_GT(cut.frames(), 3);
  EXPECT_LT(cut.frames(), 21);
  for (long k = 0; k < cut.frames(); ++k) {
    const auto a = cut.frame(k), b = good.frame(k);
    ASSERT_EQ(a.position, b.position) << "frame " << k;
    ASSERT_EQ(a.velocity, b.velocity) << "frame " << k;
    ASSERT_EQ(a.time, b.time) << "frame " << k;
  }
  const auto rep = analysis::analyse_fragments((d / "trajectory.h5").string(), {});
  EXPECT_TRUE(rep.partial);
  EXPECT_EQ(rep.frames_read, cut.frames());
  EXPECT_NE(rep.note.find("truncated"), std::string::npos) << rep.note;
  // A file that is not HDF5 at all is refused with its name.
  std::ofstream(d / "junk.h5") << "not a trajectory";
  try {
    H5mdReader junk((d / "junk.h5").string());
    FAIL();
  } catch (const std::exception& e) {
    EXPECT_NE(std::string(e.what()).find("junk.h5"), std::string::npos) << e.what();
  }
}
