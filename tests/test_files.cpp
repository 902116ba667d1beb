// Outputs are whole or absent: write_file_atomically under faults (a file-size limit, a missing folder, a body
// that throws) leaves the previous file as it was, no temporary behind, and says which file and why.
#include "pmfrag/io/atomic_file.hpp"

#include <gtest/gtest.h>
#include <sys/resource.h>
#include <unistd.h>

#include <csignal>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>

using namespace pmfrag;
namespace fs = std::filesystem;

namespace {
std::string content(const fs::path& p) {
  std::ifstream in(p);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}
fs::path fresh_dir(const std::string& name) {
  const fs::path d = fs::temp_directory_path() / ("pmfrag_files_" + name + "_" + std::to_string(::getpid()));
  fs::remove_all(d);
  fs::create_directories(d);
  return d;
}
bool only_file_in(const fs::path& dir, const std::string& name) {
  int n = 0;
  for (const auto& e : fs::directory_iterator(dir)) n += 1 + (e.path().filename() != name) * 100;
  return n == 1;
}
}  // namespace

TEST(AtomicFile, WritesAndReplacesWhole) {
  const fs::path d = fresh_dir("replace"), f = d / "summary.json";
  write_file_atomically(f, [](std::ostream& o) { o << "first\n"; });
  EXPECT_EQ(content(f), "first\n");
  write_file_atomically(f, [](std::ostream& o) { o << "second\n"; });
  EXPECT_EQ(content(f), "second\n");
  EXPECT_TRUE(only_file_in(d, "summary.json"));
  fs::remove_all(d);
}

TEST(AtomicFile, AFileSizeLimitLeavesThePreviousFileAndNamesTheCause) {
  // The disk-full case without a full disk: RLIMIT_FSIZE makes write() fail (EFBIG) past 4 KiB. SIGXFSZ,
  // which would kill the process there, is ignored as pmfrag's main does.
  const fs::path d = fresh_dir("fsize"), f = d / "fragments_final.csv";
  write_file_atomically(f, [](std::ostream& o) { o << "good table\n"; });
  auto* previous_handler = std::signal(SIGXFSZ, SIG_IGN);
  rlimit before{};
  ASSERT_EQ(::getrlimit(RLIMIT_FSIZE, &before), 0);
  rlimit small = before;
  small.rlim_cur = 4096;
  ASSERT_EQ(::setrlimit(RLIMIT_FSIZE, &small), 0);
  std::string what;
  try {
    write_file_atomically(f, [](std::ostream& o) { o << std::string(100000, 'x'); });
  } catch (const std::runtime_error& e) {
    what = e.what();
  }
  ::setrlimit(RLIMIT_FSIZE, &before);
  std::signal(SIGXFSZ, previous_handler);
  EXPECT_NE(what.find(f.string()), std::string::npos) << what;
  EXPECT_NE(what.find("File too large"), std::string::npos) << what;
  EXPECT_EQ(content(f), "good table\n") << "the previous file was touched";
  EXPECT_TRUE(only_file_in(d, "fragments_final.csv")) << "a temporary file was left behind";
  fs::remove_all(d);
}

TEST(AtomicFile, AMissingFolderOrAFailingBodyWritesNothing) {
  const fs::path d = fresh_dir("missing");
  try {
    write_file_atomically(d / "no_such_folder" / "run.json", [](std::ostream& o) { o << "{}"; });
    ADD_FAILURE() << "wrote into a folder that does not exist";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("No such file or directory"), std::string::npos) << e.what();
  }
  const fs::path f = d / "sweep.csv";
  write_file_atomically(f, [](std::ostream& o) { o << "kept\n"; });
  EXPECT_THROW(write_file_atomically(f, [](std::ostream& o) {
                 o << "half";
                 throw std::runtime_error("the body failed");
               }),
               std::runtime_error);
  EXPECT_EQ(content(f), "kept\n");
  EXPECT_TRUE(only_file_in(d, "sweep.csv"));
  fs::remove_all(d);
}

