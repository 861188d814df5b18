// Procedural relief of a planet: the height above the datum sphere and the
// ground's albedo at every direction, in one of a few physically motivated
// styles (Earth-like, Mars-like, Venus-like, Titan-like, flat), with the
// bounds the level of detail needs (the height range and an error bound of a
// mesh of a given vertex spacing).
//
// Deterministic: the same settings give bit-identical heights on every
// machine (integer hashing, no std:: distributions, no platform math beyond
// + - * / floor sqrt). Heights are evaluated in double with split lattice
// coordinates (planet/noise.glsl), so octaves below a metre are exact at any
// planet's radius.
#pragma once

#include <glm/glm.hpp>

#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "atmos/planet_file.hpp"

namespace atmos::planet {

// The styles are those of a planet file's surface (atmos/planet_file.hpp).
using ReliefStyle = SurfaceStyle;

const char* relief_style_name(ReliefStyle style);

struct ReliefSettings {
  ReliefStyle style = ReliefStyle::earth;
  std::uint64_t seed = 1;
  double radius_m = 6360e3;  // the datum sphere (the atmosphere's bottom_radius)
  // The sea's height above the datum, m; none: the style's (Earth 0, the
  // others below their lowest ground: no sea).
  std::optional<double> sea_level_m;
  // Earth style: the signed distance from a direction to the real coast, m
  // (positive on land), and the size of the data it comes from, m. When
  // given, the land and the sea are where the data put them (the relief's
  // own continents are not used) and the coast gets a fractal wiggle below
  // the data's resolution.
  std::function<double(const glm::dvec3&)> coast_distance_m;
  double coast_resolution_m = 0.0;
};

class Relief {
 public:
  // atmos::Error for a radius that is not finite and positive or an unknown style.
  explicit Relief(const ReliefSettings& settings);

  const ReliefSettings& settings() const { return settings_; }

  // Height above the datum, m, at a direction from the planet's centre (unit
  // length up to rounding; the relief is defined on the datum sphere).
  double height_m(const glm::dvec3& direction) const;

  // Linear albedo (RGB in [0, 1]) of the ground at that direction. For the
  // Earth style below sea level it is the sea floor's (the water is drawn by
  // the caller).
  glm::vec3 albedo(const glm::dvec3& direction) const;

  // The style's fine detail alone: the octaves of the detail noise whose
  // wavelength is below max_wavelength_m, m. Each octave is lattice gradient
  // noise, zero at its lattice points and of zero mean over any area many
  // wavelengths wide (Perlin 2002): added to elevation data below its
  // resolution it does not shift the data's mean height.
  double detail_m(const glm::dvec3& direction, double max_wavelength_m) const;
  // A relative variation of the ground's brightness at wavelengths from
  // max_wavelength_m down to min_wavelength_m (and not below a metre):
  // octaves of gradient noise of amplitude 0.12 halving per octave, so the
  // factor 1 + albedo_variation lies in [0.76, 1.24] with mean 1. It puts
  // detail under imagery coarser than the mesh without changing the
  // imagery's mean colour.
  double albedo_variation(const glm::dvec3& direction, double max_wavelength_m, double min_wavelength_m) const;

  // A bound of |detail_m| for that cut-off, m.
  double detail_bound_m(double max_wavelength_m) const;

  // Bounds of height_m over the whole planet, m (rigorous: from the ranges of
  // the terms the height is summed from).
  double min_height_m() const { return min_height_m_; }
  double max_height_m() const { return max_height_m_; }

  // A bound of |h - I h| where I h is the bilinear interpolation of the height
  // between the vertices of a grid of spacing spacing_m laid on the datum
  // sphere (a tangent-plane grid projected onto the sphere, or a cube-sphere
  // tile's grid), m. Non-decreasing in spacing_m. The sagitta of a chord
  // (spacing^2 / (8 R)) is not included: it is a property of the mesh, not of
  // the relief. Derivation in relief.cpp.
  double error_below_spacing_m(double spacing_m) const;

  // Sea level, m above the datum (Earth style: 0; the other styles have no
  // ocean and return the lowest height minus one metre, so is_ocean is false).
  double sea_level_m() const { return sea_level_m_; }
  bool is_ocean(const glm::dvec3& direction) const { return height_m(direction) < sea_level_m_; }

