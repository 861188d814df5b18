// atmos — the description of a planet's atmosphere.
//
// This is the only input of the physics: the precomputed tables, the GPU
// renderer and the brute-force reference all start from an `Atmosphere`.
// All quantities are SI: metres, radians, m^-1, W m^-2 nm^-1.
#pragma once

#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace atmos {

// Every failure the library reports to a caller: bad planet files, impossible
// parameters, unreadable caches, missing OpenGL. The message is one line that
// names the offending input.
class Error : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// A quantity sampled over wavelength and linearly interpolated between its
// samples (constant beyond the first and last). Coefficients given as a power
// law are sampled densely enough at load time for the interpolation to be
// exact to well below 0.1 %.
class Spectrum {
 public:
  Spectrum() = default;
  Spectrum(std::vector<double> wavelengths_nm, std::vector<double> values);
  static Spectrum constant(double value);
  Spectrum scaled(double factor) const;
  // ∫ from a to b of the piecewise-linear spectrum (constant beyond its ends).
  double integral(double from_nm, double to_nm) const;

  double at(double wavelength_nm) const;
  bool empty() const { return values_.empty(); }
  const std::vector<double>& wavelengths_nm() const { return wavelengths_nm_; }
  const std::vector<double>& values() const { return values_; }
  // Same samples (a constant 0.7 and {400 nm: 0.7, 700 nm: 0.7} differ).
  bool operator==(const Spectrum&) const = default;

 private:
  std::vector<double> wavelengths_nm_;
  std::vector<double> values_;
};

// Number density of a constituent relative to its reference density (where
// the coefficients of `Constituent` are given), as a function of altitude.
struct DensityProfile {
  enum class Kind { exponential, piecewise_linear };
  Kind kind = Kind::exponential;
  double scale_height_m = 8000.0;                  // exponential: exp(-h / H)
  std::vector<std::pair<double, double>> knots;    // piecewise linear: (altitude m, density), zero outside

  double at(double altitude_m) const;
};

// Phase function of a constituent's scattering. Every parameter is a
// spectrum: the phase may change with wavelength (dust scatters blue light
// into a narrower forward lobe than red, which makes the Martian blue
// aureole). A constant is Spectrum::constant.
//  - rayleigh: 3/(16π)(1 + ν²), Collienne 2013, eq. 3.2 (no parameters).
//  - henyey_greenstein: HG(g) = (1 - g²) / (4π (1 + g² - 2gν)^{3/2}).
//  - cornette_shanks: Collienne 2013, eq. 3.5 (Cornette & Shanks 1992).
//  - double_henyey_greenstein: w HG(g) + (1 - w) HG(g_back) (Kattawar 1975),
//    w = forward_weight; a forward lobe (g > 0) and a backward one (g_back < 0).
struct PhaseFunction {
  enum class Kind { rayleigh, henyey_greenstein, cornette_shanks, double_henyey_greenstein };
  Kind kind = Kind::rayleigh;
  Spectrum g;               // asymmetry parameter (of the forward lobe for DHG), |g| < 0.999; empty for rayleigh
  Spectrum g_back;          // DHG only: asymmetry parameter of the second lobe, |g_back| < 0.999
  Spectrum forward_weight;  // DHG only: weight w of the first lobe, in [0, 1]

  PhaseFunction() = default;
  // `g` constant over wavelength (ignored for rayleigh).
  PhaseFunction(Kind kind, double g);
  PhaseFunction(Kind kind, Spectrum g, Spectrum g_back = {}, Spectrum forward_weight = {});

  bool operator==(const PhaseFunction&) const = default;
};

// One scattering and/or absorbing species (air molecules, an aerosol, ozone).
struct Constituent {
  std::string name;
  DensityProfile density;
  Spectrum scattering;   // m^-1 at reference density
  Spectrum absorption;   // m^-1 at reference density
  PhaseFunction phase;
};

struct Atmosphere {
  std::string name;
  std::string origin;                     // preset name or file path, for messages
  std::vector<double> wavelengths_nm;     // working wavelengths of the precomputation
  double bottom_radius_m = 0.0;           // planet surface
  double top_radius_m = 0.0;              // top of the atmosphere
  std::vector<Constituent> constituents;
  Spectrum ground_albedo;                 // Lambertian, dimensionless
  Spectrum solar_irradiance;              // W m^-2 nm^-1 at the top of the atmosphere, normal incidence
  double sun_angular_radius_rad = 0.0;

  // Throws Error naming the first impossible parameter (inverted radii, NaN,
  // negative coefficients, |g| >= 0.999, a phase weight outside [0, 1], an
  // unsupported mixture of phase functions…).
  void validate() const;

  // The phase function shared by all non-Rayleigh constituents (the tables keep
  // one aerosol component so that its phase function can be applied per pixel).
  PhaseFunction aerosol_phase() const;
};

// Working wavelengths for `count` >= 3 (at most 48): 3 gives the fast
// three-wavelength mode (680, 550, 440 nm: tables hold radiance at those
// wavelengths); more give a spectral precomputation at `count` wavelengths
// evenly spaced over 360–830 nm, converted to colour through the CIE 1931
// observer (Elek & Kmoch 2010, §4.4).
std::vector<double> spectral_wavelengths(int count);

// Multiplies the number density of every constituent by `factor` (> 0): the
// same planet with a thinner or denser atmosphere (Elek & Kmoch 2010, Fig. 4).
void scale_density(Atmosphere& atmosphere, double factor);

// The extraterrestrial solar spectrum of ASTM E490-00a at 1 au
// (data/spectra/solar_irradiance.csv, 280.5–2500 nm), W m^-2 nm^-1, as its
// 10 nm running mean every 5 nm over 290–2490 nm (the working wavelengths
// sample it: the 1 nm table's Fraunhofer lines would be picked at random).
Spectrum solar_spectrum_table();

// Planck's law scaled to a total (all wavelengths) irradiance, W m^-2 nm^-1.
Spectrum blackbody_spectrum(double temperature_k, double total_irradiance_w_m2);

// Replaces the shape of the solar spectrum, keeping its irradiance over
// 360–830 nm: `spec` is "table" (ASTM E490) or "blackbody:T" (T in K).
void set_solar_spectrum(Atmosphere& atmosphere, const std::string& spec);

// Coefficients (m^-1 at the reference density) from physical inputs, sampled
// every 1 nm over 200-2000 nm. Each throws Error for inputs outside its range.
//  - Molecular (Rayleigh) scattering of a gas of refractive index n (at the
//    reference density, taken as non-dispersive), number density N (m^-3) and
//    King correction factor F in [1, 2) for depolarisation:
//    β(λ) = 8π³ (n² - 1)² F / (3 N λ⁴) (Elek & Kmoch 2010, eqs. 1-2).
Spectrum rayleigh_scattering_spectrum(double refractive_index, double number_density_m3, double king_factor = 1.0);
//  - An absorber or scatterer of cross section σ(λ) (m²) and number density
//    N (m^-3): β(λ) = N σ(λ).
Spectrum cross_section_spectrum(const Spectrum& cross_section_m2, double number_density_m3);
//  - An aerosol of optical depth τ(λ) = β_A (λ / 1 µm)^-α (Ångström 1929)
//    spread over an exponential layer of scale height H: β(λ) = τ(λ) / H at
//    the ground. α in [-1, 4], β_A >= 0.
Spectrum angstrom_aerosol_spectrum(double alpha, double beta, double scale_height_m);
//  - value · (λ / reference)^exponent (exponent -4: molecules).
Spectrum power_law_spectrum(double value, double reference_nm, double exponent);

}  // namespace atmos
