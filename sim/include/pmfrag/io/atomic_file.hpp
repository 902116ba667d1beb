// Outputs whole or absent: every file pmfrag writes in one go (run.json, summary.json, CSV tables, scene copies,
// VTU and PVD files, PNG frames, movies) goes through these helpers.
#pragma once

#include <filesystem>
#include <functional>
#include <ostream>
#include <string_view>

namespace pmfrag {

/// Writes `path` whole or not at all. `body` writes the content to a stream; it is then written to a temporary
/// file beside `path`, flushed to disk (fsync), closed and renamed over `path`. If anything fails (the body
/// throws, the disk is full, the folder is missing or read-only, a file-size limit is hit) the temporary file
/// is removed, `path` keeps its previous content, and std::runtime_error says which file and the system's
/// reason, e.g. "out/run/summary.json: cannot write: No space left on device (the previous file is unchanged)".
void write_file_atomically(const std::filesystem::path& path, const std::function<void(std::ostream&)>& body);

/// The same for content already in memory (a PNG frame encoded by libpng).
void write_file_atomically(const std::filesystem::path& path, std::string_view bytes);

/// The same for a file another library or program writes by name (VTK's writers, ffmpeg): `write(tmp)` writes
/// the temporary file and returns false if it failed (errno then says why, or EIO if it is 0) or throws; the
/// file is then flushed to disk and renamed over `path`, or removed.
void write_file_atomically_by_name(const std::filesystem::path& path,
                                   const std::function<bool(const std::filesystem::path& tmp)>& write);

/// Removes the temporary files these helpers leave when their process is killed mid-write (NAME.tmp.PID) from
/// `dir` (not its subfolders). Only for a folder whose writer holds its FolderLock: then any such file is stale.
void remove_temporaries(const std::filesystem::path& dir);

/// Makes the folder `dir` and its parents, as a place for outputs. Throws std::runtime_error in one line naming
/// the path and the cause: "PATH: cannot make the folder: Permission denied", or, when a file holds the name,
/// "PATH: is a file, not a folder (move it away or choose another folder)"; the file is left alone.
void make_folder(const std::filesystem::path& dir);

/// Throws the same "is a file, not a folder" error if a file holds the name `dir`; a folder or nothing passes.
/// For outputs that replace a folder at the end (replace_directory), checked before the work starts.
void require_folder_or_nothing(const std::filesystem::path& dir);

/// A folder of many files written whole or not at all (a render's frames/): the files are written into
/// `staged` (a sibling of `dir`), which then takes the place of `dir` in one step (renameat2 RENAME_EXCHANGE;
/// two renames where the filesystem lacks it), and the previous content is removed. Until then `dir` is
/// untouched. A file (not a folder) named `dir` is refused, not replaced. Throws std::runtime_error naming the folder and the system's reason.
void replace_directory(const std::filesystem::path& dir, const std::filesystem::path& staged);

}  // namespace pmfrag
