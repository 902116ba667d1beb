// Frames at scale: output.precision = "single" and output.gzip store the same run in fewer bytes. Readers get
// doubles either way; single-precision values are the double run's values rounded once to float.
#include "pmfrag/analysis/export_vtk.hpp"
#include "pmfrag/analysis/fragments.hpp"
#include "pmfrag/body/system.hpp"
#include "pmfrag/io/h5md.hpp"
#include "pmfrag/run/run.hpp"
#include "test_helpers.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include <sys/wait.h>
#include <unistd.h>

using namespace pmfrag;
namespace fs = std::filesystem;

namespace {
fs::path plate_run(const std::string& name, const std::vector<std::string>& output) {
  const fs::path d = test::temp_dir(name);
  std::vector<std::string> set{"time.end=3e-3", "time.dt=2e-7", "output.every=2e-4"};
  set.insert(set.end(), output.begin(), output.end());
  RunOptions ro;
  ro.out_dir = d.string();
  ro.force = true;
  EXPECT_TRUE(run_scene(read_scene(test::case_path("slit_plate_3_5.toml"), set), ro).completed);
  return d;
}
}  // namespace

TEST(Frames, SingleAndGzipHoldTheDoubleRunRoundedOnceAndTakeFewerBytes) {
  const fs::path plain = plate_run("frames_double", {});
  const fs::path small = plate_run("frames_single", {"output.precision=\"single\"", "output.gzip=4"});
  const fs::path zipped = plate_run("frames_gzip", {"output.gzip=4"});
  H5mdReader a((plain / "trajectory.h5").string()), b((small / "trajectory.h5").string()),
      z((zipped / "trajectory.h5").string());
  ASSERT_EQ(a.frames(), 16);
  ASSERT_EQ(b.frames(), a.frames());
  ASSERT_EQ(z.frames(), a.frames());
  double largest_error = 0.0;
  for (long k = 0; k < a.frames(); ++k) {
    const auto fa = a.frame(k), fb = b.frame(k), fz = z.frame(k);
    ASSERT_EQ(fa.position, fz.position) << "gzip is lossless";
    ASSERT_EQ(fa.velocity, fz.velocity);
    ASSERT_EQ(fa.position.size(), fb.position.size());
    for (std::size_t i = 0; i < fa.position.size(); ++i) {
      ASSERT_EQ(fb.position[i], static_cast<double>(static_cast<float>(fa.position[i]))) << "frame " << k << " value " << i;
      ASSERT_EQ(fb.velocity[i], static_cast<double>(static_cast<float>(fa.velocity[i])));
      largest_error = std::max(largest_error, std::abs(fb.position[i] - fa.position[i]));
    }
  }
  // The plate spans 8 x 11.4 cm: a float's half ulp at 8 cm is 2^-21 cm = 4.8e-7 cm.
  EXPECT_GT(largest_error, 0.0);
  EXPECT_LE(largest_error, 4.8e-7);
  const auto bytes = [](const fs::path& d) { return static_cast<double>(fs::file_size(d / "trajectory.h5")); };
  EXPECT_LT(bytes(zipped), 0.9 * bytes(plain));
  EXPECT_LT(bytes(small), 0.5 * bytes(plain)) << bytes(small) << " against " << bytes(plain);
  // The bond record is exact in any precision, so the fragments are the same.
  const auto fa = analysis::analyse_fragments((plain / "trajectory.h5").string(), {});
  const auto fb = analysis::analyse_fragments((small / "trajectory.h5").string(), {});
  ASSERT_EQ(fa.timeline.size(), fb.timeline.size());
  for (std::size_t k = 0; k < fa.timeline.size(); ++k) {
    EXPECT_EQ(fa.timeline[k].broken, fb.timeline[k].broken);
    EXPECT_EQ(fa.timeline[k].fragments, fb.timeline[k].fragments);
  }
}

