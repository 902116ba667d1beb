// Reading back what a run folder holds: whole text files and values from our own flat JSON (run.json,
// summary.json). Shared by the commands that gather runs (sweep, study).
#pragma once

#include <filesystem>
#include <string>

namespace pmfrag::app {

/// The file's text, or "" if it cannot be read.
std::string slurp(const std::filesystem::path& p);
/// The number after "key": (NaN if absent).
double json_number(const std::string& text, const std::string& key);
/// The string after "key": with escapes undone ("" if absent).
std::string json_string(const std::string& text, const std::string& key);

}  // namespace pmfrag::app
