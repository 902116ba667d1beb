// Scenes: the shipped cases read, build and run; errors name file, line and key.
#include "pmfrag/run/run.hpp"
#include "pmfrag/run/sweep.hpp"
#include "pmfrag/body/system.hpp"
#include "test_helpers.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <set>

using namespace pmfrag;

namespace {
std::string error_of(const std::string& text, const std::vector<std::string>& overrides = {}) {
  try {
    parse_scene(text, "bad.toml", overrides);
  } catch (const SceneError& e) {
    return e.what();
  }
  return "";
}

const char* minimal = R"(
[[body]]
lattice = "triangular"
shape = { kind = "rect", min = [0, 0], max = [2, 2] }
[[phase]]
p = 7
q = 14
[pair]
[time]
dt = 1e-7
end = 1e-6
)";
}  // namespace

TEST(Scene, GreenspanPlateHasThePapersSitesAndSlit) {
  const Scene sc = read_scene(test::case_path("slit_plate_7_14.toml"));
  const System sys = build_system(sc);
  EXPECT_EQ(sys.size(), 2698u);  // 2713 sites minus 15 voids
  // The voids i = 1070 + 41k are absent, everything else present.
  std::set<int> sites(sys.site.begin(), sys.site.end());
  for (int k = 0; k < 15; ++k) EXPECT_EQ(sites.count(1070 + 41 * k), 0u);
  EXPECT_EQ(sites.count(1069), 1u);
  EXPECT_EQ(*sites.rbegin(), 2713);
  // Every bond has length r0 (to the 8 digits of the paper's coordinates).
  for (const auto& b : sys.bonds) EXPECT_NEAR((sys.position[b[0]] - sys.position[b[1]]).norm(), 0.2, 1e-7);
  // Interior sites have 6 neighbours: count the coordination histogram's maximum.
  std::vector<int> nb(sys.size());
  for (const auto& b : sys.bonds) ++nb[b[0]], ++nb[b[1]];
  EXPECT_EQ(*std::max_element(nb.begin(), nb.end()), 6);
  EXPECT_EQ(select_particles(sys, Selection{Selection::Kind::top_row, {}, {}}, "t").size(), 40u);  // row 67: 40 sites
  EXPECT_EQ(select_particles(sys, Selection{Selection::Kind::bottom_row, {}, {}}, "t").size(), 40u);
}

TEST(Scene, CloseBlockCountsAndNeighbours) {
  for (const char* stacking : {"fcc", "hcp"}) {
    const Scene sc = read_scene(test::case_path("block3d_slit.toml"), {std::string("body.0.lattice=\"") + stacking + "\"",
                                                                      "body.0.slits=[]"});
    const System sys = build_system(sc);
    EXPECT_EQ(sys.size(), 54940u) << stacking;
    std::vector<int> nb(sys.size());
    for (const auto& b : sys.bonds) {
      EXPECT_NEAR((sys.position[b[0]] - sys.position[b[1]]).norm(), 0.2, 1e-9);
      ++nb[b[0]], ++nb[b[1]];
    }
    EXPECT_EQ(*std::max_element(nb.begin(), nb.end()), 12) << stacking;  // close packing
    // The pulled faces are the outermost row of every close-packed layer (41 sites x 20 layers), not only
    // of the layers that happen to reach the extreme y.
    for (auto kind : {Selection::Kind::top_row, Selection::Kind::bottom_row}) {
      const auto rows = select_particles(sys, Selection{kind, {}, {}}, "t");
      EXPECT_EQ(rows.size(), 41u * 20u) << stacking;
      std::set<long> layers;
      for (int i : rows) layers.insert(std::lround(sys.position[static_cast<std::size_t>(i)].z() / 0.01));
      EXPECT_EQ(layers.size(), 20u) << stacking;
    }
  }
}

