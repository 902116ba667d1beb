// Child processes for the commands that delegate work: sweep workers (this very executable) and ffmpeg for
// movies. POSIX only.
#pragma once

#include <sys/types.h>

#include <filesystem>
#include <string>
#include <vector>

namespace pmfrag::app {

/// Starts `program` (a path; or, with search_path, a name looked up on PATH) with args (args[0] is the name
/// it sees), its stdout and stderr appended to `log`. Throws std::runtime_error if it cannot start.
pid_t start_process(const std::string& program, const std::vector<std::string>& args,
                    const std::filesystem::path& log, bool search_path = false);

/// A sweep's workers die with the sweep: the sweep calls become_worker_parent() before starting them, and
/// every pmfrag process calls exit_with_worker_parent() first. A worker whose sweep is gone (killed, however)
/// then gets SIGTERM (a run writes its checkpoint and stops), so no orphan goes on writing into a case folder
/// that a rerun of the sweep clears.
void become_worker_parent();
void exit_with_worker_parent();

/// Path of an executable named `name` on PATH, or "" if there is none.
std::string find_on_path(const std::string& name);

}  // namespace pmfrag::app
