#include "physics/parameters.hpp"

#include <algorithm>
#include <cmath>

#include "atmos/colour.hpp"
#include "physics/medium_cpp.hpp"
#include "physics/table_coordinates_cpp.hpp"

namespace atmos::physics {

double mu_s_min(const Atmosphere& atmosphere) {
  const double horizon_dip = std::acos(atmosphere.bottom_radius_m / atmosphere.top_radius_m);
  const double margin = 2.0 * M_PI / 180.0;
  return std::cos(M_PI / 2.0 + horizon_dip + margin);
}

int spectral_set_count(const std::vector<double>& wavelengths_nm) { return int((wavelengths_nm.size() + 2) / 3); }

std::array<double, 3> set_wavelengths(const std::vector<double>& wavelengths_nm, int set) {
  std::array<double, 3> w{};
  for (size_t c = 0; c < 3; ++c) w[c] = wavelengths_nm.at(std::min(3 * size_t(set) + c, wavelengths_nm.size() - 1));
  return w;
}

bool srgb_channels(const std::vector<double>& wavelengths_nm) { return wavelengths_nm.size() != 3; }

glm::mat3 set_to_channels(const std::vector<double>& wavelengths_nm, int set) {
  if (!srgb_channels(wavelengths_nm)) return glm::mat3(1.0f);
  const std::vector<glm::dvec3> weights = spectral_to_srgb_weights(wavelengths_nm);
  glm::mat3 m(0.0f);
  for (size_t c = 0; c < 3; ++c) {
    const size_t i = 3 * size_t(set) + c;
    if (i < weights.size()) m[int(c)] = glm::vec3(weights[i] / kMaxLuminousEfficacy);
  }
  return m;
}

glm::mat3 channels_to_srgb_matrix(const std::vector<double>& wavelengths_nm) {
  if (srgb_channels(wavelengths_nm)) return glm::mat3(float(kMaxLuminousEfficacy));
  return radiance_to_srgb_matrix({wavelengths_nm[0], wavelengths_nm[1], wavelengths_nm[2]});
}

namespace {

// The aerosol phase function's parameters at one wavelength per channel.
void set_aerosol_phase(AtmosphereParams& p, const PhaseFunction& aerosol, const std::array<double, 3>& w) {
  auto spectrum = [&](const Spectrum& s) {
    return vec3(float(s.at(w[0])), float(s.at(w[1])), float(s.at(w[2])));
  };
  p.aerosol_phase_kind = aerosol.kind == PhaseFunction::Kind::cornette_shanks ? PHASE_CORNETTE_SHANKS
                         : aerosol.kind == PhaseFunction::Kind::double_henyey_greenstein
                             ? PHASE_DOUBLE_HENYEY_GREENSTEIN
                             : PHASE_HENYEY_GREENSTEIN;
  p.aerosol_g = spectrum(aerosol.g);
  const bool two_lobes = aerosol.kind == PhaseFunction::Kind::double_henyey_greenstein;
  p.aerosol_g_back = two_lobes ? spectrum(aerosol.g_back) : vec3(0.0f);
  p.aerosol_forward_weight = two_lobes ? spectrum(aerosol.forward_weight) : vec3(1.0f);
}

// Whether delta_scaled_params scales the aerosol of some wavelength triple or
// of the render parameters: the whole atmosphere's tables then use the nu
// axis uniform in angle (every set's tables are summed texel by texel).
// The one criterion of delta_scaled_params and has_scaled_lobe.
bool lobe_is_scaled(float g) { return g > kDeltaScaledMaxG; }

bool has_scaled_lobe(const Atmosphere& atmosphere) {
  const PhaseFunction phase = atmosphere.aerosol_phase();
  std::vector<double> wavelengths = atmosphere.wavelengths_nm;
  wavelengths.insert(wavelengths.end(), kRenderPhaseWavelengths.begin(), kRenderPhaseWavelengths.end());
  bool has_aerosol = false;
  for (const Constituent& c : atmosphere.constituents) has_aerosol |= c.phase.kind != PhaseFunction::Kind::rayleigh;
  if (!has_aerosol) return false;
  for (double w : wavelengths)
    if (lobe_is_scaled(float(phase.g.at(w)))) return true;
  return false;
}

// `params` with every constituent's coefficients at 550 nm in all channels.
AtmosphereParams params_at_550(const Atmosphere& atmosphere, const AtmosphereParams& params) {
  AtmosphereParams p = params;
  for (int i = 0; i < p.constituent_count; ++i) {
    const Constituent& c = atmosphere.constituents[size_t(i)];
    p.scattering[i] = vec3(float(c.scattering.at(550.0)));
    p.absorption[i] = vec3(float(c.absorption.at(550.0)));
  }
  return p;
}

// The vertical optical depth from radius r to the top, of params_at_550:
// 4000 trapezoid steps over the whole column (25 m on Earth, within 1e-4 of
// the column of a piecewise-linear profile whose knots are kilometres
// apart), proportionally fewer from higher up.
double optical_depth_to_top(const AtmosphereParams& p, float r) {
  const float length = p.top_radius - r;
  const int steps = std::max(16, int(std::ceil(4000.0 * length / (p.top_radius - p.bottom_radius))));
  return double(optical_depth_along_ray(p, r, 1.0f, 0.0f, length, steps).x);
}

// AtmosphereParams.scattering_r_axis for weight w (see
// scattering_x_r_from_rho_fraction in functions.glsl): at rho / H = i / (n - 1),
// (1 - w) rho / H + w (1 - tau(r) / tau(bottom)), with tau(bottom) =
// vertical_optical_depth_550 (given: computed once).
void set_scattering_r_axis(const Atmosphere& atmosphere, AtmosphereParams& p, double w, double tau_bottom) {
  p.scattering_r_optical_depth_weight = float(w);
  const int n = SCATTERING_R_AXIS_KNOTS;
  if (w == 0.0) {  // Bruneton's axis; the knots are not read, they say so
    for (int i = 0; i < n; ++i) p.scattering_r_axis[i] = float(i) / float(n - 1);
    return;
  }
  const AtmosphereParams p550 = params_at_550(atmosphere, p);
  const double H = std::sqrt((double(p.top_radius) - p.bottom_radius) * (double(p.top_radius) + p.bottom_radius));
  for (int i = 0; i < n; ++i) {
    const double s = double(i) / double(n - 1);
    const double r = std::sqrt(s * s * H * H + double(p.bottom_radius) * p.bottom_radius);
    const double tau = i == n - 1 ? 0.0 : optical_depth_to_top(p550, float(std::min(r, double(p.top_radius))));
    p.scattering_r_axis[i] = float((1.0 - w) * s + w * (1.0 - tau / tau_bottom));
  }
  p.scattering_r_axis[0] = 0.0f;
  p.scattering_r_axis[n - 1] = 1.0f;
}

}  // namespace

double vertical_optical_depth_550(const Atmosphere& atmosphere, const AtmosphereParams& params) {
  const AtmosphereParams p = params_at_550(atmosphere, params);
  return optical_depth_to_top(p, p.bottom_radius);
}

double scattering_r_optical_depth_weight(double mu_log_weight) {
  return kScatteringROpticalDepthShare * mu_log_weight;
}

namespace {

// 0 up to optical depth `range`[0], 1 from `range`[1], smoothstep in log τ
// between.
double log_smoothstep(double optical_depth, const std::array<double, 2>& range) {
  const double x = std::clamp((std::log(std::max(optical_depth, 1e-30)) - std::log(range[0])) /
                                  (std::log(range[1]) - std::log(range[0])),
                              0.0, 1.0);
  return x * x * (3.0 - 2.0 * x);
}

}  // namespace

double scattering_mu_log_weight(double vertical_optical_depth) {
  return log_smoothstep(vertical_optical_depth, kMuLogWarpOpticalDepth);
}

double source_flat_optical_depth(double vertical_optical_depth) {
  return kSourceFlatOpticalDepth * log_smoothstep(vertical_optical_depth, kSourceFlatOpticalDepthRange);
}

AtmosphereParams make_atmosphere_params(const Atmosphere& atmosphere, const TableSizes& sizes, int set,
                                        int transmittance_tile, int transmittance_tiles) {
  AtmosphereParams p{};
  const std::array<double, 3> w = set_wavelengths(atmosphere.wavelengths_nm, set);
  auto spectrum = [&](const Spectrum& s) {
    return vec3(float(s.at(w[0])), float(s.at(w[1])), float(s.at(w[2])));
  };
  p.bottom_radius = float(atmosphere.bottom_radius_m);
  p.top_radius = float(atmosphere.top_radius_m);
  p.constituent_count = int(atmosphere.constituents.size());
  set_aerosol_phase(p, atmosphere.aerosol_phase(), w);
  for (int i = 0; i < p.constituent_count; ++i) {
    const Constituent& c = atmosphere.constituents[size_t(i)];
    DensityProfile& d = p.density[i];
    if (c.density.kind == atmos::DensityProfile::Kind::exponential) {
      d.scale_height = float(c.density.scale_height_m);
      d.knot_count = 0;
    } else {
      d.scale_height = 0.0f;
      d.knot_count = int(c.density.knots.size());
      for (int k = 0; k < d.knot_count; ++k) {
        d.knot_altitude[k] = float(c.density.knots[size_t(k)].first);
        d.knot_density[k] = float(c.density.knots[size_t(k)].second);
      }
    }
    p.scattering[i] = spectrum(c.scattering);
    p.absorption[i] = spectrum(c.absorption);
    p.is_aerosol[i] = c.phase.kind == PhaseFunction::Kind::rayleigh ? 0 : 1;
  }
  p.ground_albedo = spectrum(atmosphere.ground_albedo);
  p.solar_irradiance = spectrum(atmosphere.solar_irradiance);
  p.sun_angular_radius = float(atmosphere.sun_angular_radius_rad);
  p.mu_s_min = float(mu_s_min(atmosphere));
  p.transmittance_mu_size = sizes.transmittance_mu;
  p.transmittance_r_size = sizes.transmittance_r;
  p.irradiance_mu_s_size = sizes.irradiance_mu_s;
  p.irradiance_r_size = sizes.irradiance_r;
  p.scattering_nu_size = sizes.scattering_nu;
  p.scattering_mu_s_size = sizes.scattering_mu_s;
  p.scattering_mu_size = sizes.scattering_mu;
  p.scattering_r_size = sizes.scattering_r;
  p.transmittance_tile = transmittance_tile;
  p.transmittance_tiles = transmittance_tiles;
  p.single_scattering_tile = transmittance_tile;
  p.scattering_nu_in_angle = has_scaled_lobe(atmosphere) ? 1 : 0;
  const double vertical_optical_depth = vertical_optical_depth_550(atmosphere, p);
  const double mu_log_weight = scattering_mu_log_weight(vertical_optical_depth);
  p.scattering_mu_log_weight = float(mu_log_weight);
  p.source_flat_optical_depth = float(source_flat_optical_depth(vertical_optical_depth));
  set_scattering_r_axis(atmosphere, p, scattering_r_optical_depth_weight(mu_log_weight), vertical_optical_depth);
  p.scattering_row_1_height = scattering_row_height(p, 1);
  return p;
}

AtmosphereParams delta_scaled_params(const AtmosphereParams& params, vec3& forward_fraction) {
  AtmosphereParams p = params;
  forward_fraction = vec3(0.0f);
  const float g_star = kDeltaScaledMaxG;
  for (int c = 0; c < 3; ++c) {
    const float g = params.aerosol_g[c];
    if (!lobe_is_scaled(g)) continue;
    // The forward lobe's own fraction, then its share of the phase function.
    const float lobe_fraction = (g - g_star) / (1.0f - g_star);
    p.aerosol_g[c] = g_star;
    if (params.aerosol_phase_kind == PHASE_DOUBLE_HENYEY_GREENSTEIN) {
      const float w = params.aerosol_forward_weight[c];
      forward_fraction[c] = w * lobe_fraction;
      // What is left of the forward lobe, renormalised with the second lobe.
      p.aerosol_forward_weight[c] = w * (1.0f - lobe_fraction) / (1.0f - forward_fraction[c]);
    } else {
      forward_fraction[c] = lobe_fraction;
    }
  }
  for (int i = 0; i < p.constituent_count; ++i)
    if (p.is_aerosol[i] != 0) p.scattering[i] = params.scattering[i] * (vec3(1.0f) - forward_fraction);
  return p;
}

AtmosphereParams make_render_params(const Atmosphere& atmosphere, const TableSizes& sizes) {
  AtmosphereParams p = make_atmosphere_params(atmosphere, sizes, 0);
  if (!srgb_channels(atmosphere.wavelengths_nm)) return p;
  glm::dvec3 sun(0.0), reflected(0.0);
  for (int set = 0; set < spectral_set_count(atmosphere.wavelengths_nm); ++set) {
    const AtmosphereParams s = make_atmosphere_params(atmosphere, sizes, set);
    const glm::dmat3 m(set_to_channels(atmosphere.wavelengths_nm, set));
    sun += m * glm::dvec3(s.solar_irradiance);
    reflected += m * glm::dvec3(s.ground_albedo * s.solar_irradiance);
  }
  p.solar_irradiance = vec3(sun);
  // Sunlight is inside the sRGB gamut (all channels > 0); the albedo is
  // clamped to [0, 1] all the same, as a reflectance must be.
  p.ground_albedo = clamp(vec3(reflected / sun), 0.0f, 1.0f);
  for (int i = 0; i < MAX_CONSTITUENTS; ++i) p.scattering[i] = p.absorption[i] = vec3(0.0f);
  // The run time applies the aerosol phase function per pixel in the
  // channels (linear sRGB): each channel gets the parameters at a wavelength
  // representative of it, those of the three-wavelength mode (red 680, green
  // 550, blue 440 nm, near the peaks of the sRGB colour matching functions).
  // The single aerosol table and the spectral integration store the ratio of
  // the exact per-wavelength sum to this phase function (precompute.cpp,
  // spectral_single_scattering), so the choice does not bias the result; a
  // phase function close to the channel's effective one keeps that ratio
  // smooth in nu, which the tables interpolate.
  set_aerosol_phase(p, atmosphere.aerosol_phase(), kRenderPhaseWavelengths);
  return p;
}

std::unique_ptr<SpectralSets> make_spectral_sets(const Atmosphere& atmosphere, const TableSizes& sizes) {
  const int count = spectral_set_count(atmosphere.wavelengths_nm);
  if (count > SPECTRAL_SET_CAPACITY)
    throw Error("at most " + std::to_string(3 * SPECTRAL_SET_CAPACITY) + " working wavelengths are supported, got " +
                std::to_string(atmosphere.wavelengths_nm.size()));
  auto sets = std::make_unique<SpectralSets>();
  *sets = SpectralSets{};
  sets->count = count;
  for (int k = 0; k < count; ++k) {
    // Tiles 0..count-1: the true optical depth; count..2 count-1: the scaled
    // medium's, which the single scattering reads (Tables::transmittance_tiles).
    sets->set[k] = make_atmosphere_params(atmosphere, sizes, k, k, 2 * count);
    sets->set[k].single_scattering_tile = count + k;
    sets->to_channels[k] = set_to_channels(atmosphere.wavelengths_nm, k);
  }
  return sets;
}

}  // namespace atmos::physics