TEST(Frames, BadPrecisionOrLevelIsRefusedNamingTheKey) {
  const auto refused = [](const std::string& set, const std::string& expect) {
    try {
      (void)read_scene(test::case_path("slit_plate_3_5.toml"), {set});
      ADD_FAILURE() << set << " was accepted";
    } catch (const std::exception& e) {
      EXPECT_NE(std::string(e.what()).find(expect), std::string::npos) << e.what();
    }
  };
  refused("output.precision=\"half\"", "output.precision");
  refused("output.gzip=10", "output.gzip");
  refused("output.gzip=2.5", "output.gzip");
}

TEST(Frames, PositionsOnlyLeaveVelocitiesOutAndTheirBytes) {
  const fs::path plain = plate_run("frames_all", {});
  const fs::path lean = plate_run("frames_positions", {"output.fields=[\"position\"]"});
  H5mdReader a((plain / "trajectory.h5").string()), b((lean / "trajectory.h5").string());
  ASSERT_TRUE(a.has_velocity());
  ASSERT_FALSE(b.has_velocity());
  ASSERT_EQ(b.frames(), a.frames());
  for (long k = 0; k < a.frames(); ++k) {
    const auto fa = a.frame(k), fb = b.frame(k);
    ASSERT_EQ(fa.position, fb.position) << "frame " << k << ": leaving velocities out changes no position";
    ASSERT_TRUE(fb.velocity.empty());
  }
  // The file is smaller by the velocity frames' bytes (N x 2 doubles a frame), give or take HDF5's headers.
  const double saved = static_cast<double>(fs::file_size(plain / "trajectory.h5")) -
                       static_cast<double>(fs::file_size(lean / "trajectory.h5"));
  const double velocity_bytes = static_cast<double>(a.frames()) * static_cast<double>(a.particles()) * 2 * 8;
  EXPECT_GT(saved, 0.98 * velocity_bytes);
  EXPECT_LT(saved, 1.05 * velocity_bytes);
  EXPECT_EQ(a.observable("kinetic_energy"), b.observable("kinetic_energy"));

  // Fragments are the same; their velocities are unknown (NaN), not zero.
  const auto ra = analysis::analyse_fragments((plain / "trajectory.h5").string(), {});
  const auto rb = analysis::analyse_fragments((lean / "trajectory.h5").string(), {});
  ASSERT_EQ(ra.final_fragments.size(), rb.final_fragments.size());
  for (std::size_t g = 0; g < ra.final_fragments.size(); ++g) {
    EXPECT_EQ(ra.final_fragments[g].particles, rb.final_fragments[g].particles);
    EXPECT_EQ(ra.final_fragments[g].center, rb.final_fragments[g].center);
    EXPECT_TRUE(std::isfinite(ra.final_fragments[g].velocity.y()));
    EXPECT_TRUE(std::isnan(rb.final_fragments[g].velocity.y()));
  }

  // Export writes what it can by default, and refuses a field that needs velocities by name.
  const auto res = analysis::export_vtk(lean.string(), {});
  EXPECT_EQ(res.frames_written, b.frames());
  analysis::ExportOptions speed;
  speed.fields = {"id", "speed"};
  try {
    (void)analysis::export_vtk(lean.string(), speed);
    ADD_FAILURE() << "speed exported without velocities";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("'speed' needs velocities"), std::string::npos) << e.what();
  }
}

TEST(Frames, AResumedPositionsOnlyTrajectoryStaysWithoutVelocities) {
  // The writer's resume path: reopen, keep 2 of 3 frames, append one.
  const fs::path d = test::temp_dir("frames_reopen");
  const Scene sc = read_scene(test::case_path("slit_plate_3_5.toml"), {"output.fields=[\"position\"]"});
  const System sys = build_system(sc);
  RunParameters run;
  run.dt = 1e-7, run.end = 1e-6;
  const std::string path = (d / "trajectory.h5").string();
  std::vector<double> x(sys.size() * 2, 1.0), v(sys.size() * 2, 2.0);
  {
    H5mdWriter w(path, sys, sc, run);
    for (long k = 0; k < 3; ++k) w.write_frame(k, 1e-7 * static_cast<double>(k), x, v, {});
  }
  {
    H5mdWriter w(path, 2, 0);
    x.assign(x.size(), 5.0);
    w.write_frame(9, 9e-7, x, v, {});
  }
  H5mdReader rd(path);
  EXPECT_FALSE(rd.has_velocity());
  ASSERT_EQ(rd.frames(), 3);
  EXPECT_EQ(rd.frame(1).position[0], 1.0);
  EXPECT_EQ(rd.frame(2).position[0], 5.0);
  EXPECT_EQ(rd.frame(2).step, 9);
}

