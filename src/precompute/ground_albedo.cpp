// Tables over any ground albedo from the tables over two (GroundAlbedoResponse).
#include "precompute/ground_albedo.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <glm/common.hpp>

#include <algorithm>
#include <cmath>
#include <string>

namespace atmos {
namespace {

// The albedo term of the series of ground reflections, k(a) = a / (1 - a S):
// an albedo-dependent quantity is L(a) = L(0) + G k(a).
glm::dvec3 reflection_series(const glm::dvec3& albedo, const glm::dvec3& spherical_albedo) {
  return albedo / (glm::dvec3(1.0) - albedo * spherical_albedo);
}

}  // namespace

namespace precompute {

glm::vec3 spherical_albedo_from_below(const TableSizes& sizes, const TableSet& planet, const TableSet& response,
                                      const glm::vec3& planet_albedo, const glm::vec3& response_albedo) {
  glm::dvec3 e_p(0.0), e_b(0.0);
  // Row 0 of the irradiance tables: r at the bottom of the atmosphere.
  for (int x = 0; x < sizes.irradiance_mu_s; ++x) {
    const size_t i = size_t(x);
    e_p += glm::dvec3(planet.direct_irradiance[i]) + glm::dvec3(planet.indirect_irradiance[i]);
    e_b += glm::dvec3(response.direct_irradiance[i]) + glm::dvec3(response.indirect_irradiance[i]);
  }
  const glm::dvec3 a_p(planet_albedo), a_b(response_albedo);
  glm::vec3 s(0.0f);
  for (int c = 0; c < 3; ++c) {
    const double value = (e_b[c] - e_p[c]) / (a_b[c] * e_b[c] - a_p[c] * e_p[c]);
    s[c] = std::isfinite(value) ? float(std::clamp(value, 0.0, 0.999)) : 0.0f;
  }
  return s;
}

}  // namespace precompute

TableSet tables_for_ground_albedo(const Tables& tables, const glm::vec3& albedo) {
  const GroundAlbedoResponse& g = tables.ground_response;
  if (g.empty())
    throw Error("the tables have no ground albedo response (precompute them with "
                "PrecomputeOptions::ground_albedo_response)");
  for (int c = 0; c < 3; ++c)
    if (!(albedo[c] >= 0.0f && albedo[c] <= 1.0f))
      throw Error("ground albedo must be in [0, 1] in every channel, got " + std::to_string(albedo[c]));
  // L(a) = L(a_p) + G (k(a) - k(a_p)), G = (L(a_b) - L(a_p)) / (k(a_b) - k(a_p)):
  // a weight w per channel between the two sets.
  const glm::dvec3 s(g.spherical_albedo);
  const glm::dvec3 k_p = reflection_series(glm::dvec3(g.planet_albedo), s);
  const glm::vec3 w((reflection_series(glm::dvec3(albedo), s) - k_p) /
                    (reflection_series(glm::dvec3(g.albedo), s) - k_p));
  TableSet out = tables.set;
  const auto blend = [&](std::vector<glm::vec3>& texels, const std::vector<glm::vec3>& response) {
    tbb::parallel_for(tbb::blocked_range<size_t>(0, texels.size(), 4096), [&](const tbb::blocked_range<size_t>& r) {
      for (size_t i = r.begin(); i != r.end(); ++i)
        texels[i] = glm::max(texels[i] + w * (response[i] - texels[i]), glm::vec3(0.0f));
    });
  };
  blend(out.indirect_irradiance, g.indirect_irradiance);
  blend(out.scattering, g.scattering);
  blend(out.multiple_scattering, g.multiple_scattering);
  return out;
}

}  // namespace atmos
