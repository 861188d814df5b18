// The public water optics (include/atmos/water.hpp) from physics/water.hpp.
#include "atmos/water.hpp"

#include <memory>

#include "physics/parameters.hpp"
#include "physics/water.hpp"

namespace atmos {

namespace {

WaterOptics optics_of(const physics::WaterParams& p, const std::array<double, 3>& wavelengths_nm) {
  WaterOptics o;
  o.wavelengths_nm = wavelengths_nm;
  o.refractive_index = glm::dvec3(p.refractive_index);
  o.absorption_per_m = glm::dvec3(p.absorption);
  o.backscattering_per_m = glm::dvec3(p.backscattering);
  o.diffuse_reflectance = glm::dvec3(p.diffuse_reflectance);
  o.slope_variance = glm::dvec2(p.slope_variance);
  return o;
}

}  // namespace

WaterOptics water_optics(const Water& water, const Atmosphere& atmosphere) {
  const std::array<double, 3> wavelengths = physics::water_channel_wavelengths(atmosphere);
  return optics_of(physics::make_water_params(water, wavelengths), wavelengths);
}

WaterTriples water_triples(const Water& water, const Atmosphere& atmosphere) {
  const std::unique_ptr<physics::WaterSpectrum> s = physics::make_water_spectrum(water, atmosphere);
  WaterTriples t;
  for (int k = 0; k < s->count; ++k) {
    t.optics.push_back(optics_of(s->set[k], physics::set_wavelengths(atmosphere.wavelengths_nm, k)));
    t.solar_irradiance.emplace_back(s->solar_irradiance[k]);
    t.to_channels.emplace_back(s->to_channels[k]);
    t.from_channels.emplace_back(s->from_channels[k]);
  }
  return t;
}

}  // namespace atmos
