#include "gpu/star_catalogue_bins.hpp"

#include <epoxy/gl.h>
#include <glm/geometric.hpp>
#include <glm/matrix.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <string>

#include "atmos/atmosphere.hpp"
#include "atmos/colour.hpp"
#include "gpu/gl_util.hpp"
#include "physics/checks.hpp"

namespace atmos::gpu {

namespace {

constexpr int kCells = STAR_CATALOGUE_CELLS;
constexpr int kCellCount = 6 * kCells * kCells;
// The V band's effective wavelength (Bessell, Castelli & Plez 1998,
// Table A2), where atmos::Star gives the irradiance.
constexpr double kVEffectiveWavelengthNm = 545.0;

// Planck's law (Planck 1901) at `wavelength_nm` over its value at 545 nm:
// B(λ, T) ∝ λ⁻⁵ / (exp(hc / (λ k T)) − 1).
double planck_ratio_to_v(double wavelength_nm, double temperature_k) {
  constexpr double h = 6.62607015e-34, c = 299792458.0, k = 1.380649e-23;
  auto shape = [&](double nm) {
    const double l = nm * 1e-9;
    return 1.0 / (std::pow(l, 5) * std::expm1(h * c / (l * k * temperature_k)));
  };
  return shape(wavelength_nm) / shape(kVEffectiveWavelengthNm);
}

// The cells' geometry: each cell's centre direction and the angular radius
// of the cap around it that holds the cell (its farthest corner: the cells'
// edges are arcs of great circles, the cube's grid lines seen from its
// centre).
struct CellGeometry {
  std::vector<glm::dvec3> centre;
  std::vector<double> radius;
  double largest_radius = 0.0;
};

const CellGeometry& cell_geometry() {
  static const CellGeometry geometry = [] {
    CellGeometry g;
    g.centre.resize(kCellCount);
    g.radius.resize(kCellCount);
    auto direction = [](int face, double u, double v) {
      const physics::vec3 d = physics::star_cube_direction(face, physics::vec2(float(u), float(v)));
      return glm::normalize(glm::dvec3(d));
    };
    for (int face = 0; face < 6; ++face) {
      for (int row = 0; row < kCells; ++row) {
        for (int column = 0; column < kCells; ++column) {
          const int cell = (face * kCells + row) * kCells + column;
          const double step = 2.0 / kCells;
          const double u0 = column * step - 1.0, v0 = row * step - 1.0;
          const glm::dvec3 centre = direction(face, u0 + 0.5 * step, v0 + 0.5 * step);
          double radius = 0.0;
          for (int corner = 0; corner < 4; ++corner) {
            const glm::dvec3 p = direction(face, u0 + (corner & 1) * step, v0 + (corner >> 1) * step);
            radius = std::max(radius, std::acos(std::clamp(glm::dot(centre, p), -1.0, 1.0)));
          }
          g.centre[size_t(cell)] = centre;
          g.radius[size_t(cell)] = radius;
          g.largest_radius = std::max(g.largest_radius, radius);
        }
      }
    }
    return g;
  }();
  return geometry;
}

}  // namespace

glm::vec3 star_channel_irradiance(const Star& star, const std::vector<double>& wavelengths_nm) {
  if (wavelengths_nm.size() == 3) {
    glm::vec3 e;
    for (int c = 0; c < 3; ++c)
      e[c] = float(star.v_band_irradiance * planck_ratio_to_v(wavelengths_nm[size_t(c)], star.temperature_k));
    return e;
  }
  const std::vector<glm::dvec3> weights = spectral_to_srgb_weights(wavelengths_nm);
  glm::dvec3 srgb(0.0);
  for (size_t i = 0; i < wavelengths_nm.size(); ++i)
    srgb += weights[i] * (star.v_band_irradiance * planck_ratio_to_v(wavelengths_nm[i], star.temperature_k));
  return glm::vec3(srgb / kMaxLuminousEfficacy);
}

double star_bin_radius(double sigma) {
  double radius = std::ldexp(1.0, -16);
  while (radius < 5.0 * sigma && radius < kMaxStarBinRadius) radius *= 2.0;
  return radius;
}

physics::StarCatalogueView StarBins::view(const glm::dmat3& world_from_catalogue) const {
  physics::StarCatalogueView v;
  v.enabled = true;
  v.from_world = glm::mat3(glm::transpose(world_from_catalogue));
  v.cell_first = cell_first.data();
  v.records = records.data();
  return v;
}

StarBins bin_stars(const std::vector<glm::vec3>& directions, const std::vector<glm::vec3>& irradiances,
                   double radius) {
  const CellGeometry& geometry = cell_geometry();
  // A star's candidate cells: those of a grid of points over the tangent
  // plane around it, out to the largest cell's cap beyond `radius` (where
  // the centre of any cell within `radius` lies) and one step more. The
  // step, 0.004 rad, is under half the smallest cell's width (0.0147 rad,
  // at the cube's corners), so a grid point falls in every such cell.
  // Each candidate is kept if its cap comes within `radius` of the star
  // (with 1e-5 rad for the float lookups of cells at their edges).
  constexpr double kStep = 0.004;
  const double reach = std::tan(radius + geometry.largest_radius) + kStep;
  const int steps = int(std::ceil(reach / kStep));
  std::vector<std::array<std::uint32_t, 2>> entries;  // (cell, star)
  std::vector<int> cells;
  for (size_t s = 0; s < directions.size(); ++s) {
    const glm::dvec3 d = glm::normalize(glm::dvec3(directions[s]));
    const glm::dvec3 axis = std::abs(d.x) < 0.9 ? glm::dvec3(1, 0, 0) : glm::dvec3(0, 1, 0);
    const glm::dvec3 e1 = glm::normalize(glm::cross(d, axis));
    const glm::dvec3 e2 = glm::cross(d, e1);
    cells.clear();
    for (int i = -steps; i <= steps; ++i) {
      for (int j = -steps; j <= steps; ++j) {
        const double x = i * kStep, y = j * kStep;
        if (x * x + y * y > reach * reach) continue;
        const glm::dvec3 p = glm::normalize(d + x * e1 + y * e2);
        const int cell = physics::star_cube_cell(physics::vec3(p), kCells);
        if (std::find(cells.begin(), cells.end(), cell) != cells.end()) continue;
        cells.push_back(cell);
        const double angle = std::acos(std::clamp(glm::dot(d, geometry.centre[size_t(cell)]), -1.0, 1.0));
        if (angle <= geometry.radius[size_t(cell)] + radius + 1e-5)
          entries.push_back({std::uint32_t(cell), std::uint32_t(s)});
      }
    }
  }
  StarBins bins;
  bins.radius = radius;
  bins.cell_first.assign(size_t(kCellCount) + 1, 0);
  for (const auto& e : entries) ++bins.cell_first[e[0] + 1];
  for (size_t c = 0; c < size_t(kCellCount); ++c) bins.cell_first[c + 1] += bins.cell_first[c];
  bins.records.resize(2 * entries.size());
  std::vector<std::uint32_t> next(bins.cell_first.begin(), bins.cell_first.end() - 1);
  for (const auto& e : entries) {
    const std::uint32_t slot = next[e[0]]++;
    bins.records[2 * size_t(slot)] = glm::vec4(glm::normalize(directions[e[1]]), 0.0f);
    bins.records[2 * size_t(slot) + 1] = glm::vec4(irradiances[e[1]], 0.0f);
  }
  return bins;
}

void validate_star_orientation(const glm::dmat3& m, const char* who) {
  const glm::dmat3 should_be_identity = glm::transpose(m) * m;
  double error = std::abs(glm::determinant(m) - 1.0);
  for (int c = 0; c < 3; ++c)
    for (int r = 0; r < 3; ++r) error = std::max(error, std::abs(should_be_identity[c][r] - (c == r ? 1.0 : 0.0)));
  if (!(error <= 1e-6))
    throw Error(std::string(who) + ": the star orientation is not a rotation (orthonormal, determinant 1)");
}

StarCatalogueBuffers::~StarCatalogueBuffers() {
  if (gl_context_is_current()) release();
}

void StarCatalogueBuffers::set(const std::vector<Star>& stars, const std::vector<double>& wavelengths_nm) {
  validate_stars(stars);
  std::vector<glm::vec3> directions, irradiances;
  directions.reserve(stars.size());
  irradiances.reserve(stars.size());
  for (const Star& star : stars) {
    directions.push_back(glm::vec3(glm::normalize(star.direction)));
    irradiances.push_back(gpu::star_channel_irradiance(star, wavelengths_nm));
  }
  stars_ = stars;
  directions_ = std::move(directions);
  irradiances_ = std::move(irradiances);
  bins_ = StarBins{};
  uploaded_ = false;
}

void StarCatalogueBuffers::bind(double sigma) {
  const double radius = star_bin_radius(sigma);
  if (!uploaded_ || bins_.radius != radius) {
    bins_ = bin_stars(directions_, irradiances_, radius);
    if (cells_buffer_ == 0) glCreateBuffers(1, &cells_buffer_);
    if (records_buffer_ == 0) glCreateBuffers(1, &records_buffer_);
    glNamedBufferData(cells_buffer_, GLsizeiptr(bins_.cell_first.size() * sizeof(std::uint32_t)),
                      bins_.cell_first.data(), GL_STATIC_DRAW);
    // A buffer of no records still needs a size.
    const glm::vec4 none(0.0f);
    glNamedBufferData(records_buffer_,
                      GLsizeiptr(std::max<size_t>(bins_.records.size(), 1) * sizeof(glm::vec4)),
                      bins_.records.empty() ? &none : bins_.records.data(), GL_STATIC_DRAW);
    check_gl("while uploading the star catalogue");
    uploaded_ = true;
  }
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, STAR_CATALOGUE_CELLS_BINDING, cells_buffer_);
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, STAR_CATALOGUE_RECORDS_BINDING, records_buffer_);
}

