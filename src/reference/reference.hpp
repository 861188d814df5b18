// atmos — an independent, brute-force Monte Carlo reference for the sky.
//
// This is the yardstick the precomputed tables are tested against. It shares
// nothing with the table code: it reads only the description `Atmosphere`
// (spectra, density profiles, phase functions, radii, albedo, sun) and does
// its own ray–sphere geometry, optical depth quadrature, phase function
// evaluation and sampling, all in double precision. It is slow and simple on
// purpose; every function in src/reference/reference.cpp states the equation
// it implements.
//
// Model (all SI: metres, m^-1, radians):
//  - spherical planet of radius Rb (bottom_radius_m), atmosphere up to Rt
//    (top_radius_m); nothing above Rt (density profiles are cut there);
//  - constituent i: scattering β_s,i(λ)·ρ_i(h), absorption β_a,i(λ)·ρ_i(h),
//    phase function p_i (Rayleigh, Henyey–Greenstein, Cornette–Shanks);
//  - Lambertian ground of albedo a(λ);
//  - sun: disc of angular radius α around direction `sun`, whose
//    irradiance at normal incidence at the top of the atmosphere is
//    E_sun(λ). Its radiance follows the linear limb-darkening law
//      L(θ) = L_0 (1 - u (1 - μ)),  μ = √(1 - sin²θ / sin²α),
//    θ the angle from the disc centre, u = sun_limb_darkening_u in [0, 1],
//    L_0 = E_sun / (π sin²α (1 - u/3)) (u = 0: the uniform disc of radiance
//    E_sun / (π sin²α));
//  - moons (ReferenceOptions::moons, at most 8): opaque black spheres outside
//    the atmosphere that block sunlight (solar eclipses). They only shadow:
//    a direction towards the sun disc that meets a moon carries no sunlight.
//    They are not themselves seen (they neither reflect nor hide the
//    atmosphere from an observer or point outside it).
//
// Sunlight enters only through next-event estimation: at every vertex (and at
// the point of an irradiance) one direction ω is drawn uniformly in the solid
// angle of the disc and weighted by V_moons(ω) I(μ)/⟨I⟩ (V_moons = 0 if the
// ray towards ω meets a moon, else 1; I(μ) = 1 - u (1 - μ); ⟨I⟩ = 1 - u/3, the
// exact cos θ-weighted mean of I over the sampled cap; see reference.cpp,
// sample_sun, blocked_by_moon and sun_weight), which estimates the partially
// eclipsed, limb-darkened disc without bias; the planet's own shadow is exact
// in the same way.
//
// Interactions: one atmospheric scattering event or one ground reflection.
// With `scattering_orders` = K the reference counts the light that underwent
// at most K interactions between the sun and the eye (order 1 = sun → scatter
// → eye and sun → ground → eye). The direct view of the sun disc is never
// included in a radiance.
//
// Cost (Earth preset, defaults K = 4 and 20000 paths, on the 2-core CI
// machine): about 0.3 core-seconds per radiance direction, with relative
// standard errors of 0.2–0.8 % by day, ~1–3 % with the sun 2.5° below the
// horizon and ~2–8 % at 5° below (the error scales as 1/√paths).
//
// Wavelengths share their paths: a distance is drawn for one of them and
// every other is weighted by the ratio of its density to the mixture's (see
// reference.cpp). That is unbiased, but where the light has been scattered
// hundreds of times and the wavelengths' optical depths differ a lot, the
// weights multiply into a distribution so skewed that a finite run usually
// falls far below the mean, and the standard error does not show it: on
// 100x Earth's air alone (3.6 / 9.7 / 24 optical depths at 680 / 550 /
// 440 nm) 200000 paths gave 6.5e-5 ± 3.4e-5 of the sunlight on the ground
// at 440 nm, against 0.052 ± 2 % with the three wavelengths within 0.02 nm
// of 440 nm. In optically thick atmospheres (Venus, dense scalings of Earth)
// compute one wavelength at a time, as a triple a fraction of a nanometre
// wide (tests/venus_accuracy.cpp, tests/dense_ground_accuracy.cpp).
//
// Random numbers: path i of a call uses a stream seeded from (seed, i) only,
// so results are bitwise repeatable (independent of the number of threads),
// and calls with the same seed for different directions use common random
// numbers (their errors are correlated; pass different seeds for independent
// errors).
#pragma once

