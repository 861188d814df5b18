#!/usr/bin/env bash
# The main job: install what is needed, build, and render the default gallery
# (noon sky, sunset, all-sky fisheye, the planet from orbit) of Earth, the
# dusty Mars, Titan and Venus, spectral, as PNG and OpenEXR files into
# gallery/<planet>/ (the images of README.md).
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
bash "$root/scripts/setup.sh"
bash "$root/scripts/build.sh"
atmos="${ATMOS_BUILD_DIR:-$root/build}/apps/atmos"
out="${ATMOS_GALLERY_DIR:-$root/gallery}"
mkdir -p "$out/earth" "$out/mars" "$out/venus" "$out/titan"
# Spectral (15 wavelengths), orders until the rest would add less than
# 0.1 % (Earth 14, Mars 11; Titan and Venus are foreseen to reach the cap of 64
# and solve the rest at once from order 16). About 14 minutes on 2 cores with
# an empty table cache, most of it Titan's and Venus's precomputation (Venus
# alone 4-7 minutes; cached afterwards).
for planet in earth mars titan venus; do
  (cd "$out/$planet" && "$atmos" render --planet "$planet" --wavelengths 15 --orders auto)
done
# Earth's sunset through the camera-like post chain: filmic tone map and bloom.
(cd "$out/earth" && "$atmos" render --planet earth --wavelengths 15 --orders auto --look 270,8 --fov 75 \
  --sun-azimuth 270 --sun-elevation 1 --size 960x540 --exposure 10.5 --tonemap filmic --bloom 0.05 \
  -o sunset-bloom.png)
# Earth at dusk, the sun 3° below the horizon (the ozone layer's absorption
# colours the zenith).
(cd "$out/earth" && "$atmos" render --planet earth --wavelengths 15 --sun-elevation -3 --sun-azimuth 180 \
  --look 180,4 --fov 70 --size 640x360 --exposure 7 -o dusk-spectral.png)
# Earth's night sky with the star field (the sun 18° below the horizon).
(cd "$out/earth" && "$atmos" render --planet earth --wavelengths 15 --orders auto --altitude 2 --look 315,35 \
  --fov 60 --size 960x540 --sun-elevation -18 --sun-azimuth 135 --exposure -3 -o night-stars.png)
# A total solar eclipse (a moon 0.28° wide over the sun, 25° up) from the
# ground, and the moon's shadow from 4000 km: the moon's elevation there,
# 49.4698°, puts it on the line from the sun through the ground point
# 1200 km south of the camera's nadir (at 384 400 km from the camera).
(cd "$out/earth" && "$atmos" render --planet earth --wavelengths 15 --orders auto --altitude 2 --sun-elevation 25 \
  --sun-azimuth 180 --moon 180,25,0.28 --look 180,19 --fov 50 --size 960x600 --stars --tonemap filmic \
  --bloom 0.05 --exposure 4.5 -o eclipse-ground.png)
(cd "$out/earth" && "$atmos" render --planet earth --wavelengths 15 --orders auto --altitude 4000000 \
  --sun-elevation 50 --sun-azimuth 180 --moon 180,49.4698,0.28 --look 180,-82 --fov 88 --size 960x600 \
  --tonemap filmic --exposure 12.5 -o eclipse-orbit.png)
# The total eclipse of 2024-04-08 from Dallas at 18:42:30 UTC, by date and
# place (the sun and the Moon from the ephemeris, docs/ephemeris.md), looking
# at the eclipsed sun 64° up over the orange ring of the horizon beyond the
# umbra.
(cd "$out/earth" && "$atmos" render --planet earth --wavelengths 15 --orders auto --date 2024-04-08T18:42:30Z \
  --latitude 32.78 --longitude -96.80 --look 170,40 --fov 90 --size 960x540 --stars --exposure 2 \
  -o eclipse-dallas.png)
# The real night sky by date and place: Orion, Sirius, Procyon, Aldebaran
# and the Pleiades over Vienna on 2025-01-29 at 20:30 UTC (new Moon, the sun
# 46° down), the Yale Bright Star Catalogue's stars placed by the sidereal
# time (docs/ephemeris.md, Drawing the stars).
(cd "$out/earth" && "$atmos" render --planet earth --wavelengths 15 --orders auto --date 2025-01-29T20:30:00Z \
  --latitude 48.21 --longitude 16.37 --altitude 2 --look 175,35 --fov 70 --size 960x540 --exposure -3 \
  -o night-orion-vienna.png)
# Mars's blue sunset: the glow around the sun, at EV 13 (the default
# sunset's exposure saturates it).
(cd "$out/mars" && "$atmos" render --planet mars --wavelengths 15 --orders auto --altitude 2 --look 270,6 --fov 60 \
  --sun-azimuth 270 --sun-elevation 3 --exposure 13 --tonemap filmic --size 960x540 -o blue-sunset.png)
# Under Venus' clouds: the surface sky at EV 8 (0.96-1.01 of the
# references' light on the ground at 550 nm: see README, Planets).
(cd "$out/venus" && "$atmos" render --planet venus --wavelengths 15 --orders auto --sun-elevation 40 --look 180,10 \
  --exposure 8 -o surface.png -o surface.exr)
# The example engine (examples/terrain): its own terrain and objects,
# composited by the engine plugin (atmos::AtmospherePass), default tables,
# 1280x720: haze over a valley at noon, light shafts at sunset, the same
# terrain from 400 km. Each also without the plugin (-raw), for comparison.
example="${ATMOS_BUILD_DIR:-$root/build}/examples/atmos_example_terrain"
mkdir -p "$out/plugin"
for scene in noon-valley sunset-shafts orbit-400km; do
  (cd "$out/plugin" && "$example" --scene "$scene" -o "$scene.png" -o "$scene.exr" &&
    "$example" --scene "$scene" --no-atmosphere -o "$scene-raw.png")