TEST(AtomicFile, AWriterByNameThatThrowsLeavesNoTemporary) {
  const fs::path d = fresh_dir("byname"), f = d / "crack.mp4";
  write_file_atomically(f, std::string_view("old movie"));
  EXPECT_THROW(write_file_atomically_by_name(f, [](const fs::path& tmp) -> bool {
                 std::ofstream(tmp) << "half a movie";
                 throw std::runtime_error("the encoder failed");
               }),
               std::runtime_error);
  EXPECT_EQ(content(f), "old movie");
  EXPECT_TRUE(only_file_in(d, "crack.mp4")) << "a temporary file was left behind";
  fs::remove_all(d);
}

TEST(ReplaceDirectory, TheStagedFolderTakesThePlaceOfTheOldOneWhole) {
  const fs::path d = fresh_dir("replace_dir"), frames = d / "frames", staged = d / "frames.part";
  // First render: no frames/ yet.
  fs::create_directories(staged);
  write_file_atomically(staged / "frame_00000.png", std::string_view("a0"));
  replace_directory(frames, staged);
  EXPECT_EQ(content(frames / "frame_00000.png"), "a0");
  EXPECT_FALSE(fs::exists(staged));
  // A second render of other frames replaces the first one's entirely: nothing of it is left to mix in.
  fs::create_directories(staged);
  write_file_atomically(staged / "frame_00005.png", std::string_view("b5"));
  replace_directory(frames, staged);
  EXPECT_TRUE(only_file_in(frames, "frame_00005.png"));
  EXPECT_EQ(content(frames / "frame_00005.png"), "b5");
  EXPECT_TRUE(only_file_in(d, "frames")) << "the previous frames or the staged folder were left behind";
  // A staged folder that is missing is an error naming the folder; the frames stay.
  try {
    replace_directory(frames, staged);
    ADD_FAILURE() << "replaced the frames with a folder that does not exist";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(frames.string()), std::string::npos) << e.what();
  }
  EXPECT_EQ(content(frames / "frame_00005.png"), "b5");
  fs::remove_all(d);
}

TEST(MakeFolder, MakesParentsAndRefusesAFileWhereTheFolderShouldBe) {
  const fs::path d = fresh_dir("make_folder");
  make_folder(d / "a" / "b");
  EXPECT_TRUE(fs::is_directory(d / "a" / "b"));
  make_folder(d / "a" / "b");  // already there: nothing to do
  write_file_atomically(d / "frames", std::string_view("keep"));
  for (const fs::path& p : {d / "frames", d / "frames" / "sub"}) {
    try {
      make_folder(p);
      ADD_FAILURE() << "made " << p << " through a file";
    } catch (const std::runtime_error& e) {
      EXPECT_NE(std::string(e.what()).find(p.string() + ": "), std::string::npos) << e.what();
    }
  }
  // replace_directory refuses too, and both leave the file as it was.
  make_folder(d / "frames.part");
  EXPECT_THROW(replace_directory(d / "frames", d / "frames.part"), std::runtime_error);
  EXPECT_EQ(content(d / "frames"), "keep");
  EXPECT_TRUE(fs::is_directory(d / "frames.part"));
  fs::remove_all(d);
}

TEST(AtomicFile, AKilledWritersTemporariesAreRemovedAndNothingElse) {
  const fs::path d = fresh_dir("stale");
  for (const char* name : {"frame_00003.vtu.tmp.4242", "summary.json", "notes.tmp.txt", "a.tmp."})
    std::ofstream(d / name) << "x";
  remove_temporaries(d);
  EXPECT_FALSE(fs::exists(d / "frame_00003.vtu.tmp.4242"));
  EXPECT_TRUE(fs::exists(d / "summary.json"));
  EXPECT_TRUE(fs::exists(d / "notes.tmp.txt"));
  EXPECT_TRUE(fs::exists(d / "a.tmp."));
  fs::remove_all(d);
}
