// Read-only sampler views of the render tables, for evaluating the shared
// functions on the CPU (atmos sample, the CPU renderer, tests).
#pragma once

#include "atmos/tables.hpp"
#include "physics/shader_cpp.hpp"

namespace atmos::runtime {

struct TableSamplers {
  physics::sampler2D direct_irradiance;
  physics::sampler2D indirect_irradiance;
  physics::sampler3D scattering;
  physics::sampler3D single_aerosol;
  physics::sampler3D multiple_scattering;
  physics::sampler2D spectral_optical_depth;  // one tile per wavelength triple (the "transmittance texture" of the functions)
};

inline TableSamplers make_samplers(const Tables& tables) {
  const TableSizes& s = tables.sizes;
  const TableSet& t = tables.set;
  TableSamplers out;
  out.direct_irradiance = {s.irradiance_mu_s, s.irradiance_r, t.direct_irradiance.data()};
  out.indirect_irradiance = {s.irradiance_mu_s, s.irradiance_r, t.indirect_irradiance.data()};
  out.scattering = {tables.scattering_width(), tables.scattering_height(), tables.scattering_depth(),
                    t.scattering.data()};
  out.single_aerosol = {tables.scattering_width(), tables.scattering_height(), tables.scattering_depth(),
                        t.single_aerosol.data()};
  out.multiple_scattering = {tables.scattering_width(), tables.scattering_height(), tables.scattering_depth(),
                             t.multiple_scattering.data()};
  out.spectral_optical_depth = {s.transmittance_mu * tables.transmittance_tiles(), s.transmittance_r,
                                tables.spectral_optical_depth.data()};
  return out;
}

}  // namespace atmos::runtime
