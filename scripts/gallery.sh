#!/usr/bin/env bash
# The main job: install what is needed, build, and render the default gallery
# (noon sky, sunset, all-sky fisheye, the planet from orbit; Earth and Mars)
# as PNG and OpenEXR files into gallery/.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
bash "$root/scripts/setup.sh"
bash "$root/scripts/build.sh"
out="${ATMOS_GALLERY_DIR:-$root/gallery}"
mkdir -p "$out/earth" "$out/mars"
(cd "$out/earth" && "$root/build/atmos" render --planet earth)
(cd "$out/mars" && "$root/build/atmos" render --planet mars)
echo "gallery: $out"
