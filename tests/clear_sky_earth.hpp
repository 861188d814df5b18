// The Earth of the accuracy tests' calibrated bounds: the `earth` preset with
// the thin aerosol of Bruneton & Neyret 2008 instead of the OPAC continental
// one: scattering 4e-6 m^-1 at the ground,
// single-scattering albedo 0.9, scale height 1.2 km, Cornette-Shanks g 0.8,
// optical depth 0.005 against 0.151. The slow suites measure both: the
// algorithms' accuracy on a clear sky, where their bounds were set, and the
// preset's haze, where the tables' known shortfalls are bounded separately.
#pragma once

#include <stdexcept>

#include "atmos/atmosphere.hpp"
#include "atmos/planet_file.hpp"

inline atmos::Atmosphere clear_sky_earth() {
  atmos::Atmosphere atmosphere = atmos::load_atmosphere("earth");
  atmos::Constituent& aerosol = atmosphere.constituents.at(1);
  if (aerosol.name != "aerosol") throw std::logic_error("earth.json: the second constituent is not the aerosol");
  aerosol.density.scale_height_m = 1200.0;
  aerosol.scattering = atmos::Spectrum::constant(4.0e-6);
  aerosol.absorption = atmos::Spectrum::constant(4.44e-7);
  aerosol.phase = atmos::PhaseFunction{atmos::PhaseFunction::Kind::cornette_shanks, 0.8};
  atmosphere.validate();
  return atmosphere;
}
