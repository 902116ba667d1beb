// Movies of a rendered frame sequence, encoded by ffmpeg (Debian's package; installed by scripts/install-deps).
#pragma once

#include <filesystem>
#include <string>

namespace pmfrag::app {

/// Encodes every frames_dir/frame_*.png, in name order, into out_dir/crack.mp4 (H.264, `fps` frames per
/// second, plays everywhere) and out_dir/crack.gif (at most 360 px wide, 32-colour palette, for slides and
/// web pages). Each file is written under a temporary name and renamed. Throws std::runtime_error naming
/// ffmpeg's log (out_dir/movie.log, kept on failure) if ffmpeg is missing or fails.
void encode_movie(const std::filesystem::path& frames_dir, const std::filesystem::path& out_dir, double fps);

}  // namespace pmfrag::app
