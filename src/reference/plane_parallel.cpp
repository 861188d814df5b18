// A second, deterministic reference: the fluxes of a plane-parallel
// atmosphere by the adding-doubling method (see include/atmos/reference.hpp,
// reference_plane_parallel_fluxes).
//
// Why a second reference. The Monte Carlo reference (reference.cpp) is exact
// in expectation, but in an optically thick, nearly conservative atmosphere
// (Venus: 47 optical depths at 550 nm, light scattered thousands of times)
// its paths are long and its noise is a few percent after minutes. The
// fluxes of such an atmosphere at moderate sun elevations are those of a
// plane-parallel slab to well within that: the light spreads sideways by
// about the atmosphere's thickness, 100 km against a radius of 6052 km.
// Fluxes only need the azimuthal mean (Fourier term m = 0) of the radiance,
// and for that the adding-doubling method is exact up to its quadratures,
// with no noise (Hansen & Travis 1974, Space Sci. Rev. 16, 527, §3;
// van de Hulst 1980, "Multiple light scattering", ch. 4).
//
// Discretisation (all in double precision):
//  - directions: Gauss-Legendre nodes mu_i, weights w_i on (0, 1] in each
//    hemisphere ("double Gauss"), plus the sun's mu_0 as a column only;
//  - the azimuthally averaged phase kernel
//      P(mu, mu') = ∫_0^2π p(mu mu' + sqrt(1 - mu²) sqrt(1 - mu'²) cos phi) dphi,
//    with ∫_{-1}^{1} P(mu, mu') dmu' = 1, by Gauss-Legendre in phi, each
//    incident column renormalised so that the discrete kernel conserves
//    energy exactly (Σ_i w_i (P(mu_i, mu') + P(-mu_i, mu')) = 1);
//  - layers homogeneous in altitude slices of at most
//    `max_layer_optical_depth` and `max_layer_thickness_m`, with the slice's
//    mean extinction, single-scattering albedo and phase mixture;
//  - each layer by doubling from a thin layer of optical depth <= 1e-7 in
//    the single scattering approximation (its error, of second order in the
//    thin optical depth, adds up to ~1e-7 of the light per unit optical
//    depth), the layers and the Lambertian ground by adding.
// Conventions: radiances per unit solar irradiance at normal incidence; a
// matrix M maps incident radiances at the quadrature nodes to outgoing ones,
// I_out(mu_i) = Σ_j M_ij I_in(mu_j), so that a flux is 2π Σ_i mu_i w_i I(mu_i).
#include <Eigen/Dense>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>
#include <vector>

#include "reference/reference.hpp"
#include "reference/reference_detail.hpp"
#include "physics/quadrature.hpp"

