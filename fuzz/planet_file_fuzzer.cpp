// libFuzzer target: atmos::parse_atmosphere on arbitrary bytes.
//
// A planet file either parses into an Atmosphere that validate() accepts and
// whose every number is finite, or is refused with an atmos::Error whose
// message is one line naming the file. Anything else (another exception
// type, a crash, a sanitizer report, a hang) is a finding: this target aborts
// with the reason, and libFuzzer saves the input.
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <string>
#include <typeinfo>

#include "atmos/planet_file.hpp"

namespace {

const char* const kOrigin = "fuzz.json";

[[noreturn]] void finding(const std::string& what) {
  std::fprintf(stderr, "planet_file_fuzzer: %s\n", what.c_str());
  std::abort();
}

void check_finite(double x, const char* what) {
  if (!std::isfinite(x)) finding(std::string("a parsed planet holds a non-finite ") + what);
}

void check_spectrum(const atmos::Spectrum& s, const char* what) {
  for (double w : s.wavelengths_nm()) check_finite(w, what);
  for (double v : s.values()) check_finite(v, what);
  if (s.wavelengths_nm().size() != s.values().size()) finding(std::string(what) + ": wavelengths and values differ in count");
}

// What a successful parse promises: validate() passes and every number is finite.
void check_parsed(const atmos::Atmosphere& a) {
  try {
    a.validate();
  } catch (const atmos::Error& e) {
    finding(std::string("parse_atmosphere returned a planet that validate() refuses: ") + e.what());
  }
  for (double w : a.wavelengths_nm) check_finite(w, "working wavelength");
  check_finite(a.bottom_radius_m, "bottom_radius");
  check_finite(a.top_radius_m, "top_radius");
  check_finite(a.sun_angular_radius_rad, "sun_angular_radius");
  check_spectrum(a.solar_irradiance, "solar_irradiance");
  check_spectrum(a.ground_albedo, "ground_albedo");
  for (const atmos::Constituent& c : a.constituents) {
    check_spectrum(c.scattering, "scattering");
    check_spectrum(c.absorption, "absorption");
    check_spectrum(c.phase.g, "phase g");
    check_spectrum(c.phase.g_back, "phase g_back");
    check_spectrum(c.phase.forward_weight, "phase forward_weight");
    check_finite(c.density.scale_height_m, "scale_height");
    for (const auto& [altitude, density] : c.density.knots) {
      check_finite(altitude, "density altitude");
      check_finite(density, "density");
    }
    // The working wavelengths are where the precomputation samples the spectra.
    for (double w : a.wavelengths_nm) {
      check_finite(c.scattering.at(w), "scattering at a working wavelength");
      check_finite(c.absorption.at(w), "absorption at a working wavelength");
    }
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  atmos::Atmosphere atmosphere;
  try {
    atmosphere = atmos::parse_atmosphere(text, kOrigin);
  } catch (const atmos::Error& e) {
    const std::string message = e.what();
    if (message.find('\n') != std::string::npos) finding("an error message of several lines: " + message);
    if (message.rfind(std::string(kOrigin) + ": ", 0) != 0) finding("an error message that does not name the file: " + message);
    return 0;
  } catch (const std::exception& e) {
    finding(std::string("an exception that is not an atmos::Error (") + typeid(e).name() + "): " + e.what());
  } catch (...) {
    finding("an exception that is not a std::exception");
  }
  check_parsed(atmosphere);
  return 0;
}
