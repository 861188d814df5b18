// atmos — the planet's surface: a terrain globe drawn under the atmosphere.
//
// The globe is a quadtree of terrain tiles on the equal-angle cube-sphere
// (Ronchi, Iacono & Paolucci 1996), refined where a tile's geometric error
// would exceed a screen-space bound (Ulrich 2002), with vertices that morph
// towards their parent's grid before the parent takes over (Strugar 2009),
// so that levels change without popping and neighbours of different levels
// meet without cracks; skirts hide what rounding leaves. Tile positions are
// kept in double precision and drawn relative to the camera (Cozzi & Ring
// 2011, ch. 5), with reversed-Z depth (Reed 2015), so that nothing jitters at
// a metre above the ground nor at a hundred planet radii.
//
// The globe uses atmos as an engine does: it lights its surface in its own
// shaders with the GLSL library of an AtmospherePass (the sun's transmittance
// and the sky's irradiance at each point's own altitude; the planet's
// shadow), and writes lit colour and depth that the engine hands to
// AtmospherePass::render() (SurfaceMode::lit_colour,
// DepthEncoding::reversed_z), which adds the aerial perspective and the sky.
//
// Units: positions in the engine's world frame and units (PlanetFrame of the
// pass), heights in metres, radiance as FrameInput (cd/m² divided by
// nits_per_unit, linear sRGB).
//
// Eclipses (GlobeView::moons): the moons dim each ground point's light as
// the pass dims the G-buffer surfaces it lights itself, the sun's part by
// the fraction of the limb-darkened sun they leave the point and the sky's
// by the documented approximation for diffuse light (atmos_eclipse of
// plugin.hpp's GLSL library), evaluated per pixel; so the lit colour
// needs no dimming by the engine. Give the FrameInput the same moons.
//
// Sun shadows of the terrain (opt-in, GlobeSettings::shadow_cascades):
// cascaded shadow maps near the camera (Dimitrov 2007) at the practical
// split scheme's distances (Zhang et al. 2006), which dim the sun's part of
// the ground's light (not the sky's), and whose largest cascade the engine
// hands to AtmospherePass::render() for its light shafts
// (shadow_map_for_pass).
//
// Threading and GL state: as AtmospherePass (plugin.hpp): construct, draw
// and destroy with the engine's OpenGL 4.5 core context current. draw()
// changes the bound program, vertex array, buffers, texture units
// first_unit..first_unit+4 of the pass's library, the clip control (left at
// GL_LOWER_LEFT, GL_ZERO_TO_ONE), the depth function (GL_GREATER) and test
// (enabled), and disables face culling and blending. With shadows it also
// renders into its own framebuffers (then binds again the draw framebuffer
// that was bound), binds texture unit first_unit+5 and a sampler object
// there, and leaves depth clamping disabled. Unless
// GlobeSettings::complete_every_frame, a globe runs one thread of its own
// that builds tile meshes on the CPU (it makes no GL call); the destructor
// stops it, waiting for the tile it is building.
#pragma once

#include <glm/mat4x4.hpp>
#include <glm/vec3.hpp>

#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <vector>

#include "atmos/atmosphere.hpp"
#include "atmos/eclipse.hpp"
#include "atmos/planet_file.hpp"
#include "atmos/plugin.hpp"

