#!/usr/bin/env bash
# pmfrag render --movie: an MP4 with one video frame per PNG frame, a GIF, no stale frames from an earlier
# render in the movie, and a clear error (frames kept) when ffmpeg is missing.
#   movie_test.sh PMFRAG SOURCE_DIR
set -u
pmfrag=$1 src=$2
source "$(dirname "$0")/check.sh"
d=$(mktemp -d)
trap 'rm -rf "$d"' EXIT
"$pmfrag" run "$src/cases/impact.toml" --out "$d/run" -q --set time.end=2e-4 --set output.every=2e-5 > /dev/null || exit 1
count() { ffprobe -v error -count_frames -select_streams v:0 -show_entries stream=nb_read_frames -of csv=p=0 "$1"; }

"$pmfrag" render "$d/run" --size 160 --movie > "$d/out.txt" 2>&1
check "render --movie exits 0" "[ $? -eq 0 ]"
check "11 PNG frames" "[ \$(ls $d/run/frames/frame_*.png | wc -l) -eq 11 ]"
check "crack.mp4 has the 11 frames, at least 160 px wide" "[ \"\$(count $d/run/crack.mp4)\" = 11 ] && [ \$(ffprobe -v error -show_entries stream=width -of csv=p=0 $d/run/crack.mp4) -ge 160 ]"
check "crack.gif is a GIF with 11 frames" "head -c 6 $d/run/crack.gif | grep -q GIF89a && [ \"\$(count $d/run/crack.gif)\" = 11 ]"
check "no temporary files left" "! ls $d/run/*.tmp $d/run/movie.log 2>/dev/null"

"$pmfrag" render "$d/run" --size 160 --every 5 --movie > /dev/null 2>&1
check "a second render replaces the frames (0, 5, 10)" "[ \$(ls $d/run/frames/frame_*.png | wc -l) -eq 3 ]"
check "and the movie holds only those 3" "[ \"\$(count $d/run/crack.mp4)\" = 3 ]"

err=$(PATH=/nonexistent "$pmfrag" render "$d/run" --size 160 --every 2 --movie 2>&1 >/dev/null); rc=$?
check "without ffmpeg: non-zero exit naming ffmpeg" "[ $rc -ne 0 ] && echo \"\$err\" | grep -q ffmpeg"
check "without ffmpeg: the frames are still written" "[ \$(ls $d/run/frames/frame_*.png | wc -l) -eq 6 ]"
exit $fail
