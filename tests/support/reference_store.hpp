// Stored results of the references (src/reference), for the accuracy tests.
//
// The Monte Carlo and plane-parallel references are deterministic: the same
// inputs and the same reference code give bit-identical results. Their
// results are stored in tests/data/reference/<test suite>.json, each under a
// key that hashes the call's inputs (every field of the atmosphere, the
// geometry, the options) together with the reference's source code (its
// tokens without comments, see cmake/hash_sources.cmake). These functions
// have the signatures of the reference's and behave according to
// ATMOS_REFERENCE_MODE:
//   stored (default)  return the stored result; a missing one fails the test
//                     with the command that regenerates the store;
//   verify            for the first call of each test suite and a fixed
//                     quarter of the others (verified_entry), compute, fail
//                     the test if the stored result differs in any bit and
//                     return the computed one; the rest as in stored mode
//                     (the full tier);
//   write             compute and store (scripts/update-references.sh);
//   fill              return the stored result, compute and store a missing one
//                     (to complete a store after an interrupted write).
// The keys: support/reference_key.hpp.
#pragma once

#include <glm/vec3.hpp>

#include <string>
#include <vector>

#include "atmos/atmosphere.hpp"
#include "reference/reference.hpp"

namespace atmos_test::oracle {

atmos::ReferenceResult reference_radiance(const atmos::Atmosphere& atmosphere, const glm::dvec3& observer,
                                          const glm::dvec3& view, const glm::dvec3& sun,
                                          const atmos::ReferenceOptions& options);

atmos::ReferenceResult reference_irradiance(const atmos::Atmosphere& atmosphere, const glm::dvec3& point,
                                            const glm::dvec3& normal, const glm::dvec3& sun,
                                            const atmos::ReferenceOptions& options);

atmos::ReferenceResult reference_horizontal_irradiance(const atmos::Atmosphere& atmosphere, const glm::dvec3& point,
                                                       const glm::dvec3& sun, const atmos::ReferenceOptions& options);

atmos::ReferenceResult reference_radiance_to_point(const atmos::Atmosphere& atmosphere, const glm::dvec3& observer,
                                                   const glm::dvec3& point, const glm::dvec3& sun,
                                                   const atmos::ReferenceOptions& options);

std::vector<double> reference_transmittance(const atmos::Atmosphere& atmosphere, const glm::dvec3& from,
                                            const glm::dvec3& to);

atmos::PlaneParallelFluxes reference_plane_parallel_fluxes(const atmos::Atmosphere& atmosphere, double mu_s,
                                                           const atmos::PlaneParallelOptions& options = {});

}  // namespace atmos_test::oracle
