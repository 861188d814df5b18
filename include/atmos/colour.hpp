// atmos — from radiance at the working wavelengths to colour.
//
// Radiance is spectral (W m^-2 sr^-1 nm^-1 at each working wavelength). For
// display and for `atmos sample` it is converted to CIE 1931 XYZ (2° observer)
// and then to linear sRGB, scaled so that Y is the luminance in cd/m².
#pragma once

#include <glm/mat3x3.hpp>
#include <glm/vec3.hpp>

#include <array>

namespace atmos {

// Maximum luminous efficacy, lm/W (CIE).
inline constexpr double kMaxLuminousEfficacy = 683.0;

// CIE 1931 2° colour matching functions (x̄, ȳ, z̄) at a wavelength in nm, from
// the multi-lobe Gaussian fit of Wyman, Sloan & Shirley 2013 ("Simple Analytic
// Approximations to the CIE XYZ Color Matching Functions", JCGT 2(2)), which
// follows the tabulated functions to within about 1 % of their peak.
glm::dvec3 cie_1931_color_matching(double wavelength_nm);

// The matrix M such that linear sRGB (cd/m² luminance scale) = M * radiance,
// for radiance sampled at three wavelengths. The spectrum between the samples
// is reconstructed piecewise linearly (constant beyond the outer samples,
// over 360–830 nm), integrated against the matching functions times 683 lm/W,
// and converted with the sRGB (IEC 61966-2-1) matrix.
glm::mat3 radiance_to_srgb_matrix(const std::array<double, 3>& wavelengths_nm);

// Luminance (cd/m²) of a linear sRGB colour on the cd/m² scale (seed 000 eq. 4.27).
inline double srgb_luminance(const glm::dvec3& rgb) { return 0.2126 * rgb.x + 0.7152 * rgb.y + 0.0722 * rgb.z; }

}  // namespace atmos
