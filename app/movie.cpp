#include "movie.hpp"

#include "process.hpp"
#include "pmfrag/io/atomic_file.hpp"

#include <sys/wait.h>

#include <cstdio>
#include <cstring>
#include <fstream>
#include <stdexcept>
#include <vector>

namespace pmfrag::app {

namespace fs = std::filesystem;

namespace {
// ffmpeg's own reason, the last line of its log (e.g. "Error writing trailer of ...: No space left on device").
std::string last_line(const fs::path& log) {
  std::ifstream in(log);
  std::string line, last;
  while (std::getline(in, line))
    if (!line.empty()) last = line;
  return last.empty() ? "exited with an error and no message" : last;
}
}  // namespace

void encode_movie(const fs::path& frames_dir, const fs::path& out_dir, double fps) {
  const std::string ffmpeg = find_on_path("ffmpeg");
  if (ffmpeg.empty())
    throw std::runtime_error("--movie needs ffmpeg, which is not on PATH (bash scripts/install-deps installs it)");
  const fs::path log = out_dir / "movie.log";
  fs::remove(log);
  char rate[32];
  std::snprintf(rate, sizeof rate, "%g", fps);
  const std::vector<std::string> input{"-y", "-loglevel", "error", "-framerate", rate, "-pattern_type", "glob",
                                       "-i", (frames_dir / "frame_*.png").string()};
  struct Output {
    std::string name;
    std::vector<std::string> args;
  };
  const std::vector<Output> outputs{
      // H.264 needs even sizes; yuv420p is what every player decodes.
      {"crack.mp4",
       {"-vf", "pad=ceil(iw/2)*2:ceil(ih/2)*2:color=white", "-c:v", "libx264", "-pix_fmt", "yuv420p", "-crf",
        "23", "-movflags", "+faststart", "-f", "mp4"}},
      // One palette for the whole clip keeps the GIF small and its colours steady.
      {"crack.gif",
       {"-vf", "scale='min(360,iw)':-2:flags=lanczos,split[a][b];[a]palettegen=max_colors=32[p];[b][p]paletteuse=dither=none",
        "-f", "gif"}},
  };
  for (const auto& out : outputs) {
    const fs::path file = out_dir / out.name;
    std::string why;
    try {
      // Whole or absent: ffmpeg writes a temporary file, renamed over the old movie only once it succeeded.
      write_file_atomically_by_name(file, [&](const fs::path& tmp) {
        std::vector<std::string> args{"ffmpeg"};
        args.insert(args.end(), input.begin(), input.end());
        args.insert(args.end(), out.args.begin(), out.args.end());
        args.push_back(tmp.string());
        const pid_t pid = start_process(ffmpeg, args, log);
        int status = 0;
        if (::waitpid(pid, &status, 0) == pid && WIFEXITED(status) && WEXITSTATUS(status) == 0) return true;
        why = WIFSIGNALED(status) ? std::string("killed by ") + strsignal(WTERMSIG(status)) : last_line(log);
        return false;
      });
    } catch (const std::runtime_error& e) {
      if (why.empty()) throw;  // ffmpeg succeeded; the flush or the rename failed, and the message says why
      throw std::runtime_error(file.string() + ": cannot write: ffmpeg: " + why + " (the previous file is unchanged; " +
                               "its log is " + log.string() + ")");
    }
  }
  fs::remove(log);
}

}  // namespace pmfrag::app