  // Bounds of one term of the height (a noise octave, a crater class, a
  // large-scale field): its range of values and its smoothness, per metre of
  // arc on the datum sphere. Exposed for the tests.
  struct TermBound {
    double low_m = 0, high_m = 0;   // the term's values lie in [low, high]
    double slope = 0;               // Lipschitz constant along the datum sphere, m/m
    double curvature_per_m = -1;    // bound of |second directional derivative| in 3D, 1/m; < 0: kinked
  };
  const std::vector<TermBound>& term_bounds() const { return terms_; }

  // A crater found by crater_at: centre on the datum sphere (unit
  // direction), radius (rim), depth below and rim height above the
  // surrounding surface, m.
  struct Crater {
    glm::dvec3 centre{0.0};
    double radius_m = 0, depth_m = 0, rim_height_m = 0;
  };
  // Number of crater size classes of the style (diameters [D, 2D), D halving
  // from class to class), the smallest diameter of a class, and the crater of
  // class `size_class` whose ejecta (two crater radii) covers `direction`, if
  // any. For the tests and for placing things on the ground.
  int crater_class_count() const { return int(craters_.size()); }
  double crater_class_min_diameter_m(int size_class) const;
  bool crater_at(const glm::dvec3& direction, int size_class, Crater& crater) const;

  // The Mars style's canyon (a Valles Marineris): the direction of the middle
  // of its floor; (0, 0, 0) for the other styles. For placing cameras.
  glm::dvec3 canyon_centre() const;

  // One octave of a noise layer: its lattice (inverse wavelength, offset, key)
  // and its amplitude.
  struct Octave {
    double inv_wavelength_per_m = 0;
    double amplitude_m = 0;
    glm::dvec3 offset{0.0};  // dyadic fraction of a cell per axis
    glm::uvec3 key{0u};      // hashed seed of the layer and octave
  };
  // One crater size class: diameters [D, 2D) on a lattice of cell S = 20 D.
  struct CraterClass {
    double min_diameter_m = 0;
    double cell_m = 0;
    double inv_cell_per_m = 0;
    double simple_depth_m = 0, simple_depth_shape = 0;    // d = 0.14 D^0.90 (km) at D = min_diameter
    double complex_depth_m = 0, complex_depth_shape = 0;  // d = 0.25 D^0.49 (km)
    double rim_m = 0, rim_shape = 0;                      // h_r = 0.036 D^1.014 (km)
    glm::dvec3 offset{0.0};
    glm::uvec3 key{0u};
  };

 private:
  double large_scale_field(const glm::dvec3& p_m) const;
  double dichotomy_coordinate(const glm::dvec3& direction, const glm::dvec3& p_m) const;
  double craters_m(const glm::dvec3& p_m) const;
  double canyon_m(const glm::dvec3& direction, const glm::dvec3& p_m) const;
  double crater_presence(const glm::dvec3& centre_direction) const;
  bool crater_in_cell(const glm::dvec3& p_m, const CraterClass& size_class, Crater& crater, double& r) const;
  double sum_octaves(const std::vector<Octave>& octaves, const glm::dvec3& p_m) const;
  void add_octave_bounds(const std::vector<Octave>& octaves);
  void calibrate_threshold(double fraction_below);
  void finish_bounds();

  ReliefSettings settings_;
  double min_height_m_ = 0, max_height_m_ = 0, sea_level_m_ = 0;
  std::vector<TermBound> terms_;

  std::vector<Octave> large_scale_;  // continents / highlands / the dichotomy boundary's wobble
  std::vector<Octave> belt_;         // where mountains rise
  std::vector<Octave> ridges_;       // ridged octaves
  std::vector<Octave> detail_;       // fBm down to below a metre
  std::vector<Octave> dunes_;        // Titan: ridges stretched east-west
  std::vector<Octave> coast_wiggle_; // Earth with a data coast: the coast's detail, m of distance
  std::vector<CraterClass> craters_;
  double threshold_ = 0;             // the large-scale field's value at the coast / highland edge
  glm::dvec3 dichotomy_axis_{0.0, 0.0, -1.0};
  // The canyon runs along the great circle with pole canyon_pole_, centred
  // on canyon_centre_; canyon_wobble_ varies its width.
  glm::dvec3 canyon_pole_{0.0}, canyon_centre_{0.0};
  std::vector<Octave> canyon_wobble_;
  double crater_presence_low_ = 0, crater_presence_high_ = 0;
};

// One octave's noise at p (planet-centred m): gradient_noise (noise.glsl) on
// the octave's lattice, p / wavelength + offset. The relief's layers are
// sums of it.
double octave_noise(const glm::dvec3& p_m, const Relief::Octave& octave);

}  // namespace atmos::planet
