#include "physics/parameters.hpp"

#include <cmath>

namespace atmos::physics {

double mu_s_min(const Atmosphere& atmosphere) {
  const double horizon_dip = std::acos(atmosphere.bottom_radius_m / atmosphere.top_radius_m);
  const double margin = 2.0 * M_PI / 180.0;
  return std::cos(M_PI / 2.0 + horizon_dip + margin);
}

AtmosphereParams make_atmosphere_params(const Atmosphere& atmosphere, const TableSizes& sizes, int set) {
  AtmosphereParams p{};
  const double* w = &atmosphere.wavelengths_nm.at(size_t(3 * set));
  auto spectrum = [&](const Spectrum& s) {
    return vec3(float(s.at(w[0])), float(s.at(w[1])), float(s.at(w[2])));
  };
  p.bottom_radius = float(atmosphere.bottom_radius_m);
  p.top_radius = float(atmosphere.top_radius_m);
  p.constituent_count = int(atmosphere.constituents.size());
  const PhaseFunction aerosol = atmosphere.aerosol_phase();
  p.aerosol_phase_kind =
      aerosol.kind == PhaseFunction::Kind::cornette_shanks ? PHASE_CORNETTE_SHANKS : PHASE_HENYEY_GREENSTEIN;
  p.aerosol_g = float(aerosol.g);
  for (int i = 0; i < p.constituent_count; ++i) {
    const Constituent& c = atmosphere.constituents[size_t(i)];
    DensityProfile& d = p.density[i];
    if (c.density.kind == atmos::DensityProfile::Kind::exponential) {
      d.scale_height = float(c.density.scale_height_m);
      d.knot_count = 0;
    } else {
      d.scale_height = 0.0f;
      d.knot_count = int(c.density.knots.size());
      for (int k = 0; k < d.knot_count; ++k) {
        d.knot_altitude[k] = float(c.density.knots[size_t(k)].first);
        d.knot_density[k] = float(c.density.knots[size_t(k)].second);
      }
    }
    p.scattering[i] = spectrum(c.scattering);
    p.absorption[i] = spectrum(c.absorption);
    p.is_aerosol[i] = c.phase.kind == PhaseFunction::Kind::rayleigh ? 0 : 1;
  }
  p.ground_albedo = spectrum(atmosphere.ground_albedo);
  p.solar_irradiance = spectrum(atmosphere.solar_irradiance);
  p.sun_angular_radius = float(atmosphere.sun_angular_radius_rad);
  p.mu_s_min = float(mu_s_min(atmosphere));
  p.transmittance_mu_size = sizes.transmittance_mu;
  p.transmittance_r_size = sizes.transmittance_r;
  p.irradiance_mu_s_size = sizes.irradiance_mu_s;
  p.irradiance_r_size = sizes.irradiance_r;
  p.scattering_nu_size = sizes.scattering_nu;
  p.scattering_mu_s_size = sizes.scattering_mu_s;
  p.scattering_mu_size = sizes.scattering_mu;
  p.scattering_r_size = sizes.scattering_r;
  return p;
}

}  // namespace atmos::physics
