#include "atmos/table_sizes.hpp"

#include <string>

#include "atmos/atmosphere.hpp"

namespace atmos {

void TableSizes::validate() const {
  auto check = [](int value, int minimum, const char* name) {
    if (value < minimum || value > 4096)
      throw Error(std::string("table size ") + name + " = " + std::to_string(value) + " is outside [" +
                  std::to_string(minimum) + ", 4096]");
  };
  check(transmittance_mu, 4, "transmittance_mu");
  check(transmittance_r, 4, "transmittance_r");
  check(irradiance_mu_s, 4, "irradiance_mu_s");
  check(irradiance_r, 2, "irradiance_r");
  check(scattering_nu, 2, "scattering_nu");
  check(scattering_mu_s, 4, "scattering_mu_s");
  check(scattering_mu, 8, "scattering_mu");
  check(scattering_r, 2, "scattering_r");
  if (scattering_mu % 2 != 0) throw Error("table size scattering_mu must be even (half below, half above the horizon)");
  const double texels = double(scattering_nu) * scattering_mu_s * scattering_mu * scattering_r;
  if (texels > 64.0 * 1024 * 1024) throw Error("scattering tables of more than 64 Mi texels are not supported");
}

}  // namespace atmos
