// The public water optics (include/atmos/water.hpp) from physics/water.hpp.
#include "atmos/water.hpp"

#include "physics/parameters.hpp"
#include "physics/water.hpp"

namespace atmos {

WaterOptics water_optics(const Water& water, const Atmosphere& atmosphere) {
  WaterOptics o;
  o.wavelengths_nm = physics::kRenderPhaseWavelengths;
  if (atmosphere.wavelengths_nm.size() == 3)
    o.wavelengths_nm = {atmosphere.wavelengths_nm[0], atmosphere.wavelengths_nm[1], atmosphere.wavelengths_nm[2]};
  const physics::WaterParams p = physics::make_water_params(water, o.wavelengths_nm);
  o.refractive_index = glm::dvec3(p.refractive_index);
  o.absorption_per_m = glm::dvec3(p.absorption);
  o.backscattering_per_m = glm::dvec3(p.backscattering);
  o.diffuse_reflectance = glm::dvec3(p.diffuse_reflectance);
  o.slope_variance = glm::dvec2(p.slope_variance);
  return o;
}

}  // namespace atmos
