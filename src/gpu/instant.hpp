// The instant approximate mode's GL-free part (AtmospherePass from
// InstantTables; physics/instant_atmosphere.glsl): the frame's settings of
// the mode, and the CPU twins of its per-frame sky-view table and
// aerial-perspective volume and of the composite, for the tests.
#pragma once

#include <glm/glm.hpp>

#include <vector>

#include "atmos/plugin.hpp"
#include "gpu/atmosphere_pass.hpp"
#include "gpu/composite_cpp.hpp"

namespace atmos::gpu {

// The instant mode's changes to a frame of make_pass_frame: surfaces seen
// from the atmosphere read the volume alone, at every altitude (there is no
// 4D table to evaluate them exactly with), none reads the space volume.
void make_instant_frame(const physics::AtmosphereParams& params, physics::PassFrame& frame);

// Read-only sampler views of the instant tables.
struct InstantSamplers {
  physics::sampler2D spectral_optical_depth;  // one tile per wavelength triple, then the scaled medium's
  physics::sampler2D multiple_scattering;     // Ψ_ms, one tile per triple
  physics::sampler2D indirect_irradiance;
};
InstantSamplers make_instant_samplers(const InstantTables& tables);

// This frame's instant sky-view table on the CPU, texel by texel as the
// GPU pass computes it (cameras in the atmosphere).
CpuSkyView compute_instant_sky_view_cpu(const physics::AtmosphereParams& params,
                                        const physics::SpectralSets& spectral, const InstantSamplers& samplers,
                                        const glm::vec3& camera, const glm::vec3& sun);

// This frame's instant aerial-perspective volume on the CPU, as the compute
// pass fills it (all zero / one when !frame.volume).
CpuVolume compute_instant_volume_cpu(const physics::AtmosphereParams& params, const physics::SpectralSets& spectral,
                                     const InstantSamplers& samplers, const physics::PassFrame& frame);

// The CPU twin of AtmospherePass::render() in the instant mode at the given
// pixels, as composite_cpu (gpu/atmosphere_pass.hpp) for the exact mode.
std::vector<glm::vec3> composite_instant_cpu(const Atmosphere& atmosphere, const InstantTables& tables,
                                             const PlanetFrame& planet, const FrameInput& input,
                                             const CpuEngineBuffers& buffers, const std::vector<glm::ivec2>& pixels);

// The sky radiance along unit view rays from a camera in the atmosphere
// (m, planet-centred), without the sun disc, in the tables' channels (for
// three wavelengths, spectral radiance at each, W m^-2 sr^-1 nm^-1,
// comparable with src/reference), as the instant pass computes it: read
// from this frame's sky-view table, phase functions per ray.
std::vector<glm::dvec3> instant_sky_radiance_cpu(const Atmosphere& atmosphere, const InstantTables& tables,
                                                 const glm::dvec3& camera, const glm::dvec3& sun,
                                                 const std::vector<glm::dvec3>& views);

// The light between a camera in the atmosphere and the points camera +
// offsets[i], as the instant pass computes it for surfaces (its volume).
std::vector<AerialPerspectiveSample> instant_aerial_perspective_cpu(const Atmosphere& atmosphere,
                                                                    const InstantTables& tables,
                                                                    const glm::dvec3& camera, const glm::dvec3& sun,
                                                                    const std::vector<glm::dvec3>& offsets);

}  // namespace atmos::gpu