TEST(Frames, ATrajectoryItsWriterDidNotCloseIsNotAppendedTo) {
  // A writer killed between flushes may leave half of a frame's metadata in the file; its PATH.writing stays,
  // and resume rebuilds from the frames the checkpoint counts instead of appending.
  const fs::path d = test::temp_dir("frames_marker");
  const Scene sc = read_scene(test::case_path("slit_plate_3_5.toml"), {});
  const System sys = build_system(sc);
  RunParameters run;
  run.dt = 1e-7, run.end = 1e-6;
  const std::string path = (d / "trajectory.h5").string();
  const std::vector<double> x(sys.size() * 2, 1.0), v(sys.size() * 2, 2.0);
  {
    H5mdWriter w(path, sys, sc, run);
    w.write_frame(0, 0.0, x, v, {});
    EXPECT_FALSE(trajectory_opens_for_append(path)) << "a trajectory still being written";
  }
  EXPECT_TRUE(trajectory_opens_for_append(path));
  EXPECT_FALSE(fs::exists(path + ".writing"));
  const pid_t child = fork();
  ASSERT_GE(child, 0);
  if (child == 0) {  // appends a frame and dies without closing, as under SIGKILL
    H5mdWriter w(path, 1, 0);
    w.write_frame(1, 1e-7, x, v, {});
    _exit(0);
  }
  int status = 0;
  ASSERT_EQ(waitpid(child, &status, 0), child);
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_TRUE(fs::exists(path + ".writing"));
  EXPECT_FALSE(trajectory_opens_for_append(path));
}

TEST(Frames, FieldsWithoutPositionOrUnknownAreRefusedNamingTheKey) {
  for (const std::string set : {"output.fields=[\"velocity\"]", "output.fields=[\"position\", \"force\"]",
                                "output.fields=\"position\""}) {
    try {
      (void)read_scene(test::case_path("slit_plate_3_5.toml"), {set});
      ADD_FAILURE() << set << " was accepted";
    } catch (const std::exception& e) {
      EXPECT_NE(std::string(e.what()).find("output.fields"), std::string::npos) << set << ": " << e.what();
    }
  }
}

// The trajectory keeps the overrides a run was made with, in order, for what is drawn and said of it
// (render's titles state them).
TEST(Frames, TheTrajectoryGivesBackTheOverridesThatRan) {
  const fs::path d = plate_run("frames_overrides", {"kinematic.0.velocity=[0.0, 40.0]"});
  H5mdReader rd((d / "trajectory.h5").string());
  const std::vector<std::string> expected{"time.end=3e-3", "time.dt=2e-7", "output.every=2e-4",
                                          "kinematic.0.velocity=[0.0, 40.0]"};
  EXPECT_EQ(rd.overrides(), expected);
  fs::remove_all(d);
}

// The bond record names the model its events belong to; a cutoff run's re-formed events are legal only if it
// reads back as "cutoff" (text attributes are UTF-8: the reader must ask for that character set).
TEST(Frames, TheBondRecordNamesItsModel) {
  for (const std::string model : {"bonded", "cutoff"}) {
    const fs::path d = plate_run("frames_model_" + model, {"pair.model=\"" + model + "\""});
    H5mdReader rd((d / "trajectory.h5").string());
    ASSERT_TRUE(rd.has_bond_record());
    EXPECT_EQ(rd.bond_record().model, model);
    fs::remove_all(d);
  }
}
