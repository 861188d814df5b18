// atmos — the texel counts of the precomputed tables. They are part of the
// tables' parameterisation (the mappings between r, mu, mu_s, nu and texture
// coordinates, src/physics), so they belong to the physics layer.
#pragma once

namespace atmos {

// Texel counts of the tables. The 4D scattering tables are stored as 3D
// textures of (nu * mu_s) x mu x r texels.
struct TableSizes {
  int transmittance_mu = 256;
  int transmittance_r = 64;
  int irradiance_mu_s = 64;
  int irradiance_r = 16;
  int scattering_nu = 8;
  int scattering_mu_s = 32;
  int scattering_mu = 128;  // even: half for rays that hit the ground, half for the others
  int scattering_r = 32;

  // Throws Error for sizes the parameterisation cannot use (too small, odd
  // scattering_mu, more than 64 Mi texels per table).
  void validate() const;
  bool operator==(const TableSizes&) const = default;
};

}  // namespace atmos