done
# The terrain globe (atmos::Globe, examples/globe) under the plugin, 960x540:
# Earth (Blue Marble imagery, GSHHG coasts) from 2.5 planet radii at noon and
# at the terminator, north up; a descent of five frames from 2.5 radii to 2 m
# onto the Red Sea's Egyptian coast; Mars's southern highlands from orbit
# and from 2 m; and the canyon of the Mars style (the mars-thesis air, the
# clearer one) at sunset, from 100 m above its floor 7 km south of its north
# wall, looking west along it into the blue glow around the sun (2.5° up).
globe="${ATMOS_BUILD_DIR:-$root/build}/examples/atmos_example_globe"
mkdir -p "$out/globe/earth" "$out/globe/earth-noon" "$out/globe/earth-terminator" "$out/globe/mars" \
  "$out/globe/mars-canyon"
# Noon from orbit at EV 15, a sunlit scene's exposure (the "sunny 16" rule:
# f/16 at 1/ISO s); at the default EV 13 the sunlit desert saturates.
"$globe" --planet earth --descent 1 --latitude 10 --longitude 20 --heading 0 --sun-elevation 90 --exposure 15 \
  --out-dir "$out/globe/earth-noon"
"$globe" --planet earth --descent 1 --latitude 10 --longitude 20 --heading 0 --sun-elevation 0 --sun-azimuth 90 \
  --out-dir "$out/globe/earth-terminator"
"$globe" --planet earth --descent 5 --latitude 26.5 --longitude 33.6 --sun-elevation 35 --sun-azimuth 200 \
  --out-dir "$out/globe/earth"
"$globe" --planet mars --latitude -35 --longitude 60 --descent 5 --sun-elevation 12 --exposure 12 \
  --out-dir "$out/globe/mars"
"$globe" --planet mars-thesis --descent 2 --from-radii 1 --to 100 --latitude -1.38 --longitude 138.27 \
  --heading 280 --sun-elevation 2.5 --sun-azimuth 250 --exposure 10 --shadow-distance 150000 \
  --out-dir "$out/globe/mars-canyon"
# The sea (atmos::Ocean over the globe, 7 m/s of wind) over the Pacific: a
# sunset from a ship's deck (2 m, the sun 3° up ahead) and the sun's glint
# from 1.5 planet radii (the sun 50° up at the ground point).
mkdir -p "$out/globe/ocean-deck" "$out/globe/ocean-glint"
"$globe" --planet earth --ocean --wind 7 --descent 2 --from-radii 0.001 --to 2 --latitude 0 --longitude -150 \
  --heading 270 --sun-elevation 3 --sun-azimuth 270 --exposure 11 --out-dir "$out/globe/ocean-deck"
"$globe" --planet earth --ocean --wind 7 --descent 1 --from-radii 1.5 --latitude 5 --longitude -150 \
  --sun-elevation 50 --sun-azimuth 90 --exposure 13 --out-dir "$out/globe/ocean-glint"
# A shallow lagoon: the sea's shelf, 2 m deep for 19 km off the coast of
# Andros in the Bahamas (the Earth style's relief off GSHHG's coast), from
# 1.5 km, 25° down, the sun 60° up behind the camera: the sand shows
# through the water up to a low coast beyond. The bathymetry at 1024
# texels per cube face (10 km) resolves the shelf.
mkdir -p "$out/globe/ocean-lagoon" "$out/globe/ocean-eclipse"
"$globe" --planet earth --ocean --wind 4 --bathymetry-texels 1024 --descent 1 --from-radii 0.000235 \
  --latitude 24.6 --longitude -77.55 --heading 200 --pitch -25 --sun-elevation 60 --sun-azimuth 330 --exposure 13.5 \
  --out-dir "$out/globe/ocean-lagoon"
# The sea in the umbra of a total solar eclipse: from a ship's bridge (6 m)
# over the Pacific, a moon 0.28° wide on the sun (30° up, west): the camera
# at the centre of an umbra about 180 km wide, the sky dark but for the
# twilight beyond the umbra along the horizon, mirrored by the sea; the
# sun's disc hidden, its corona as the pass draws it.
"$globe" --planet earth --ocean --wind 5 --descent 1 --from-radii 0.000001 --latitude 0 --longitude -150 \
  --heading 270 --pitch 10 --sun-elevation 30 --sun-azimuth 270 --moon 270,30,0.28 --stars --exposure 1 \
  --out-dir "$out/globe/ocean-eclipse"
# Stereo: the canyon at sunset as a red-cyan anaglyph, each eye through its
# own off-axis frustum (atmos render --stereo), 200 m apart (hyperstereo, for
# walls kilometres away) and converged at 5 km.
(cd "$out/mars" && "$atmos" render --planet mars-thesis --surface globe --latitude -1.38 --longitude 138.27 \
  --altitude 100 --look 280,2 --fov 60 --sun-elevation 2.5 --sun-azimuth 250 --exposure 10 --size 960x540 \
  --stereo anaglyph --ipd 200 --convergence 5000 -o canyon-anaglyph.png)
# The viewer (atmos view) under Xvfb, its panel shown: 400 km over the
# Mediterranean, the sun 12° up in the local frame of the ground below.
mkdir -p "$out/viewer"
xvfb-run -a -s "-screen 0 1280x720x24" "$atmos" view --frames 5 --altitude 400000 --pitch -22 --heading 20 \
  --sun-azimuth 250 --sun-elevation 12 --latitude 33 --longitude 8 --screenshot "$out/viewer/orbit-panel.png"
echo "gallery: $out"
