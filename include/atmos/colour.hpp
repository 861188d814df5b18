// atmos — from radiance at the working wavelengths to colour.
//
// Radiance is spectral (W m^-2 sr^-1 nm^-1 at each working wavelength). For
// display and for `atmos sample` it is converted to CIE 1931 XYZ (2° observer)
// and then to linear sRGB, scaled so that Y is the luminance in cd/m².
#pragma once

#include <glm/mat3x3.hpp>
#include <glm/vec3.hpp>

#include <array>
#include <vector>

namespace atmos {

// Maximum luminous efficacy, lm/W (CIE).
inline constexpr double kMaxLuminousEfficacy = 683.0;

// CIE 1931 2° colour matching functions (x̄, ȳ, z̄) at a wavelength in nm:
// the CIE's 1 nm table (data/spectra/cie1931_2deg.csv, CIE 015:2004, with its
// source), linearly interpolated; zero outside 360–830 nm.
glm::dvec3 cie_1931_color_matching(double wavelength_nm);

// Per-wavelength weights w_i such that linear sRGB on the cd/m² scale is
// Σ_i w_i L(λ_i) for a spectrum sampled at `wavelengths_nm` (distinct, any
// order; a repeated wavelength gets weight 0 after its first occurrence).
// The spectrum between the samples is reconstructed piecewise linearly
// (constant beyond the outer samples), integrated over 360–830 nm against the
// matching functions times 683 lm/W, and converted with the sRGB
// (IEC 61966-2-1) matrix. The conversion of a spectrum, not of three
// arbitrary samples of it (Elek & Kmoch 2010, §4.4).
std::vector<glm::dvec3> spectral_to_srgb_weights(const std::vector<double>& wavelengths_nm);

// The same for three wavelengths, as a matrix: linear sRGB = M * radiance.
glm::mat3 radiance_to_srgb_matrix(const std::array<double, 3>& wavelengths_nm);

// CIE 1931 XYZ (Y in cd/m²) from linear sRGB on the cd/m² scale.
glm::dvec3 srgb_to_xyz(const glm::dvec3& rgb);

// Luminance (cd/m²) of a linear sRGB colour on the cd/m² scale (Collienne 2013, eq. 4.27).
inline double srgb_luminance(const glm::dvec3& rgb) { return 0.2126 * rgb.x + 0.7152 * rgb.y + 0.0722 * rgb.z; }

}  // namespace atmos