#include <glm/vec3.hpp>

#include <cstdint>
#include <vector>

#include "atmos/atmosphere.hpp"

namespace atmos {

// A moon: an opaque black sphere of radius `radius` (m) centred at `centre`
// (planet-centred, m). It blocks the sunlight of every sun direction ω sampled
// from a point o for which the ray o + t ω meets the sphere at some t > 0.
struct ReferenceMoon {
  glm::dvec3 centre{0.0};
  double radius = 0.0;
};

struct ReferenceOptions {
  int scattering_orders = 4;  // K >= 1: maximum number of interactions counted
  int paths = 20000;          // Monte Carlo paths per estimate (>= 2), first dimension stratified
  std::uint64_t seed = 1;     // the same seed gives bitwise identical results
  // Solar eclipses: at most 8 moons, each with a finite centre, a finite
  // radius > 0 and entirely outside the atmosphere (|centre| - radius > Rt);
  // otherwise the estimators throw Error. Empty: no eclipse.
  std::vector<ReferenceMoon> moons;
  // u of the linear limb-darkening law I(μ) = 1 - u (1 - μ) of the sun disc
  // (relative to its centre), in [0, 1] (else Error). The disc's irradiance at
  // normal incidence stays E_sun for every u. 0: uniform disc; with no moons
  // and u = 0 the results are bitwise those of the reference without eclipses.
  double sun_limb_darkening_u = 0.0;
};

struct ReferenceResult {
  // One value per working wavelength (atmosphere.wavelengths_nm, same order).
  // reference_radiance: spectral radiance, W m^-2 sr^-1 nm^-1.
  // reference_*irradiance: spectral irradiance, W m^-2 nm^-1 (same field).
  std::vector<double> radiance;
  // Monte Carlo standard error of the mean, same units, per wavelength. It is
  // computed as if the paths were independent, which overestimates the error
  // of the stratified estimator slightly (conservative).
  std::vector<double> standard_error;
};

// Radiance arriving at `observer` (planet-centred position, m) from the view
// direction `view` (unit vector: the radiance seen "looking along view"), with
// the sun in direction `sun` (unit vector). The observer may be inside the
// atmosphere (at or above the ground) or outside it (the ray then starts where
// it enters the top boundary; a ray missing the atmosphere gives 0). If the
// view ray hits the ground, the radiance reflected by the ground (lit by sun
// and sky) attenuated to the observer is included. Throws Error for an
// invalid atmosphere or options, non-unit directions, or an observer below the
// ground.
ReferenceResult reference_radiance(const Atmosphere& atmosphere, const glm::dvec3& observer, const glm::dvec3& view,
                                   const glm::dvec3& sun, const ReferenceOptions& options);

// Irradiance on a small flat surface at `point` (m) facing `normal` (unit
// vector): E = ∫_{ω·n>0} L_in(ω) (ω·n) dω, sun disc plus sky, where the light
// counted underwent at most K-1 interactions, so that a(λ)/π · E is the
// ground radiance of orders <= K: K = 1 gives the direct sun only (attenuated,
// with partial visibility of the disc), K = 2 adds single scattered skylight,
// etc. With normal pointing down at the top of the atmosphere it is the
// upward flux leaving the atmosphere.
ReferenceResult reference_irradiance(const Atmosphere& atmosphere, const glm::dvec3& point, const glm::dvec3& normal,
                                     const glm::dvec3& sun, const ReferenceOptions& options);

// reference_irradiance with the normal = local vertical (point / |point|); at
// a ground point this is the irradiance that lights the Lambertian ground.
ReferenceResult reference_horizontal_irradiance(const Atmosphere& atmosphere, const glm::dvec3& point,
                                                const glm::dvec3& sun, const ReferenceOptions& options);

// Radiance arriving at `observer` (m) from the straight segment between the
// observer and `point` (m): the light scattered towards the observer by the
// atmosphere between them, with at most K interactions, as
// reference_radiance counts them (the first interaction on the segment,
// later ones anywhere, the ground included). The light of the point itself
// (a surface there, or the atmosphere beyond it) is NOT included: this is
// the in-scatter of aerial perspective, to be added to the point's own
// radiance times reference_transmittance(observer, point). Only the part of
// the segment inside the atmosphere counts (an observer outside starts
// where the segment enters it). observer == point gives 0. Throws Error as
// reference_radiance does, and if the point is below the ground or the
// segment passes below it (by more than 1 mm).
ReferenceResult reference_radiance_to_point(const Atmosphere& atmosphere, const glm::dvec3& observer,
                                            const glm::dvec3& point, const glm::dvec3& sun,
                                            const ReferenceOptions& options);

// Transmittance exp(-τ(λ)) of the straight segment from `from` to `to` (m),
// one value per working wavelength (τ as reference_detail::optical_depth:
// only the part inside the atmosphere counts). Deterministic (quadrature).
// Throws Error if the segment passes below the ground by more than 1 mm.
std::vector<double> reference_transmittance(const Atmosphere& atmosphere, const glm::dvec3& from,
                                            const glm::dvec3& to);

// A second, deterministic reference for the fluxes of optically thick
// atmospheres (src/reference/plane_parallel.cpp): the atmosphere as a
// plane-parallel slab (no curvature; sun zenith cosine mu_s > 0 everywhere),
// solved for the azimuthal mean of the radiance by adding-doubling, exact up
// to its quadratures: `streams` Gauss directions per hemisphere and layers
// of at most `max_layer_optical_depth` and `max_layer_thickness_m`. Where the
// Monte Carlo reference has a few percent of noise after minutes (Venus:
// paths of thousands of interactions), this gives the fluxes to ~1e-4 in
// seconds. Shares nothing with the table code; the phase functions are
// reference_detail::phase_function. Per working wavelength, W m^-2 nm^-1:
//  - upward_top: the flux leaving the top of the atmosphere (sun at
//    normal-incidence irradiance E_sun);
//  - ground_direct: the unscattered sunlight on a horizontal ground,
//    E_sun mu_s exp(-tau / mu_s);
//  - ground_diffuse: the sky light on it (all orders, the light the ground
//    reflects back to the sky and down again included);
//  - upward_radiance_top[l][i], downward_radiance_ground[l][i]: the
//    azimuthal means of the diffuse radiance leaving the top upwards and
//    reaching the ground from above, W m^-2 sr^-1 nm^-1, at zenith cosines
//    mu[i] (the Gauss nodes on (0, 1], increasing).
// Valid against a spherical planet where the sun is well above the horizon
// and the atmosphere thin against the radius. Throws Error for an invalid
// atmosphere, mu_s outside (0, 1] or bad options.
struct PlaneParallelOptions {
  int streams = 32;
  double max_layer_optical_depth = 0.05;
  double max_layer_thickness_m = 500.0;
};
struct PlaneParallelFluxes {
  std::vector<double> upward_top, ground_direct, ground_diffuse;
  std::vector<double> mu;
  std::vector<std::vector<double>> upward_radiance_top, downward_radiance_ground;
};
PlaneParallelFluxes reference_plane_parallel_fluxes(const Atmosphere& atmosphere, double mu_s,
                                                    const PlaneParallelOptions& options = {});

}  // namespace atmos