void StarCatalogueBuffers::unbind() {
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, STAR_CATALOGUE_CELLS_BINDING, 0);
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, STAR_CATALOGUE_RECORDS_BINDING, 0);
}

void StarCatalogueBuffers::release() {
  if (cells_buffer_ != 0) glDeleteBuffers(1, &cells_buffer_);
  if (records_buffer_ != 0) glDeleteBuffers(1, &records_buffer_);
  cells_buffer_ = records_buffer_ = 0;
  uploaded_ = false;
}

void set_star_catalogue_uniforms(std::uint32_t program, bool enabled, const glm::dmat3& world_from_catalogue) {
  const glm::mat3 from_world(glm::transpose(world_from_catalogue));
  glProgramUniform1i(program, 60, enabled ? 1 : 0);
  glProgramUniformMatrix3fv(program, 61, 1, GL_FALSE, &from_world[0][0]);
}

}  // namespace atmos::gpu

namespace atmos {

glm::vec3 star_channel_irradiance(const Star& star, const std::vector<double>& wavelengths_nm) {
  return gpu::star_channel_irradiance(star, wavelengths_nm);
}

void validate_star_orientation(const glm::dmat3& m, const char* who) { gpu::validate_star_orientation(m, who); }

void validate_stars(const std::vector<Star>& stars) {
  for (size_t i = 0; i < stars.size(); ++i) {
    const Star& s = stars[i];
    const std::string which = "star " + std::to_string(i) + ": ";
    const glm::dvec3& d = s.direction;
    if (!(std::isfinite(d.x) && std::isfinite(d.y) && std::isfinite(d.z)) || glm::length(d) == 0.0)
      throw Error(which + "its direction is zero or not finite");
    if (!std::isfinite(s.v_band_irradiance) || s.v_band_irradiance < 0.0)
      throw Error(which + "its irradiance " + number_text(s.v_band_irradiance) + " is negative or not finite");
    if (!(s.temperature_k >= 1000.0 && s.temperature_k <= 100000.0))
      throw Error(which + "its temperature " + number_text(s.temperature_k) + " K is outside [1000, 100000]");
  }
}

}  // namespace atmos