TEST(Scene, SlitRemovesCrossingBondsOnly) {
  const std::string text = std::string(minimal) + "";
  Scene sc = parse_scene(text, "t.toml");
  const std::size_t intact = build_system(sc).bonds.size();
  sc.bodies[0].slits.push_back(Segment{Vec3(1.05, -1, 0), Vec3(1.05, 0.9, 0)});
  const System cut = build_system(sc);
  EXPECT_LT(cut.bonds.size(), intact);
  for (const auto& b : cut.bonds) EXPECT_FALSE(sc.bodies[0].slits[0].crossed_by(cut.position[b[0]], cut.position[b[1]]));
}

TEST(Scene, EveryShippedCaseRunsAFewSteps) {
  const auto out = test::temp_dir("cases");
  int count = 0;
  for (const auto& entry : std::filesystem::directory_iterator(std::string(PMFRAG_SOURCE_DIR) + "/cases")) {
    if (entry.path().extension() != ".toml") continue;
    if (entry.path().stem().string().rfind("sweep_", 0) == 0) {  // a sweep spec, not a scene: its cases must read
      const SweepSpec spec = read_sweep_spec(entry.path().string());
      const Scene base = read_scene(spec.base, spec.set);
      for (const auto& k : sweep_cases(spec, base.phases.size())) (void)read_scene(spec.base, k.overrides);
      continue;
    }
    Scene sc = read_scene(entry.path().string());
    const System sys = build_system(sc);
    const double dt = choose_step(sc, sys).dt;
    sc.time.end = 5 * dt;
    sc.output.every = dt;
    RunOptions ro;
    ro.out_dir = (out / entry.path().stem()).string();
    const RunResult r = run_scene(sc, ro);
    EXPECT_TRUE(r.completed) << entry.path() << ": " << r.message;
    EXPECT_EQ(r.frames, 6) << entry.path();
    EXPECT_TRUE(std::filesystem::exists(ro.out_dir + "/trajectory.h5"));
    ++count;
  }
  EXPECT_GE(count, 6);
  std::filesystem::remove_all(out);
}

TEST(Scene, ErrorsNameFileLineAndKey) {
  // minimal's lines: 2 [[body]], 3 lattice, 4 shape, 5 [[phase]], 6 p, 7 q, 8 [pair], 9 [time], 10 dt, 11 end
  const std::string m = minimal;
  auto with = [&](const std::string& from, const std::string& to) {
    std::string t = m;
    t.replace(t.find(from), from.size(), to);
    return t;
  };
  EXPECT_EQ(error_of(m), "");
  EXPECT_EQ(error_of(m + "frobnicate = 1\n"), "bad.toml:12: key 'time.frobnicate': unknown key");
  EXPECT_EQ(error_of("frobnicate = 1" + m), "bad.toml:1: key 'frobnicate': unknown key");
  EXPECT_EQ(error_of(with("dt = 1e-7", "dt = \"fast\"")), "bad.toml:10: key 'time.dt': expected a step in seconds, \"auto\" or \"adaptive\" (got \"fast\")");
  EXPECT_EQ(error_of(with("dt = 1e-7", "dt = -1e-7")), "bad.toml:10: key 'time.dt': must be positive (got -0.000000)");
  EXPECT_EQ(error_of(with("dt = 1e-7", "dt = nan")), "bad.toml:10: key 'time.dt': must be finite (got nan)");
  EXPECT_EQ(error_of(with("end = 1e-6\n", "")), "bad.toml:9: key 'time.end': missing (required)");
  EXPECT_EQ(error_of(with("q = 14", "q = 7")), "bad.toml:7: key 'phase[0].q': q must be greater than p (got p = 7, q = 7)");
  EXPECT_EQ(error_of(with("p = 7", "p = 0")), "bad.toml:6: key 'phase[0].p': p must be >= 1 (got 0)");
  EXPECT_EQ(error_of(with("lattice = \"triangular\"", "lattice = \"square\"")),
            "bad.toml:3: key 'body[0].lattice': unknown lattice 'square' (greenspan_plate, triangular, hcp, fcc)");
  EXPECT_EQ(error_of(with("[pair]", "[pair]\nmodel = \"springs\"")),
            "bad.toml:9: key 'pair.model': expected \"bonded\" or \"cutoff\" (got \"springs\")");
  EXPECT_EQ(error_of(with("q = 14", "q = 14\nmass = 0.05")), "bad.toml:5: key 'phase[0].G': missing (required)");
  EXPECT_EQ(error_of(m, {"time.frob=3"}), "bad.toml (--set): key 'time.frob': unknown key");
  EXPECT_EQ(error_of(m, {"time.end=-1"}), "bad.toml (--set): key 'time.end': must be positive (got -1.000000)");
  EXPECT_EQ(error_of(m, {"time.end=2e-6"}), "");
  EXPECT_NE(error_of("[[body]\nx=1"), "");  // TOML syntax: line reported
  EXPECT_EQ(error_of("[[body]\nx=1").rfind("bad.toml:1:", 0), 0u);
  // r0 must be positive
  EXPECT_EQ(error_of(with("lattice = \"triangular\"", "lattice = \"triangular\"\nr0 = -0.2")),
            "bad.toml:4: key 'body[0].r0': must be positive (got -0.200000)");
}

