#include "atmos/colour.hpp"

#include <cmath>

namespace atmos {
namespace {

// Piecewise Gaussian lobe of Wyman et al. 2013: width `below` left of the
// centre and `above` right of it.
double lobe(double x, double centre, double below, double above) {
  const double s = (x < centre ? below : above);
  const double t = (x - centre) / s;
  return std::exp(-0.5 * t * t);
}

}  // namespace

glm::dvec3 cie_1931_color_matching(double l) {
  const double x = 1.056 * lobe(l, 599.8, 37.9, 31.0) + 0.362 * lobe(l, 442.0, 16.0, 26.7) -
                   0.065 * lobe(l, 501.1, 20.4, 26.2);
  const double y = 0.821 * lobe(l, 568.8, 46.9, 40.5) + 0.286 * lobe(l, 530.9, 16.3, 31.1);
  const double z = 1.217 * lobe(l, 437.0, 11.8, 36.0) + 0.681 * lobe(l, 459.0, 26.0, 13.8);
  return {x, y, z};
}

glm::mat3 radiance_to_srgb_matrix(const std::array<double, 3>& w) {
  // Sort the sample wavelengths, remembering which channel each came from.
  std::array<int, 3> order = {0, 1, 2};
  for (int i = 0; i < 3; ++i)
    for (int j = i + 1; j < 3; ++j)
      if (w[order[j]] < w[order[i]]) std::swap(order[i], order[j]);
  const double l0 = w[order[0]], l1 = w[order[1]], l2 = w[order[2]];

  // xyz_from[c] = XYZ of a spectrum that is the hat function of channel c.
  glm::dmat3 xyz_from(0.0);  // column c: XYZ per unit radiance in channel c
  for (double l = 360.0; l <= 830.0; l += 1.0) {
    std::array<double, 3> hat = {0.0, 0.0, 0.0};  // weights of the sorted samples at l
    if (l <= l0) {
      hat[0] = 1.0;
    } else if (l >= l2) {
      hat[2] = 1.0;
    } else if (l <= l1) {
      const double t = (l - l0) / (l1 - l0);
      hat[0] = 1.0 - t;
      hat[1] = t;
    } else {
      const double t = (l - l1) / (l2 - l1);
      hat[1] = 1.0 - t;
      hat[2] = t;
    }
    const double weight = (l == 360.0 || l == 830.0) ? 0.5 : 1.0;  // trapezoid, 1 nm steps
    const glm::dvec3 cmf = cie_1931_color_matching(l) * (kMaxLuminousEfficacy * weight);
    for (int k = 0; k < 3; ++k) xyz_from[order[k]] += cmf * hat[k];
  }
  // sRGB from XYZ (IEC 61966-2-1), column-major as glm stores it.
  const glm::dmat3 srgb_from_xyz(3.2406, -0.9689, 0.0557,   // column X
                                 -1.5372, 1.8758, -0.2040,  // column Y
                                 -0.4986, 0.0415, 1.0570);  // column Z
  return glm::mat3(srgb_from_xyz * xyz_from);
}

}  // namespace atmos
