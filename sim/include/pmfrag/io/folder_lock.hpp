// One writer per run folder. `pmfrag run`, `--resume`, `fragments`, `export` and `render` write into a run
// folder; two at once would leave one run's trajectory beside another's run.json. Each holds an advisory
// lock (flock) on DIR/.pmfrag.lock while it writes, and a second writer is refused at once, told who holds
// it. The kernel drops the lock when its holder exits, however it exits, so a killed process leaves no
// stale lock. Readers that write nothing take no lock and never wait.
#pragma once

#include <filesystem>
#include <stdexcept>
#include <string>

namespace pmfrag {

/// Thrown when another process holds the folder's lock.
struct FolderBusyError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

class FolderLock {
 public:
  /// Takes the lock of `dir` (created if missing) or throws FolderBusyError naming the holder's pid and
  /// command line; throws std::runtime_error naming the path and the cause if the lock file cannot be made.
  explicit FolderLock(const std::filesystem::path& dir);
  ~FolderLock();
  FolderLock(const FolderLock&) = delete;
  FolderLock& operator=(const FolderLock&) = delete;

  /// The lock file, DIR/.pmfrag.lock: while held it names the holder ("pid 1234: pmfrag run ...").
  static std::filesystem::path file_of(const std::filesystem::path& dir) { return dir / ".pmfrag.lock"; }

 private:
  int fd_ = -1;
};

}  // namespace pmfrag