TEST(Scene, SelectionsAndRegionsThatSelectNothingAreRefused) {
  const std::string m = minimal;
  Scene sc = parse_scene(m + "[[kinematic]]\nselect = { region = { kind = \"disc\", center = [50, 50], radius = 1 } }\n"
                             "velocity = [0, 1]\n",
                         "k.toml");
  try {
    RunOptions ro;
    ro.out_dir = test::temp_dir("nothing").string();
    (void)run_scene(sc, ro);
    FAIL() << "expected an error";
  } catch (const SceneError& e) {
    EXPECT_NE(std::string(e.what()).find("kinematic[0].select"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("selects no particle"), std::string::npos) << e.what();
  }
  Scene holes = parse_scene(m, "h.toml");
  Region everything;
  everything.kind = Region::Kind::disc;
  everything.center = Vec3(1, 1, 0);
  everything.radius = 10.0;
  holes.bodies[0].holes.push_back(everything);
  EXPECT_THROW(build_system(holes), SceneError);
}

TEST(Scene, ATargetOverlappingTheBodyIsRefusedNamingBoth) {
  const std::string two = R"(
[[body]]
name = "disc"
lattice = "triangular"
shape = { kind = "disc", center = [0.0, 1.0], radius = 1.0 }
[[body]]
name = "wall"
lattice = "triangular"
shape = { kind = "rect", min = [-3.0, -0.5], max = [3.0, 0.3] }
[[phase]]
p = 7
q = 14
[pair]
[[kinematic]]
select = { body = "wall" }
velocity = [0.0, 0.0]
[time]
dt = 1e-7
end = 1e-6
)";
  try {
    (void)build_system(parse_scene(two, "overlap.toml"));
    FAIL() << "expected an error";
  } catch (const SceneError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("bodies 'disc' and 'wall' overlap"), std::string::npos) << what;
    EXPECT_NE(what.find("overlap.toml"), std::string::npos) << what;
  }
  // moved clear of each other, the same scene builds
  EXPECT_NO_THROW((void)build_system(parse_scene(two, "clear.toml", {"body.0.shape.center=[0.0, 1.6]"})));
}