namespace atmos {

struct GlobeSettings {
  // The largest screen-space geometric error of the drawn mesh, in pixels of
  // the viewport's height (the bound refines tiles until it holds, down to
  // the finest level).
  double max_screen_error_px = 1.0;
  // Tiles uploaded per draw() at most (bounds a frame's upload time; about
  // 23 KB each). A background thread, one per globe, builds the tiles a
  // draw lacks and their ancestors, coarse levels first, then the nearest;
  // the draw uploads those it has finished, and until its tile arrives an
  // area is drawn by its nearest resident ancestor, never left open. The
  // thread keeps at most twice this many finished tiles waiting (CPU
  // memory).
  int max_tiles_per_frame = 48;
  // GPU memory of the resident tiles, bytes, never exceeded: the least
  // recently drawn tiles are evicted, and new tiles that would not fit
  // beside the current frame's stay pending, drawn by their ancestors (a
  // coarser view, not more memory); they are not built either. At least
  // the 30 tiles of levels 0 and 1 (0.7 MB), always resident.
  std::size_t memory_cap_bytes = std::size_t(256) << 20;
  // Build every tile the view needs in draw() (in parallel, with TBB) and
  // upload it before drawing (stills, tests, benchmarks), within the memory
  // cap: no ancestor stands in, no background thread, no upload bound.
  bool complete_every_frame = false;
  // The texture units of the atmosphere's GLSL library: first_unit..first_unit+4
  // (and first_unit+5: the shadow maps).
  int first_unit = 0;

  // Sun shadows of the terrain: the number of cascades, 0 (off: no shadow
  // maps, no cost, the unshadowed image) to 4. Each cascade is a square
  // depth map of shadow_map_size texels a side (even, 64..16384;
  // GL_DEPTH_COMPONENT32F, owned by the globe) covering a slice of the view
  // frustum between the nearest drawn ground and shadow_distance_m; the
  // slices' texels grow with their distance from the camera (practical
  // splits, Zhang et al. 2006). With 4 x 2048 texels over 20 km, a camera
  // 2 m above the ground and a 60 degree field of view, the texels measure
  // about 0.13, 0.4, 2.3 and 24 m from the nearest slice to the farthest.
  int shadow_cascades = 0;
  int shadow_map_size = 2048;  // texels
  // How far shadows reach: view depth from the camera, m (> 0). They fade
  // out over the last tenth of the farthest cascade; beyond, and from
  // cameras whose nearest ground is farther (from orbit), the ground is
  // sunlit and no shadow map is drawn.
  double shadow_distance_m = 20e3;
};

// One view: the same frame as the FrameInput that follows it.
struct GlobeView {
  glm::dmat4 view{1.0};        // world -> view, engine units (rigid)
  glm::dmat4 projection{1.0};  // view -> clip, reversed-Z (near plane at depth 1): reversed_z_projection()
  int width = 0;               // viewport, pixels
  int height = 0;
  glm::dvec3 sun_direction{0.0, 0.0, 1.0};  // world frame, towards the sun
  double sun_illuminance_lux = 0.0;          // as FrameInput: 0 = the atmosphere's own sun
  double nits_per_unit = 1.0;                // cd/m² per unit of the colour written
  // Moons that eclipse the sun, as FrameInput::moons: at most kMaxMoons
  // spheres in PLANET-CENTRED METRES in the world's axes (not engine
  // units), validated as validate_moons does. Empty, or no moon near
  // enough to the sun to hide any of it from the atmosphere
  // (moons_may_eclipse): the uneclipsed light, at no cost. With an eclipse
  // the ground's pixels run the eclipse's overlaps (~60 disc overlaps
  // each), and the first such draw compiles the eclipse's shaders.
  std::vector<Moon> moons;
};

struct GlobeStats {
  int tiles_drawn = 0;      // including ancestors standing in for pending tiles
  int tiles_pending = 0;    // selected (for the view or as shadow casters) but not yet resident
  int tiles_generated = 0;  // made resident this draw (built, here or by the background thread, and uploaded)
  int tiles_queued = 0;     // after the draw: requests the background thread has yet to build
  int tiles_ready = 0;      // after the draw: tiles built and waiting for an upload (CPU memory)
  int nodes_visited = 0;    // quadtree nodes visited by the selection
  int view_selections = 0;  // the view's selections this draw: 1, for all the views of draw_views too
  long long triangles = 0;  // drawn, skirts included
  double selection_ms = 0.0;   // CPU: the quadtree traversal and culling
  // CPU time of draw()'s thread for new tiles: their requests and uploads,
  // and with complete_every_frame their building (relief and meshes).
  double generation_ms = 0.0;
  std::size_t resident_bytes = 0;  // GPU memory of the resident tiles after the draw
  int shadow_cascades = 0;        // cascades drawn (0: none this frame)
  int shadow_casters = 0;         // tile draws into the cascades, all cascades together
  long long shadow_triangles = 0;  // drawn into the cascades, skirts included
  double shadow_selection_ms = 0.0;  // CPU: the cascades' fit and their casters' selections
};

// A cascade of the globe's sun shadows for AtmospherePass::render(): the
// FrameInput's shadow_map and shadow_matrix.
struct GlobeShadowMap {
  // A GL_TEXTURE_2D of GL_DEPTH_COMPONENT32F (a view of one layer of the
  // globe's cascades, owned by the globe; valid until its destruction),
  // standard depth (0 towards the sun); 0: no shadows this frame.
  std::uint32_t texture = 0;
  // The engine's world (engine units) -> the cascade's clip space: an
  // orthographic projection from the sun, standard [-1, 1] depth.
  glm::dmat4 matrix{1.0};
  double texel_m = 0.0;  // the side of a texel, m
};

class Globe {
 public:
  // Builds the globe of `atmosphere`'s planet (its datum is the atmosphere's
  // bottom radius) with the relief of `surface` (load_surface: a planet
  // file's "surface"), lit through `pass`, which must outlive the globe.
  // Throws atmos::Error on invalid settings, a sea level outside the
  // atmosphere (below the planet's centre or above its top), a surface
  // whose lowest point lies below the pass's atmosphere (give the pass
  // extend_below_datum(atmosphere, surface)), or without a current OpenGL
  // 4.5 context.
  Globe(const Atmosphere& atmosphere, const PlanetSurface& surface, const AtmospherePass& pass,
        const GlobeSettings& settings = {});
  ~Globe();
  Globe(const Globe&) = delete;
  Globe& operator=(const Globe&) = delete;

