// The stars of a catalogue (atmos::Star) as the renderers read them
// (physics/stars.glsl: star_catalogue_radiance): each star's irradiance in
// the tables' channels, and the stars binned by the cells of a cube map,
// on the CPU for render_cpu and in two shader storage buffers for the GPU.
#pragma once

#include <glm/mat3x3.hpp>
#include <glm/vec3.hpp>
#include <glm/vec4.hpp>

#include <cstdint>
#include <vector>

#include "atmos/renderer.hpp"
#include "physics/stars_cpp.hpp"

namespace atmos::gpu {

// The irradiance of `star` in the channels of tables computed at
// `wavelengths_nm`: its blackbody spectrum scaled to its irradiance at
// 545 nm, at the three wavelengths (three-wavelength tables), or weighted
// by spectral_to_srgb_weights over all of them (spectral tables, whose
// channels are linear sRGB over 683 lm/W), as the sun's irradiance is.
glm::vec3 star_channel_irradiance(const Star& star, const std::vector<double>& wavelengths_nm);

// The radius the bins are built for, radians: a power of two times 2^-16
// rad at least five image widths (5 sigma, where the Gaussian image is
// 4e-6 of its peak), so that a camera that changes its field of view
// little keeps its bins; at most kMaxStarBinRadius (images wider than
// that, of cameras whose pixels span degrees, are cut there).
double star_bin_radius(double sigma);
inline constexpr double kMaxStarBinRadius = 0.0625;

// The stars binned by cell: cell_first has STAR_CATALOGUE_CELLS² x 6 + 1
// entries (a cell's records are cell_first[c] .. cell_first[c + 1] - 1),
// records two vec4 per entry (the unit direction, then the channel
// irradiance).
struct StarBins {
  std::vector<std::uint32_t> cell_first;
  std::vector<glm::vec4> records;
  double radius = 0.0;  // the star_bin_radius they were built for

  // The C++ view of the bins for physics::StarField (valid while they live).
  physics::StarCatalogueView view(const glm::dmat3& world_from_catalogue) const;
};

// Bins `directions` (unit, the catalogue's frame) with their channel
// irradiances: a cell lists every star within `radius` of some point of it
// (conservatively: of the cap around the cell's centre that holds the cell).
StarBins bin_stars(const std::vector<glm::vec3>& directions, const std::vector<glm::vec3>& irradiances,
                   double radius);

// Throws atmos::Error unless `m` is a rotation (orthonormal with
// determinant 1, to 1e-6); `who` names the caller.
void validate_star_orientation(const glm::dmat3& m, const char* who);

// A catalogue for one renderer: the stars' directions and channel
// irradiances, their bins for the current image width, and on the GPU the
// bins' two storage buffers. Needs a current OpenGL context to upload.
class StarCatalogueBuffers {
 public:
  StarCatalogueBuffers() = default;
  ~StarCatalogueBuffers();
  StarCatalogueBuffers(const StarCatalogueBuffers&) = delete;
  StarCatalogueBuffers& operator=(const StarCatalogueBuffers&) = delete;

  // Validates and keeps `stars` (their irradiance in the channels of
  // `wavelengths_nm`); the bins are built at the next bind.
  void set(const std::vector<Star>& stars, const std::vector<double>& wavelengths_nm);
  const std::vector<Star>& stars() const { return stars_; }
  bool empty() const { return stars_.empty(); }

  // Binds the bins for images of width `sigma` (rebuilt and uploaded when
  // star_bin_radius(sigma) changed) at the binding points of stars.glsl.
  void bind(double sigma);
  // Unbinds them.
  static void unbind();
  // Releases the buffers (with the context current).
  void release();

 private:
  std::vector<Star> stars_;
  std::vector<glm::vec3> directions_;
  std::vector<glm::vec3> irradiances_;
  StarBins bins_;
  std::uint32_t cells_buffer_ = 0;
  std::uint32_t records_buffer_ = 0;
  bool uploaded_ = false;
};

// Sets the uniforms of stars.glsl's catalogue in `program`: drawn or not,
// and the rotation from the world's axes to the catalogue's frame.
void set_star_catalogue_uniforms(std::uint32_t program, bool enabled, const glm::dmat3& world_from_catalogue);

}  // namespace atmos::gpu
