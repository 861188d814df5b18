#include "atmos/sky.hpp"

#include <cmath>

#include "atmos/colour.hpp"
#include "physics/moons.hpp"
#include "physics/parameters.hpp"
#include "physics/radiance_to_camera_cpp.hpp"
#include "runtime/table_samplers.hpp"

namespace atmos {

struct SkyModel::Impl {
  physics::AtmosphereParams params;
  std::unique_ptr<physics::SpectralSets> spectral;
  runtime::TableSamplers samplers;
  glm::dmat3 to_srgb;
};

SkyModel::SkyModel(const Atmosphere& atmosphere, const Tables& tables) : impl_(std::make_unique<Impl>()) {
  check_tables_match(atmosphere, tables);
  impl_->params = physics::make_render_params(atmosphere, tables.sizes);
  impl_->spectral = physics::make_spectral_sets(atmosphere, tables.sizes);
  impl_->samplers = runtime::make_samplers(tables);
  impl_->to_srgb = glm::dmat3(physics::channels_to_srgb_matrix(tables.wavelengths_nm));
}

SkyModel::~SkyModel() = default;

glm::dvec3 SkyModel::radiance(const glm::dvec3& observer, const glm::dvec3& view, const glm::dvec3& sun,
                              bool include_sun_disc, const std::vector<Moon>& moons) const {
  const auto& s = impl_->samplers;
  // Each ray integrates its own low-sun single scattering (exact, not
  // interpolated from a sky-view table: this is the form the reference
  // tests measure).
  const physics::sampler2D no_sky_view{};
  const physics::SkyViewFrame no_frame{};
  const physics::Moons physics_moons = physics::make_moons(impl_->params, moons);
  return glm::dvec3(physics::radiance_along_view_ray(
      impl_->params, *impl_->spectral, s.spectral_optical_depth, s.scattering, s.single_aerosol,
      s.multiple_scattering, s.indirect_irradiance, no_sky_view, no_sky_view, no_sky_view, false, no_frame,
      glm::vec3(observer), glm::vec3(view), glm::vec3(sun), include_sun_disc, physics::StarField{false, 0.0f},
      physics_moons, physics::moons_may_eclipse(impl_->params, physics_moons, glm::vec3(sun))));
}

void SkyModel::horizontal_irradiance(const glm::dvec3& point, const glm::dvec3& sun, glm::dvec3& sun_irradiance,
                                     glm::dvec3& sky_irradiance) const {
  const auto& s = impl_->samplers;
  glm::vec3 sky;
  const glm::vec3 p(point);
  sun_irradiance = glm::dvec3(physics::sun_and_sky_irradiance(impl_->params, *impl_->spectral, s.spectral_optical_depth,
                                                              s.indirect_irradiance,
                                                              p, glm::normalize(p), glm::vec3(sun), sky));
  sky_irradiance = glm::dvec3(sky);
}

glm::dvec3 SkyModel::to_srgb(const glm::dvec3& spectral) const { return impl_->to_srgb * spectral; }

glm::dvec3 observer_position(const Atmosphere& atmosphere, double altitude_m) {
  return {0.0, 0.0, atmosphere.bottom_radius_m + altitude_m};
}

glm::dvec3 direction_from_azimuth_elevation(double azimuth_deg, double elevation_deg) {
  const double az = azimuth_deg * M_PI / 180.0, el = elevation_deg * M_PI / 180.0;
  return {std::cos(el) * std::sin(az), std::cos(el) * std::cos(az), std::sin(el)};
}

}  // namespace atmos