  // Binds the globe to another atmosphere of the same planet and its pass
  // (new tables: another density, other constituents, other wavelengths),
  // keeping the surface, its open rasters and the resident tiles, so that
  // new tables cost one link of the lit programs (a cache hit once the
  // driver has compiled them for `pass`) instead of a new globe, and none
  // when `pass`'s glsl_library() is the text the globe's programs were
  // linked with (an atmosphere of the same structure). `pass`
  // must outlive the globe (the old one may then be destroyed). Throws
  // atmos::Error, with the globe still bound to its old pass, when
  // `atmosphere`'s bottom radius is not the globe's datum (the relief is
  // built on it: build a new Globe), on a sea level outside `atmosphere`,
  // or a pass that does not reach the lowest ground, as the constructor.
  void rebind(const Atmosphere& atmosphere, const AtmospherePass& pass);
  // Links the programs rebind(..., pass) needs (the lit programs with
  // `pass`'s library, none when that is the library the globe draws with)
  // for it to take instead of linking them itself: it
  // may run on another thread whose current context shares the globe's
  // objects (a GL share group) while the globe draws on, but not while
  // rebind() or another link_rebind_programs() runs. Throws atmos::Error on
  // compile errors.
  void link_rebind_programs(const AtmospherePass& pass);

  // Draws the surface into the bound framebuffer's colour attachment 0 (lit
  // colour, RGB) and depth attachment (reversed-Z: clear it to 0 first),
  // after the shadow maps when shadows are on. Throws atmos::Error, with
  // nothing drawn, on non-finite or singular matrices, an empty viewport,
  // a zero sun direction, invalid moons (validate_moons), or, with
  // shadows, a projection that is not a perspective one.
  void draw(const GlobeView& view);

