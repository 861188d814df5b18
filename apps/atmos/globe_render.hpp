// atmos render --surface globe: the shots of `atmos render` drawn the way an
// engine draws a planet with atmos. The terrain globe (atmos::Globe) writes
// the planet's surface, lit by the atmosphere, into a colour and a
// reversed-Z depth texture; the engine plugin (atmos::AtmospherePass) adds
// the aerial perspective, the sky, the sun, the stars and the moons' eclipse.
// Every camera model of atmos::Camera: perspective cameras are drawn
// directly, fisheye and equirect ones through a cube map.
#pragma once

#include <glm/vec3.hpp>

#include <memory>
#include <vector>

#include "atmos/atmosphere.hpp"
#include "atmos/eclipse.hpp"
#include "atmos/image.hpp"
#include "atmos/planet_file.hpp"
#include "atmos/renderer.hpp"
#include "atmos/tables.hpp"

namespace atmos_cli {

class GlobeRenderer {
 public:
  // With an OpenGL 4.5 context current (atmos::Error otherwise, or on a
  // surface the globe cannot open). `surface`: atmos::load_surface of the
  // planet. With `tables` holding their ground albedo response the air is
  // lit by the globe's regional albedo around each camera, else by the
  // atmosphere's constant. Every tile a view
  // needs is generated before it is drawn
  // (GlobeSettings::complete_every_frame): stills have no next frame.
  // `atmosphere` is the planet's, at its datum; `tables` those of
  // atmos::extend_below_datum(atmosphere, surface), the air the pass draws
  // (continued down to the lowest ground).
  GlobeRenderer(const atmos::Atmosphere& atmosphere, const atmos::Tables& tables, const atmos::PlanetSurface& surface);
  ~GlobeRenderer();
  GlobeRenderer(const GlobeRenderer&) = delete;
  GlobeRenderer& operator=(const GlobeRenderer&) = delete;

  // `position` (planet-centred, m) raised along its vertical by the height
  // of the globe's surface below it: an altitude above the datum sphere
  // becomes the same altitude above the terrain (or the sea).
  glm::dvec3 above_terrain(const glm::dvec3& position) const;

  // The image of `camera` (at its position as given) in cd/m², linear sRGB,
  // rows top-down: what Renderer::render gives with set_stars(stars) and
  // set_moons(moons), with the globe for the ground.
  atmos::Image render(const atmos::Camera& camera, const glm::dvec3& sun_direction, bool stars,
                      const std::vector<atmos::Moon>& moons);

  // The stars of a catalogue instead of the procedural field, in the
  // planet's frame (AtmospherePass::set_star_catalogue); empty: procedural.
  void set_star_catalogue(const std::vector<atmos::Star>& stars);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace atmos_cli
