#include "pmfrag/io/atomic_file.hpp"

#include <fcntl.h>
#include <stdio.h>  // renameat2
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <sstream>
#include <stdexcept>
#include <string>

namespace pmfrag {

namespace fs = std::filesystem;

namespace {

// The temporary name: beside the file (a rename within one folder is atomic), unique to this process.
fs::path temporary_for(const fs::path& path) { return path.string() + ".tmp." + std::to_string(::getpid()); }

[[noreturn]] void fail(const fs::path& path, const fs::path& tmp, int error) {
  ::unlink(tmp.c_str());
  throw std::runtime_error(path.string() + ": cannot write: " + std::strerror(error) + " (the previous file is unchanged)");
}

// Flushes the temporary file to disk and renames it over the file; on failure removes it and throws.
void commit(const fs::path& path, const fs::path& tmp) {
  const int fd = ::open(tmp.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) fail(path, tmp, errno);
  if (::fsync(fd) != 0) {
    const int error = errno;
    ::close(fd);
    fail(path, tmp, error);
  }
  ::close(fd);
  if (::rename(tmp.c_str(), path.c_str()) != 0) fail(path, tmp, errno);
}

}  // namespace

void write_file_atomically(const fs::path& path, const std::function<void(std::ostream&)>& body) {
  std::ostringstream text;
  body(text);  // a body that throws leaves nothing behind: no file was opened yet
  write_file_atomically(path, std::string_view(text.view()));
}

void write_file_atomically(const fs::path& path, std::string_view bytes) {
  const fs::path tmp = temporary_for(path);
  const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) fail(path, tmp, errno);
  for (std::size_t done = 0; done < bytes.size();) {
    const ssize_t n = ::write(fd, bytes.data() + done, bytes.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      const int error = n < 0 ? errno : EIO;
      ::close(fd);
      fail(path, tmp, error);
    }
    done += static_cast<std::size_t>(n);
  }
  if (::fsync(fd) != 0) {
    const int error = errno;
    ::close(fd);
    fail(path, tmp, error);
  }
  if (::close(fd) != 0) fail(path, tmp, errno);
  if (::rename(tmp.c_str(), path.c_str()) != 0) fail(path, tmp, errno);
}

void write_file_atomically_by_name(const fs::path& path, const std::function<bool(const fs::path& tmp)>& write) {
  const fs::path tmp = temporary_for(path);
  errno = 0;
  bool written = false;
  try {
    written = write(tmp);
  } catch (...) {
    ::unlink(tmp.c_str());
    throw;
  }
  if (!written) fail(path, tmp, errno != 0 ? errno : EIO);
  commit(path, tmp);
}

void remove_temporaries(const fs::path& dir) {
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(dir, ec)) {
    const std::string name = e.path().filename().string();
    const auto at = name.rfind(".tmp.");
    if (at == std::string::npos || at + 5 == name.size()) continue;
    if (name.find_first_not_of("0123456789", at + 5) != std::string::npos) continue;
    if (e.is_regular_file(ec)) fs::remove(e.path(), ec);
  }
}

void require_folder_or_nothing(const fs::path& dir) {
  std::error_code ec;
  if (fs::exists(fs::symlink_status(dir, ec)) && !fs::is_directory(dir, ec))
    throw std::runtime_error(dir.string() + ": is a file, not a folder (move it away or choose another folder)");
}

void make_folder(const fs::path& dir) {
  require_folder_or_nothing(dir);
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec) throw std::runtime_error(dir.string() + ": cannot make the folder: " + ec.message());
}

void replace_directory(const fs::path& dir, const fs::path& staged) {
  const auto fail_dir = [&](int error) {
    throw std::runtime_error(dir.string() + ": cannot replace with " + staged.string() + ": " + std::strerror(error));
  };
  require_folder_or_nothing(dir);
  std::error_code ec;
  if (!fs::exists(dir, ec)) {
    if (::rename(staged.c_str(), dir.c_str()) != 0) fail_dir(errno);
    return;
  }
  if (::renameat2(AT_FDCWD, staged.c_str(), AT_FDCWD, dir.c_str(), RENAME_EXCHANGE) != 0) {
    if (errno != EINVAL && errno != ENOSYS) fail_dir(errno);
    // No exchange on this filesystem: the old folder steps aside first, so the new one can take its name.
    const fs::path old = dir.string() + ".old." + std::to_string(::getpid());
    if (::rename(dir.c_str(), old.c_str()) != 0) fail_dir(errno);
    if (::rename(staged.c_str(), dir.c_str()) != 0) {
      const int error = errno;
      ::rename(old.c_str(), dir.c_str());
      fail_dir(error);
    }
    fs::remove_all(old, ec);
    return;
  }
  fs::remove_all(staged, ec);  // it holds the previous content now
}

}  // namespace pmfrag
