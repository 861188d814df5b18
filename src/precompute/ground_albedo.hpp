// The render tables' dependence on the ground albedo (GroundAlbedoResponse).
#pragma once

#include <glm/vec3.hpp>

#include "atmos/tables.hpp"

namespace atmos::precompute {

// The atmosphere's spherical albedo seen from below, S per channel, from the
// same tables over two Lambertian grounds of albedos a_p and a_b: the total
// irradiance of the ground (sun and sky) obeys E(a) = E(0) / (1 - a S)
// (every reflection sends a E up, of which the air returns S; Tanré et al.
// 1979), so E_p (1 - a_p S) = E_b (1 - a_b S) and
//   S = (E_b - E_p) / (a_b E_b - a_p E_p),
// with E the irradiance summed over the sun's zenith angles at the bottom of
// the atmosphere. Clamped to [0, 1) (a physical S; the discretised tables
// can stray by rounding where the ground sees little light).
glm::vec3 spherical_albedo_from_below(const TableSizes& sizes, const TableSet& planet, const TableSet& response,
                                      const glm::vec3& planet_albedo, const glm::vec3& response_albedo);

}  // namespace atmos::precompute
