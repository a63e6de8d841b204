#!/usr/bin/env bash
# Makes the seed corpora that code has to make (docs/reliability.md):
#   - visibility files, images, colour-map inputs: fuzz_make_seeds (make_seeds.cpp)
#   - tiny videos (Debian's ffmpeg encodes them) for video_file, and for
#     video_decoder what the shipped ffmpeg lists and decodes from them.
# Usage: tests/fuzz/make_seeds.sh <build folder with fuzz_make_seeds>
# (`make fuzz-seeds` builds it in build-asan and runs this). Seeds are small
# (a few KB); rerunning rewrites them identically except for the encoders'
# own metadata.
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
build=$1
"$build/tests/fuzz/fuzz_make_seeds" "$here"

decoder=${PENUMBRA_FFMPEG:-$here/../../.deps/imageio-ffmpeg-0.6.0/bin/ffmpeg}
videos=$here/video_file/corpus
listings=$here/video_decoder/corpus
mkdir -p "$videos" "$listings"
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
# 8x4 pixels (HEVC: 32x16, its smallest), 3 frames at 12 fps of a test pattern.
src=(-f lavfi -i "testsrc2=size=8x4:rate=12:duration=0.25")
ffmpeg -loglevel error -y "${src[@]}" -c:v libx264 -pix_fmt yuv420p -g 2 "$videos/h264.mp4"
ffmpeg -loglevel error -y "${src[@]}" -c:v mjpeg -pix_fmt yuvj444p "$videos/mjpeg.avi"
ffmpeg -loglevel error -y "${src[@]}" -c:v ffv1 "$videos/ffv1.mkv"
ffmpeg -loglevel error -y "${src[@]}" -c:v mpeg4 -pix_fmt yuv420p "$videos/mpeg4.mov"
ffmpeg -loglevel error -y -f lavfi -i "testsrc2=size=32x16:rate=12:duration=0.25" -c:v libx265 -x265-params log-level=none -pix_fmt yuv420p10le -tag:v hvc1 "$videos/hevc10.mp4"

# video_decoder inputs: status byte, listing, NUL, frames (video_decoder.cpp).
# The listing is the framecrc lines and FFmpeg's description of the input
# (the stand-in prints it on stdout and stderr); the frames are in the
# decoder's own pixel format, which the reader asks for when it is planar YUV.
for video in h264.mp4 mjpeg.avi ffv1.mkv; do
  name=${video%.*}
  "$decoder" -hide_banner -nostdin -nostats -v info -i "$videos/$video" -map 0:v:0 -c copy -f framecrc - \
    > "$tmp/listing" 2> "$tmp/description"
  format=$(sed -n 's/.*Stream #0:0.*: Video: [^,]*, \([a-z0-9]*\).*/\1/p' "$tmp/description" | head -n 1)
  "$decoder" -hide_banner -nostdin -v error -i "$videos/$video" -map 0:v:0 -f rawvideo -pix_fmt "$format" - > "$tmp/frames"
  cat "$tmp/description" >> "$tmp/listing"
  { printf '\000'; cat "$tmp/listing"; printf '\000'; cat "$tmp/frames"; } > "$listings/$name"
  # The decoder stops half-way through the second of the three frames, then fails.
  { printf '\360'; cat "$tmp/listing"; printf '\000'; head -c $(( $(stat -c %s "$tmp/frames") / 2 )) "$tmp/frames"; } \
    > "$listings/${name}_truncated"
done
# An 8K video whose decoder delivers almost nothing (the frame buffer must not
# be trusted to the listing's dimensions alone).
sed 's/^#dimensions 0: .*/#dimensions 0: 7680x4320/' "$tmp/listing" > "$tmp/listing8k"
{ printf '\360'; cat "$tmp/listing8k"; printf '\000'; head -c 60 "$tmp/frames"; } > "$listings/8k_truncated"
# The probe fails (ffmpeg's message on stderr, status 1).
printf '\017\000' > "$listings/probe_fails"
ls -l "$videos" "$listings"
