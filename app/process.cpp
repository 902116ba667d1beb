#include "process.hpp"

#include <fcntl.h>
#include <sys/prctl.h>
#include <spawn.h>
#include <unistd.h>

#include <csignal>
#include <cstdlib>
#include <string>
#include <sstream>
#include <stdexcept>

extern char** environ;

namespace pmfrag::app {

pid_t start_process(const std::string& program, const std::vector<std::string>& args,
                    const std::filesystem::path& log, bool search_path) {
  std::vector<char*> argv;
  for (const auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
  argv.push_back(nullptr);
  posix_spawn_file_actions_t fa;
  posix_spawn_file_actions_init(&fa);
  posix_spawn_file_actions_addopen(&fa, 1, log.c_str(), O_WRONLY | O_CREAT | O_APPEND, 0644);
  posix_spawn_file_actions_adddup2(&fa, 1, 2);
  pid_t pid = -1;
  const int rc = search_path ? posix_spawnp(&pid, program.c_str(), &fa, nullptr, argv.data(), environ)
                             : posix_spawn(&pid, program.c_str(), &fa, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&fa);
  if (rc != 0) throw std::runtime_error("cannot start " + program + " (log: " + log.string() + ")");
  return pid;
}

namespace {
constexpr const char* parent_variable = "PMFRAG_WORKER_OF";
}

void become_worker_parent() { ::setenv(parent_variable, std::to_string(::getpid()).c_str(), 1); }

void exit_with_worker_parent() {
  const char* parent = std::getenv(parent_variable);
  if (!parent) return;
  const pid_t sweep = static_cast<pid_t>(std::atol(parent));
  ::unsetenv(parent_variable);  // not for what this worker starts in turn
  if (sweep == ::getpid()) return;
  ::prctl(PR_SET_PDEATHSIG, SIGTERM);
  if (::getppid() != sweep) std::raise(SIGTERM);  // the sweep died before the signal was armed
}

std::string find_on_path(const std::string& name) {
  const char* path = std::getenv("PATH");
  std::stringstream dirs(path ? path : "/usr/bin:/bin");
  for (std::string d; std::getline(dirs, d, ':');) {
    const std::filesystem::path p = std::filesystem::path(d.empty() ? "." : d) / name;
    if (::access(p.c_str(), X_OK) == 0) return p.string();
  }
  return "";
}

}  // namespace pmfrag::app
