// From an atmos::Atmosphere (spectra, SI units) to the AtmosphereParams of the
// shared functions, for one triple of working wavelengths.
#pragma once

#include "atmos/atmosphere.hpp"
#include "atmos/tables.hpp"
#include "physics/shader_cpp.hpp"

namespace atmos::physics {

// Lowest sun zenith cosine stored in the scattering tables: the sun is below
// the horizon of every point of the atmosphere (the horizon dip seen from the
// top, acos(R_bottom / R_top)) plus a margin of 2° for the light scattered by
// the last lit layers.
double mu_s_min(const Atmosphere& atmosphere);

// The parameters of wavelength triple `set` (wavelengths 3 set .. 3 set + 2).
AtmosphereParams make_atmosphere_params(const Atmosphere& atmosphere, const TableSizes& sizes, int set);

}  // namespace atmos::physics
