// atmos — the sea on the globe: the water surface at the planet's sea level,
// lit per pixel by the atmosphere's own functions (AtmospherePass's GLSL
// library) and the water's physics (physics/water.glsl, docs/water.md).
//
// The surface is the sea-level sphere, intersected exactly by each pixel's
// view ray in the fragment shader (in camera-relative float arithmetic from
// double-precision inputs, so that it does not jitter at 2 m nor at 100
// planet radii); near the camera, where the waves span 8 pixels or more,
// the ray meets the waves' displaced height field instead (docs/water.md,
// "Displaced waves"). It is drawn after the terrain (Globe::draw) into the same
// colour and reversed-Z depth attachments, and the depth test keeps the
// land in front of it; the terrain draws its sea flat at sea level, just
// behind the water. The colour written is the lit radiance / nits_per_unit
// and the depth is the surface's (the sphere's where a trough lies beyond
// it), so AtmospherePass::render() (lit_colour,
// reversed_z) adds the aerial perspective in front of it as for the
// terrain.
//
// The radiance at a point (docs/water.md, "The sea on the globe"): the sun
// glint (Cox & Munk 1954 slopes, microfacet BRDF) times the sun's light
// transmitted to the point (and the same for the light of the view's
// moons, GlobeView::moons, Lambertian spheres lit by the sun), the reflected sky (the rough surface's
// reflectance times one sky lookup from the point in the mean reflected
// direction, or the 16-node slope quadrature's 16), and the light leaving
// the water (Lee et al. 1999's column over the seabed at the point's depth,
// read from a cube map of the ground's height baked at construction). The
// atmosphere's light at sea level (the sky's radiance, the sun's and the
// sky's irradiance) and the rough surface's reflectance of the sky are read
// from maps filled at construction from the pass's functions and the
// water's (docs/water.md, "The fast path"), one filtered fetch each per
// pixel; they are filled again when the pass's ground albedo changes. The
// slopes are split between resolved waves — a sum of sine waves from a
// Pierson & Moskowitz 1964 spectrum that tilt the normal — and the
// unresolved rest, whose variance widens the BRDF, in proportions set by
// each wave's size on the screen (Bruneton, Neyret & Holzschuch 2010): the
// total slope variance is Cox & Munk's at every distance, so the mean
// radiance does not change where waves fade into the BRDF. The waves of 16
// pixels or more per wavelength also displace the surface.
//
// Threading and GL state: as Globe (globe.hpp). draw() changes the bound
// program and vertex array, texture units first_unit..first_unit+9, the
// viewport, the clip control (GL_LOWER_LEFT, GL_ZERO_TO_ONE), the depth function
// (GL_GREATER), test (enabled) and mask (GL_TRUE), enables
// GL_TEXTURE_CUBE_MAP_SEAMLESS, and disables blending and face culling;
// filling the maps (at construction, and in draw() after a change of the
// pass's ground albedo) also disables the scissor test and restores the
// draw framebuffer binding and the viewport.
#pragma once

#include <glm/mat3x3.hpp>
#include <glm/vec3.hpp>

#include <memory>

#include "atmos/atmosphere.hpp"
#include "atmos/globe.hpp"
#include "atmos/planet_file.hpp"
#include "atmos/plugin.hpp"
#include "atmos/water.hpp"

namespace atmos {

struct OceanSettings {
  // The water and the wind over it (atmos/water.hpp; validated as
  // water_optics does).
  Water water;
  // The azimuth the wind blows towards, degrees clockwise from north, at
  // the waves' anchor point (the sea below the camera; it moves with the
  // camera by steps, see docs/water.md).
  double wind_azimuth_deg = 90.0;
  // The seabed's albedo, linear RGB in [0, 1] (sand by default).
  glm::dvec3 seabed_albedo{0.45, 0.38, 0.26};
  // The sea's depth is read from a cube map of the ground's height of
  // bathymetry_texels x bathymetry_texels per face (16..2048; 256: 39 km
  // texels on Earth), baked once at construction (on Earth's procedural
  // relief about 4 s per million texels on two cores: 256 takes 1.5-2 s).
  int bathymetry_texels = 256;
  // The reflected sky: false, one sky lookup in the slope quadrature's
  // mean reflected direction times the rough surface's reflectance (from
  // its map); true, the 16-node quadrature itself, with 16 lookups of the
  // sky's map per pixel.
  bool sky_quadrature = false;
  // The texture units of the atmosphere's GLSL library: first_unit..first_unit+4,
  // first_unit+5 the bathymetry, first_unit+6..first_unit+9 the sea's maps
  // of the sky, the irradiances, the reflectance and the light from below.
  int first_unit = 0;
};

// How many of the catalogue's stars the water mirrors (Ocean::set_stars).
inline constexpr int kOceanMirroredStars = 16;

class Ocean {
 public:
  // The sea of `surface` (its sea level above `atmosphere`'s bottom radius,
  // the globe's datum; none: the style's, Earth's 0) and its lakes (its
  // lake mask and level: water at that level over the ground below it,
  // where the mask says so, sampled on the bathymetry's texels) lit through
  // `pass`, which must outlive the ocean. A surface without a sea (a style
  // other than Earth without a sea level) nor lakes makes an ocean that
  // draws nothing. Throws atmos::Error on settings outside their ranges
  // (one line naming the field), a sea or lake level outside the atmosphere
  // (below the planet's centre or above its top), a lake level not above
  // the sea level, lakes without a mask or a level, rasters that cannot be
  // read (as Globe; the lake mask's message names its file), or without a
  // current OpenGL 4.5 context.
  Ocean(const Atmosphere& atmosphere, const PlanetSurface& surface, const AtmospherePass& pass,
        const OceanSettings& settings = {});
  ~Ocean();
  Ocean(const Ocean&) = delete;
  Ocean& operator=(const Ocean&) = delete;

  // Draws the sea into the bound framebuffer (colour attachment 0 and the
  // reversed-Z depth the globe drew), at `time_s` seconds of the waves'
  // clock. Throws atmos::Error, with nothing drawn, on the view's invalid
  // input (as Globe::draw) or a non-finite time.
  void draw(const GlobeView& view, double time_s = 0.0);

  bool has_sea() const;
  // The sea level above the datum, m (NaN without a sea).
  double sea_level_m() const;
  // Whether the surface has lakes (PlanetSurface::lake_mask), and their
  // level above the datum, m (NaN without lakes).
  bool has_lakes() const;
  double lake_level_m() const;

  // The stars whose light the water mirrors, through the glint's BRDF as
  // the sun's (each a point of its irradiance above the atmosphere,
  // attenuated towards it): the kOceanMirroredStars brightest (in the
  // tables' middle channel) of the pass's star catalogue
  // (AtmospherePass::set_star_catalogue) as it is at this call, turned into
  // the world's axes by `world_from_star_catalogue` (as
  // FrameInput::world_from_star_catalogue; call again when it changes).
  // Off (the default), or an empty catalogue: none. Throws atmos::Error,
  // changing nothing, unless `world_from_star_catalogue` is a rotation.
  void set_stars(bool on, const glm::dmat3& world_from_star_catalogue = glm::dmat3(1.0));
  // The depth of the sea below the point of the sea level in `direction`
  // (planet axes, any length), m: the sea level less the ground's height
  // there (0 over land). The shader reads the same heights from the
  // bathymetry's texels, bilinearly.
  double depth_m(const glm::dvec3& direction) const;

  struct Impl;

 private:
  std::unique_ptr<Impl> impl_;
};

}  // namespace atmos
