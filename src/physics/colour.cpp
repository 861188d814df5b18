#include "atmos/colour.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <sstream>
#include <string>

#include "atmos/atmosphere.hpp"
#include "data/embedded_files.hpp"

namespace atmos {
namespace {

// sRGB from XYZ (IEC 61966-2-1), column-major as glm stores it.
const glm::dmat3 kSrgbFromXyz(3.2406, -0.9689, 0.0557,   // column X
                              -1.5372, 1.8758, -0.2040,  // column Y
                              -0.4986, 0.0415, 1.0570);  // column Z

// The 1 nm table, 360..830 nm, parsed once from the embedded CSV.
const std::vector<glm::dvec3>& cie_table() {
  static const std::vector<glm::dvec3> table = [] {
    const char* text = data::embedded_file("data/spectra/cie1931_2deg.csv");
    if (text == nullptr) throw Error("the CIE 1931 table is not embedded in this build");
    std::vector<glm::dvec3> rows;
    std::istringstream in(text);
    std::string line;
    double expected = 360.0;
    while (std::getline(in, line)) {
      if (line.empty() || line[0] == '#' || line[0] == 'w') continue;
      double l, x, y, z;
      if (std::sscanf(line.c_str(), "%lf,%lf,%lf,%lf", &l, &x, &y, &z) != 4 || l != expected)
        throw Error("the embedded CIE 1931 table is malformed near '" + line + "'");
      rows.emplace_back(x, y, z);
      expected += 1.0;
    }
    if (rows.size() != 471) throw Error("the embedded CIE 1931 table does not span 360-830 nm");
    return rows;
  }();
  return table;
}

}  // namespace

glm::dvec3 cie_1931_color_matching(double l) {
  const std::vector<glm::dvec3>& t = cie_table();
  if (!(l >= 360.0 && l <= 830.0)) return glm::dvec3(0.0);
  const double x = l - 360.0;
  const size_t i = std::min(size_t(x), t.size() - 2);
  const double f = x - double(i);
  return t[i] * (1.0 - f) + t[i + 1] * f;
}

std::vector<glm::dvec3> spectral_to_srgb_weights(const std::vector<double>& w) {
  // Distinct wavelengths in increasing order, remembering where each came from.
  std::vector<size_t> order(w.size());
  std::iota(order.begin(), order.end(), size_t(0));
  std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) { return w[a] < w[b]; });
  std::vector<size_t> distinct;
  for (size_t i : order)
    if (distinct.empty() || w[i] != w[distinct.back()]) distinct.push_back(i);

  std::vector<glm::dvec3> xyz(w.size(), glm::dvec3(0.0));
  const std::vector<glm::dvec3>& cmf = cie_table();
  for (int n = 0; n <= 470; ++n) {
    const double l = 360.0 + n;
    const double weight = (n == 0 || n == 470) ? 0.5 : 1.0;  // trapezoid, 1 nm steps
    const glm::dvec3 c = cmf[size_t(n)] * (kMaxLuminousEfficacy * weight);
    // The hat functions of the piecewise-linear reconstruction at l.
    if (l <= w[distinct.front()]) {
      xyz[distinct.front()] += c;
    } else if (l >= w[distinct.back()]) {
      xyz[distinct.back()] += c;
    } else {
      size_t k = 0;
      while (w[distinct[k + 1]] < l) ++k;
      const double t = (l - w[distinct[k]]) / (w[distinct[k + 1]] - w[distinct[k]]);
      xyz[distinct[k]] += c * (1.0 - t);
      xyz[distinct[k + 1]] += c * t;
    }
  }
  for (glm::dvec3& v : xyz) v = kSrgbFromXyz * v;
  return xyz;
}

glm::mat3 radiance_to_srgb_matrix(const std::array<double, 3>& w) {
  const std::vector<glm::dvec3> weights = spectral_to_srgb_weights({w[0], w[1], w[2]});
  return glm::mat3(glm::vec3(weights[0]), glm::vec3(weights[1]), glm::vec3(weights[2]));
}

glm::dvec3 srgb_to_xyz(const glm::dvec3& rgb) { return glm::inverse(kSrgbFromXyz) * rgb; }

}  // namespace atmos
