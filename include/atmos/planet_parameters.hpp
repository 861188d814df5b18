// atmos — one description of the planet's adjustable parameters: name,
// unit, valid range, default and the range a user interface offers. The
// planet-file parser checks its values against it, atmos view builds its
// sliders from it (label, unit, range) and checks what is typed in, and the
// CLI's --wavelengths and --density-scale take their ranges and help from
// it; docs/planet-format.md lists it.
#pragma once

#include <string>
#include <vector>

namespace atmos {

struct PlanetParameter {
  const char* name;   // the planet file's key ("bottom_radius", "constituents[].density.scale_height"), or
                      // an edit of the planet ("density_scale", "constituents[].scattering_scale")
  const char* label;  // for a user interface ("ground radius")
  const char* unit;   // the unit values are shown and typed in ("km", "deg", "1": dimensionless)
  double si_per_unit;  // SI value of one `unit` (km: 1000; 1 for counts and ratios)
  // The valid values, in `unit`: min < v < max, or <= where inclusive;
  // infinite bounds for none.
  double min, max;
  bool min_inclusive, max_inclusive;
  double default_value;  // in `unit`: the earth preset's (or the identity of an edit)
  // The range a slider offers, in `unit`, and whether it moves logarithmically.
  double slider_min, slider_max;
  bool logarithmic;
  const char* meaning;
};

// Every parameter, in the order of docs/planet-format.md's table.
const std::vector<PlanetParameter>& planet_parameters();
// The parameter called `name`; atmos::Error for an unknown name.
const PlanetParameter& planet_parameter(const std::string& name);

// "in [1, 1e+06] km", "positive", "in (-0.999, 0.999)": the valid range as
// messages and help texts state it.
std::string valid_range_text(const PlanetParameter& parameter);
// Throws atmos::Error("<what> must be <valid_range_text>, got <v> <unit>")
// unless `value_si` (SI units) is a valid value of the parameter `name`;
// `what` names it for the message (a file's key path, a slider's label).
void check_planet_parameter(const std::string& name, double value_si, const std::string& what);

}  // namespace atmos
