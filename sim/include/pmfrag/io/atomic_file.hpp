// Outputs whole or absent: every file pmfrag writes in one go (run.json, summary.json, CSV tables, scene copies,
// PVD collections) goes through write_file_atomically.
#pragma once

#include <filesystem>
#include <functional>
#include <ostream>

namespace pmfrag {

/// Writes `path` whole or not at all. `body` writes the content to a stream; it is then written to a temporary
/// file beside `path`, flushed to disk (fsync), closed and renamed over `path`. If anything fails (the body
/// throws, the disk is full, the folder is missing or read-only, a file-size limit is hit) the temporary file
/// is removed, `path` keeps its previous content, and std::runtime_error says which file and the system's
/// reason, e.g. "out/run/summary.json: cannot write: No space left on device (the previous file is unchanged)".
void write_file_atomically(const std::filesystem::path& path, const std::function<void(std::ostream&)>& body);

/// The same for a file another library writes by name (VTK's writers): `write(tmp)` writes the temporary file
/// and returns false if it failed; it is then flushed to disk and renamed over `path`, or removed.
void write_file_atomically_by_name(const std::filesystem::path& path,
                                   const std::function<bool(const std::filesystem::path& tmp)>& write);

}  // namespace pmfrag
