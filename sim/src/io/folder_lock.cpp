#include "pmfrag/io/folder_lock.hpp"

#include "pmfrag/io/atomic_file.hpp"

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <fstream>
#include <iterator>

namespace pmfrag {

namespace {
// This process's command line, its arguments joined by spaces (Linux: /proc/self/cmdline).
std::string command_line() {
  std::ifstream in("/proc/self/cmdline", std::ios::binary);
  std::string raw((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  while (!raw.empty() && raw.back() == '\0') raw.pop_back();
  for (char& c : raw)
    if (c == '\0') c = ' ';
  return raw.empty() ? "unknown command" : raw;
}

std::string read_holder(int fd) {
  char buf[512];
  const ssize_t n = pread(fd, buf, sizeof buf - 1, 0);
  if (n <= 0) return "another process (it has not named itself yet)";
  std::string s(buf, static_cast<std::size_t>(n));
  while (!s.empty() && (s.back() == '\n' || s.back() == '\0')) s.pop_back();
  return s;
}
}  // namespace

FolderLock::FolderLock(const std::filesystem::path& dir) {
  make_folder(dir);
  const std::filesystem::path file = file_of(dir);
  fd_ = open(file.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
  if (fd_ < 0)  // the first thing a writer puts in the folder, so this is where a read-only folder shows
    throw std::runtime_error(dir.string() + ": cannot write in the folder: " + std::strerror(errno) + " (its lock, " +
                             file.filename().string() + ", cannot be opened)");
  if (flock(fd_, LOCK_EX | LOCK_NB) != 0) {
    const int err = errno;
    const std::string holder = err == EWOULDBLOCK ? read_holder(fd_) : std::string();
    close(fd_);
    fd_ = -1;
    if (err == EWOULDBLOCK)
      throw FolderBusyError(dir.string() + ": in use by another pmfrag (" + holder +
                            "); one writer at a time: wait for it to finish, or use another folder");
    throw std::runtime_error(file.string() + ": cannot lock: " + std::strerror(err));
  }
  // Name the holder for whoever is refused (best effort: the lock itself is what counts).
  const std::string me = "pid " + std::to_string(getpid()) + ": " + command_line() + "\n";
  if (ftruncate(fd_, 0) == 0 && pwrite(fd_, me.data(), me.size(), 0) < 0) {
    // a full disk may refuse the note; the lock still holds
  }
  remove_temporaries(dir);  // what a killed writer left: with the lock held, no one else is writing them
}

FolderLock::~FolderLock() {
  if (fd_ >= 0) close(fd_);  // releases the lock
}

}  // namespace pmfrag
