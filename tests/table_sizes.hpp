// Table sizes shared by the GPU tests: small enough to precompute in about
// a second, large enough for the renderers' code paths (both halves of the
// mu axis, several nu tiles, twilight rows of mu_s).
#pragma once

#include "atmos/tables.hpp"

namespace atmos_test {

inline atmos::TableSizes small_gpu_sizes() {
  atmos::TableSizes s;
  s.transmittance_mu = 64;
  s.transmittance_r = 16;
  s.irradiance_mu_s = 32;
  s.irradiance_r = 8;
  s.scattering_nu = 4;
  s.scattering_mu_s = 16;
  s.scattering_mu = 32;
  s.scattering_r = 8;
  return s;
}

}  // namespace atmos_test