// docs/scenes.md lists every key the parser reads: each example on the page parses, and the keys the parser
// asks for over those examples and every case in cases/ are exactly the keys the page's tables list.
TEST(SceneKeys, DocumentMatchesTheParser) {
  const std::string page = test::read_text(std::string(PMFRAG_SOURCE_DIR) + "/docs/scenes.md");
  std::set<std::string> documented;
  std::istringstream lines(page);
  std::vector<std::string> examples;
  std::string line, example;
  bool in_example = false;
  for (int number = 1; std::getline(lines, line); ++number) {
    if (line == "```toml") {
      in_example = true;
      example.clear();
    } else if (in_example && line == "```") {
      in_example = false;
      examples.push_back(example);
    } else if (in_example) {
      example += line + "\n";
    } else if (line.rfind("| `", 0) == 0) {  // a table row: its first cell is the key
      const auto end = line.find('`', 3);
      ASSERT_NE(end, std::string::npos) << "docs/scenes.md:" << number;
      documented.insert(line.substr(3, end - 3));
    }
  }
  ASSERT_GE(examples.size(), 4u);
  std::set<std::string> asked;
  for (std::size_t k = 0; k < examples.size(); ++k) {
    try {
      parse_scene(examples[k], "docs/scenes.md example " + std::to_string(k + 1), {}, &asked);
    } catch (const SceneError& e) {
      ADD_FAILURE() << e.what();
    }
  }
  for (const auto& f : std::filesystem::directory_iterator(std::string(PMFRAG_SOURCE_DIR) + "/cases")) {
    if (f.path().extension() != ".toml" || f.path().stem().string().rfind("sweep_", 0) == 0) continue;
    parse_scene(test::read_text(f.path().string()), f.path().string(), {}, &asked);
  }
  for (const auto& k : asked) EXPECT_TRUE(documented.count(k)) << "the parser reads '" << k << "': not in docs/scenes.md";
  for (const auto& k : documented) EXPECT_TRUE(asked.count(k)) << "docs/scenes.md lists '" << k << "': no example or case reaches it";
}

// Keys named as messages print them work in --set too.
TEST(SceneKeys, SetTakesTheKeysMessagesPrint) {
  const std::string text = R"(
[[body]]
lattice = "triangular"
shape = { kind = "disc", center = [0.0, 0.0], radius = 1.0 }
holes = [ { kind = "disc", center = [0.0, 0.0], radius = 0.2 } ]
[[phase]]
p = 7
q = 14
[time]
dt = 1e-7
end = 1e-6
)";
  const std::string what = error_of(text, {"body[0].holes[0].radius=-1.0"});
  EXPECT_NE(what.find("key 'body[0].holes[0].radius': must be positive"), std::string::npos) << what;
  EXPECT_DOUBLE_EQ(parse_scene(text, "t.toml", {"body[0].holes[0].radius=0.3"}).bodies[0].holes[0].radius, 0.3);
  EXPECT_DOUBLE_EQ(parse_scene(text, "t.toml", {"body.0.r0=0.1"}).bodies[0].r0, 0.1);
}

// run.json is written from the run's result and read back into the same typed fields (sweeps and studies
// gather runs this way); a file that is not a run record is refused, naming it.
TEST(RunRecord, ReadsBackWhatTheRunWrote) {
  const auto dir = test::temp_dir("run_record");
  RunOptions ro;
  ro.out_dir = (dir / "run").string();
  ro.force = true;
  const RunResult ran = run_scene(read_scene(test::case_path("impact.toml"), {"time.end=2e-5"}), ro);
  const RunResult back = read_run_record((dir / "run" / "run.json").string());
  EXPECT_TRUE(back.completed);
  EXPECT_EQ(back.steps, ran.steps);
  EXPECT_EQ(back.frames, ran.frames);
  EXPECT_EQ(back.particles, ran.particles);
  EXPECT_EQ(back.dt, ran.dt);  // doubles are written to round-trip exactly
  EXPECT_EQ(back.dt_min, ran.dt_min);
  EXPECT_EQ(back.wall_s, ran.wall_s);
  EXPECT_EQ(back.setup_s, ran.setup_s);
  EXPECT_GT(ran.setup_s, 0.0);  // the system and lists take time to build before the first frame
  EXPECT_EQ(back.output_s, ran.output_s);
  EXPECT_GT(ran.output_s, 0.0);  // frames were written...
  EXPECT_LT(ran.output_s, ran.wall_s);  // ...within the run's wall time
  EXPECT_EQ(back.pair_model, ran.pair_model);
  EXPECT_EQ(back.first_break_time, ran.first_break_time);
  EXPECT_EQ(back.threads(), ran.threads());
  long steps = 0;
  for (const long s : back.thread_steps) steps += s;
  EXPECT_EQ(steps, ran.steps);
  std::ofstream(dir / "bad.json") << "{ \"completed\": tru";
  try {
    read_run_record((dir / "bad.json").string());
    ADD_FAILURE() << "a torn run.json was read";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("bad.json"), std::string::npos) << e.what();
  }
  std::filesystem::remove_all(dir);
}