namespace atmos {
namespace {

constexpr double kPi = std::numbers::pi;
using Eigen::MatrixXd;
using Eigen::VectorXd;
using physics::gauss_legendre;

// The reflection and transmission of a layer (or a stack of layers) for the
// azimuthal mean: R_top for light incident from above, R_bottom from below,
// T_down and T_up the transmissions (the unscattered part included); and its
// response to the solar beam incident at its top, per unit irradiance at
// normal incidence: the diffuse radiance reflected upwards (beam_up) and
// transmitted downwards (beam_down), and the beam's own transmission e.
struct Layer {
  MatrixXd r_top, r_bottom, t_down, t_up;
  VectorXd beam_up, beam_down;
  double e = 1.0;
};

// The beam's part of `a` over `b`: the diffuse light d (down) and u (up) at
// the interface, `down` = (I - R_bottom(a) R_top(b))^-1. Returns d.
VectorXd add_beam(const Layer& a, const Layer& b, const MatrixXd& down, Layer& ab) {
  const VectorXd d = down * (a.beam_down + a.e * a.r_bottom * b.beam_up);
  const VectorXd u = a.e * b.beam_up + b.r_top * d;
  ab.beam_up = a.beam_up + a.t_up * u;
  ab.beam_down = a.e * b.beam_down + b.t_down * d;
  ab.e = a.e * b.e;
  return d;
}

// `a` over `b` (adding, Hansen & Travis 1974 eqs. 93-96 in this notation);
// `interface_down`, if given, receives the diffuse radiance going down
// between them due to the beam.
Layer add(const Layer& a, const Layer& b, VectorXd* interface_down = nullptr) {
  const int n = int(a.r_top.rows());
  const MatrixXd identity = MatrixXd::Identity(n, n);
  // Light going down through a meets b, and bounces between them.
  const MatrixXd down = (identity - a.r_bottom * b.r_top).partialPivLu().inverse();
  const MatrixXd up = (identity - b.r_top * a.r_bottom).partialPivLu().inverse();
  Layer ab;
  ab.r_top = a.r_top + a.t_up * b.r_top * down * a.t_down;
  ab.t_down = b.t_down * down * a.t_down;
  ab.r_bottom = b.r_bottom + b.t_down * a.r_bottom * up * b.t_up;
  ab.t_up = a.t_up * up * b.t_up;
  const VectorXd d = add_beam(a, b, down, ab);
  if (interface_down) *interface_down = d;
  return ab;
}

// The same for two identical homogeneous layers (symmetric: R_top =
// R_bottom, T_down = T_up), half the work.
Layer double_layer(const Layer& a) {
  const int n = int(a.r_top.rows());
  const MatrixXd down = (MatrixXd::Identity(n, n) - a.r_top * a.r_top).partialPivLu().inverse();
  Layer ab;
  const MatrixXd t_down = a.t_down * down;
  ab.r_top = a.r_top + t_down * a.r_top * a.t_down;
  ab.t_down = t_down * a.t_down;
  ab.r_bottom = ab.r_top;
  ab.t_up = ab.t_down;
  add_beam(a, a, down, ab);
  return ab;
}

// Azimuthal means of one phase function: same[i][j] = P(mu_i, mu_j) (both
// directions in the same hemisphere) and opposite[i][j] = P(-mu_i, mu_j),
// for j < n the quadrature nodes and j = n the sun's mu_0.
struct Kernel {
  MatrixXd same, opposite;  // n x (n + 1)
};

Kernel azimuthal_kernel(const PhaseFunction& phase, double wavelength_nm, const std::vector<double>& mu,
                        double mu_0) {
  const int n = int(mu.size());
  std::vector<double> phi, phi_weight;
  gauss_legendre(512, 0.0, kPi, phi, phi_weight);
  std::vector<double> cos_phi(phi.size());
  for (size_t k = 0; k < phi.size(); ++k) cos_phi[k] = std::cos(phi[k]);
  Kernel kernel{MatrixXd(n, n + 1), MatrixXd(n, n + 1)};
  for (int j = 0; j <= n; ++j) {
    const double mu_j = j < n ? mu[size_t(j)] : mu_0;
    const double sin_j = std::sqrt(std::max(0.0, 1.0 - mu_j * mu_j));
    for (int i = 0; i < n; ++i) {
      const double mu_i = mu[size_t(i)], sin_i = std::sqrt(std::max(0.0, 1.0 - mu_i * mu_i));
      double same = 0.0, opposite = 0.0;
      for (size_t k = 0; k < phi.size(); ++k) {
        // The 2π of the azimuth is the two halves [0, π] and [π, 2π].
        const double spread = sin_i * sin_j * cos_phi[k];
        same += 2.0 * phi_weight[k] * reference_detail::phase_function(phase, wavelength_nm, mu_i * mu_j + spread);
        opposite +=
            2.0 * phi_weight[k] * reference_detail::phase_function(phase, wavelength_nm, -mu_i * mu_j + spread);
      }
      kernel.same(i, j) = same;
      kernel.opposite(i, j) = opposite;
    }
  }
  return kernel;
}

// One homogeneous layer of optical depth tau, single-scattering albedo omega
// and azimuthal phase kernel `kernel` (mixed and renormalised), by doubling.
Layer homogeneous_layer(double tau, double omega, const Kernel& kernel, const std::vector<double>& mu,
                        const std::vector<double>& w, double mu_0) {
  const int n = int(mu.size());
  int doublings = 0;
  double delta = tau;
  while (delta > 1e-7) {
    delta *= 0.5;
    ++doublings;
  }
  // The thin layer: unscattered light exp(-delta / mu), plus single
  // scattering omega delta / mu P (first order in delta).
  Layer layer;
  layer.r_top = MatrixXd(n, n);
  layer.t_down = MatrixXd(n, n);
  layer.beam_up = VectorXd(n);
  layer.beam_down = VectorXd(n);
  for (int i = 0; i < n; ++i) {
    const double path = omega * delta / mu[size_t(i)];
    for (int j = 0; j < n; ++j) {
      layer.r_top(i, j) = path * kernel.opposite(i, j) * w[size_t(j)];
      layer.t_down(i, j) = path * kernel.same(i, j) * w[size_t(j)] + (i == j ? std::exp(-delta / mu[size_t(i)]) : 0.0);
    }
    // The beam of unit normal irradiance is a radiance of 1 / (2π) per unit
    // "weight" in the azimuthal mean.
    layer.beam_up(i) = path * kernel.opposite(i, n) / (2.0 * kPi);
    layer.beam_down(i) = path * kernel.same(i, n) / (2.0 * kPi);
  }
  layer.r_bottom = layer.r_top;
  layer.t_up = layer.t_down;
  layer.e = std::exp(-delta / mu_0);
  for (int k = 0; k < doublings; ++k) layer = double_layer(layer);
  return layer;
}

struct Slice {
  double optical_depth = 0.0;
  double omega = 0.0;
  std::vector<double> phase_weight;  // per constituent: its share of the slice's scattering
};

// The altitude slices at one wavelength, top first: cut so that none holds
// more than max_layer_optical_depth or is thicker than max_layer_thickness_m;
// their optical depths and scattering shares integrated with the midpoint
// rule on steps of max_layer_thickness_m / 64 (at most 1/4096 of the
// atmosphere).
std::vector<Slice> make_slices(const Atmosphere& a, double wavelength_nm, const PlaneParallelOptions& options) {
  const double top = a.top_radius_m - a.bottom_radius_m;
  const size_t count = a.constituents.size();
  std::vector<double> scattering(count), absorption(count);
  for (size_t c = 0; c < count; ++c) {
    scattering[c] = a.constituents[c].scattering.at(wavelength_nm);
    absorption[c] = a.constituents[c].absorption.at(wavelength_nm);
  }
  const double step = std::min(options.max_layer_thickness_m / 64.0, top / 4096.0);
  std::vector<Slice> slices;
  Slice current;
  std::vector<double> current_scattering(count, 0.0);
  double current_scattering_total = 0.0, current_absorption = 0.0, current_thickness = 0.0;
  auto close = [&]() {
    const double total_scattering = current_scattering_total;
    current.optical_depth = total_scattering + current_absorption;
    current.omega = current.optical_depth > 0.0 ? total_scattering / current.optical_depth : 0.0;
    current.phase_weight.assign(count, 0.0);
    for (size_t c = 0; c < count; ++c)
      current.phase_weight[c] = total_scattering > 0.0 ? current_scattering[c] / total_scattering : 0.0;
    slices.push_back(current);
    current = Slice();
    std::fill(current_scattering.begin(), current_scattering.end(), 0.0);
    current_scattering_total = 0.0;
    current_absorption = 0.0;
    current_thickness = 0.0;
  };
  const int steps = int(std::ceil(top / step));
  for (int k = 0; k < steps; ++k) {
    const double h0 = top * k / steps, h1 = top * (k + 1) / steps, h = 0.5 * (h0 + h1), dh = h1 - h0;
    double scattered = 0.0, absorbed = 0.0;
    std::vector<double> per(count);
    for (size_t c = 0; c < count; ++c) {
      const double rho = a.constituents[c].density.at(h);
      per[c] = scattering[c] * rho * dh;
      scattered += per[c];
      absorbed += absorption[c] * rho * dh;
    }
    const double depth_so_far = current_scattering_total + current_absorption;
    if (current_thickness > 0.0 &&
        (depth_so_far + scattered + absorbed > options.max_layer_optical_depth ||
         current_thickness + dh > options.max_layer_thickness_m * (1.0 + 1e-9)))
      close();
    for (size_t c = 0; c < count; ++c) current_scattering[c] += per[c];
    current_scattering_total += scattered;
    current_absorption += absorbed;
    current_thickness += dh;
  }
  if (current_thickness > 0.0) close();
  std::reverse(slices.begin(), slices.end());  // top first
  return slices;
}

}  // namespace

PlaneParallelFluxes reference_plane_parallel_fluxes(const Atmosphere& atmosphere, double mu_s,
                                                    const PlaneParallelOptions& options) {
  atmosphere.validate();
  if (!(mu_s > 0.0 && mu_s <= 1.0)) throw Error("plane-parallel reference: the sun must be above the horizon");
  if (options.streams < 2 || options.streams > 256)
    throw Error("plane-parallel reference: streams must be in [2, 256]");
  if (!(options.max_layer_optical_depth > 0.0) || !(options.max_layer_thickness_m > 0.0))
    throw Error("plane-parallel reference: layer limits must be positive");
  std::vector<double> mu, w;
  gauss_legendre(options.streams, 0.0, 1.0, mu, w);
  const int n = options.streams;
  const size_t wavelengths = atmosphere.wavelengths_nm.size();
  PlaneParallelFluxes out;
  out.upward_top.assign(wavelengths, 0.0);
  out.ground_direct.assign(wavelengths, 0.0);
  out.ground_diffuse.assign(wavelengths, 0.0);
  out.mu = mu;
  out.upward_radiance_top.assign(wavelengths, std::vector<double>(size_t(n), 0.0));
  out.downward_radiance_ground.assign(wavelengths, std::vector<double>(size_t(n), 0.0));
  tbb::parallel_for(size_t(0), wavelengths, [&](size_t l) {
    const double lambda = atmosphere.wavelengths_nm[l];
    const std::vector<Slice> slices = make_slices(atmosphere, lambda, options);
    std::vector<Kernel> kernels;
    for (const Constituent& c : atmosphere.constituents) kernels.push_back(azimuthal_kernel(c.phase, lambda, mu, mu_s));
    Layer stack;
    bool first = true;
    for (const Slice& slice : slices) {
      Kernel mixed{MatrixXd::Zero(n, n + 1), MatrixXd::Zero(n, n + 1)};
      for (size_t c = 0; c < kernels.size(); ++c) {
        mixed.same += slice.phase_weight[c] * kernels[c].same;
        mixed.opposite += slice.phase_weight[c] * kernels[c].opposite;
      }
      // Renormalise each incident column (energy conservation of the
      // discrete kernel).
      for (int j = 0; j <= n; ++j) {
        double sum = 0.0;
        for (int i = 0; i < n; ++i) sum += w[size_t(i)] * (mixed.same(i, j) + mixed.opposite(i, j));
        if (sum > 0.0) {
          mixed.same.col(j) /= sum;
          mixed.opposite.col(j) /= sum;
        }
      }
      const Layer layer = homogeneous_layer(slice.optical_depth, slice.omega, mixed, mu, w, mu_s);
      stack = first ? layer : add(stack, layer);
      first = false;
    }
    // The Lambertian ground: I_up = albedo / π · (flux down).
    const double albedo = atmosphere.ground_albedo.at(lambda);
    Layer ground;
    ground.r_top = MatrixXd(n, n);
    for (int i = 0; i < n; ++i)
      for (int j = 0; j < n; ++j) ground.r_top(i, j) = 2.0 * albedo * mu[size_t(j)] * w[size_t(j)];
    ground.r_bottom = MatrixXd::Zero(n, n);
    ground.t_down = MatrixXd::Zero(n, n);
    ground.t_up = MatrixXd::Zero(n, n);
    ground.beam_up = VectorXd::Constant(n, albedo * mu_s / kPi);
    ground.beam_down = VectorXd::Zero(n);
    ground.e = 0.0;
    // d: the diffuse light down at the ground, with the bounces between the
    // ground and the atmosphere.
    VectorXd d;
    const Layer whole = add(stack, ground, &d);
    const double sun = atmosphere.solar_irradiance.at(lambda);
    double diffuse = 0.0, upward = 0.0;
    for (int i = 0; i < n; ++i) {
      diffuse += 2.0 * kPi * mu[size_t(i)] * w[size_t(i)] * d(i);
      upward += 2.0 * kPi * mu[size_t(i)] * w[size_t(i)] * whole.beam_up(i);
      out.upward_radiance_top[l][size_t(i)] = sun * whole.beam_up(i);
      out.downward_radiance_ground[l][size_t(i)] = sun * d(i);
    }
    out.upward_top[l] = sun * upward;
    out.ground_direct[l] = sun * mu_s * stack.e;
    out.ground_diffuse[l] = sun * diffuse;
  });
  return out;
}

}  // namespace atmos