  // Several views of one frame with one level of detail (the two eyes of a
  // stereo pair or a headset): the tiles are selected, streamed and their
  // shadow maps drawn once, for `lod_view`, whose frustum must hold every
  // view's (atmos::covering_eye, stereo.hpp) and whose height sets the
  // screen-space error (at least the views' pixels per unit of tangent);
  // then each of `views` is drawn with that one mesh, placed relative to
  // lod_view's position (the same morphs, so the same geometry, in every
  // view), after bind_target(i) has bound views[i]'s framebuffer (empty:
  // all into the bound one). The sun, the moons and the light are
  // lod_view's; views[i] gives only its view, projection and viewport.
  // last_stats() holds the one selection and the triangles of all views.
  // Throws atmos::Error as draw() for lod_view or any of the views.
  void draw_views(const GlobeView& lod_view, const std::vector<GlobeView>& views,
                  const std::function<void(std::size_t)>& bind_target);

  // Height of the drawn surface's relief above the datum, metres, below the
  // world position `position` (engine units): what a camera must stay above.
  double height_m(const glm::dvec3& position) const;
  // The mean albedo of the ground around the point below `position` (engine
  // units), linear RGB in [0, 1]: over the spherical cap centred there whose
  // radius is the distance to the horizon from `position` (at least 50 km,
  // at most the part of the planet visible from there), uniformly in area,
  // from 256 points of the surface's albedo at the cap's scale. Hand it to
  // AtmospherePass::set_ground_albedo, so that the air and the sky light
  // follow the ground below the camera (snow, desert, sea) rather than the
  // atmosphere's constant. Throws atmos::Error for a non-finite position.
  glm::dvec3 regional_albedo(const glm::dvec3& position) const;

  // The lowest and highest surface of the planet above the datum, metres.
  double min_height_m() const;
  double max_height_m() const;

  const GlobeStats& last_stats() const;

  // The shadow map of the last draw() to hand to AtmospherePass::render()
  // for its light shafts: the farthest cascade, which covers all the
  // shadows' reach (texture 0 when shadows are off or out of reach).
  GlobeShadowMap shadow_map_for_pass() const;

  struct Impl;

 private:
  std::unique_ptr<Impl> impl_;
};

// The lowest point of `surface` on a planet whose datum sphere has radius
// datum_radius_m, m above the datum: elevation data's minimum less the
// detail added below them, and the procedural relief's minimum over 40000
// directions less a tenth of its sampled range (the relief's exact minimum
// is not known; a bound that adds every term's worst case lies kilometres
// lower than any point). Opens the surface's elevation raster, if any
// (atmos::Error as Globe's constructor).
double lowest_surface_height_m(const PlanetSurface& surface, double datum_radius_m);

// The same atmosphere continued below its bottom (the datum) down to the
// lowest point of `surface`, for the AtmospherePass that lights and
// composites a globe whose ground goes below the datum (Mars's northern
// lowlands, Hellas, the Dead Sea shore): bottom_radius is lowered by that
// depth d and every density profile is continued downwards, so that the
// air above the datum is unchanged:
//  - exponential: rho(h) = exp(-h / H) becomes exp(-(h' - d) / H), the
//    same profile with its coefficients times exp(d / H) (h' = h + d, the
//    altitude above the new bottom);
//  - piecewise linear: the knots move up by d, and a profile that starts at
//    the datum keeps its lowest density below it.
// Returns `atmosphere` unchanged when the surface stays above the datum.
// The Globe keeps `atmosphere` (the datum); the pass takes this one.
Atmosphere extend_below_datum(const Atmosphere& atmosphere, const PlanetSurface& surface);

// An infinite perspective projection with reversed-Z depth (OpenGL with
// glClipControl(GL_LOWER_LEFT, GL_ZERO_TO_ONE)): the near plane at depth 1,
// infinity at 0 (depth = near / distance along the view axis). fov_y in
// radians, near in engine units.
glm::dmat4 reversed_z_projection(double fov_y_rad, double aspect, double near);

}  // namespace atmos
