// Reading back what a run folder holds: whole text files. Shared by the commands that gather runs (sweep,
// study); run.json is read by pmfrag::read_run_record, summary.json with nlohmann-json.
#pragma once

#include <filesystem>
#include <string>

namespace pmfrag::app {

/// The file's text, or "" if it cannot be read.
std::string slurp(const std::filesystem::path& p);

}  // namespace pmfrag::app
