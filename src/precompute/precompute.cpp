// The precomputation pipeline (seed 004 §4.2, Bruneton & Neyret 2008 §4):
// transmittance, direct irradiance and single scattering, then for each
// scattering order n = 2..K the scattering density of order n, the sky
// irradiance of order n - 1 and the multiple scattering of order n; with auto
// orders that reach the cap K, the orders after K summed at once (tail.cpp).
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <memory>
#include <string>

#include "atmos/colour.hpp"
#include "atmos/tables.hpp"
#include "physics/parameters.hpp"
#include "precompute/steps.hpp"

namespace atmos {

void TableSizes::validate() const {
  auto check = [](int value, int minimum, const char* name) {
    if (value < minimum || value > 4096)
      throw Error(std::string("table size ") + name + " = " + std::to_string(value) + " is outside [" +
                  std::to_string(minimum) + ", 4096]");
  };
  check(transmittance_mu, 4, "transmittance_mu");
  check(transmittance_r, 4, "transmittance_r");
  check(irradiance_mu_s, 4, "irradiance_mu_s");
  check(irradiance_r, 2, "irradiance_r");
  check(scattering_nu, 2, "scattering_nu");
  check(scattering_mu_s, 4, "scattering_mu_s");
  check(scattering_mu, 8, "scattering_mu");
  check(scattering_r, 2, "scattering_r");
  if (scattering_mu % 2 != 0) throw Error("table size scattering_mu must be even (half below, half above the horizon)");
  const double texels = double(scattering_nu) * scattering_mu_s * scattering_mu * scattering_r;
  if (texels > 64.0 * 1024 * 1024) throw Error("scattering tables of more than 64 Mi texels are not supported");
}

void check_tables_match(const Atmosphere& atmosphere, const Tables& tables) {
  tables.sizes.validate();
  if (tables.wavelengths_nm != atmosphere.wavelengths_nm)
    throw Error("the tables were not computed for the wavelengths of atmosphere '" + atmosphere.name + "'");
  const TableSizes& s = tables.sizes;
  const TableSet& t = tables.set;
  const size_t transmittance = size_t(s.transmittance_mu) * size_t(s.transmittance_r);
  const size_t irradiance = size_t(s.irradiance_mu_s) * size_t(s.irradiance_r);
  const size_t scattering =
      size_t(tables.scattering_width()) * size_t(tables.scattering_height()) * size_t(tables.scattering_depth());
  if (t.indirect_irradiance.size() != irradiance ||
      t.direct_irradiance.size() != irradiance || t.scattering.size() != scattering ||
      t.single_aerosol.size() != scattering || t.multiple_scattering.size() != scattering ||
      tables.spectral_optical_depth.size() != transmittance * size_t(tables.transmittance_tiles()))
    throw Error("the tables hold fewer or more texels than their sizes say");
  if (tables.spectral_sets() > SPECTRAL_SET_CAPACITY)
    throw Error("the tables have more wavelengths than the run time supports");
}

namespace {

// Fields kept by the tail solver between restarts (memory: 31 tables of the
// scattering table's size, 390 MB with the default sizes), of which 10 are
// carried over each restart (tail.cpp: the deflated restart).
constexpr int kTailRestart = 30;
constexpr int kTailDeflation = 10;

// Radiance summed over the texels of a scattering table, per channel of
// the set, with the phase function of each texel's nu tile for phase-free
// tables (`phase` 0: none, 1: Rayleigh, 2: aerosol). A measure of how much
// light an order adds, for auto orders and the convergence report.
glm::dvec3 channel_sums(const physics::AtmosphereParams& a, const precompute::Table3D& table, int phase) {
  return tbb::parallel_reduce(
      tbb::blocked_range<int>(0, table.depth), glm::dvec3(0.0),
      [&](const tbb::blocked_range<int>& slices, glm::dvec3 sum) {
        for (int z = slices.begin(); z != slices.end(); ++z)
          for (int y = 0; y < table.height; ++y)
            for (int x = 0; x < table.width; ++x) {
              const float nu = physics::scattering_texel_tile_nu(a, physics::vec3(float(x), float(y), float(z)));
              const glm::vec3 p = phase == 0   ? glm::vec3(1.0f)
                                  : phase == 1 ? glm::vec3(physics::rayleigh_phase_function(nu))
                                               : physics::aerosol_phase_function(a, nu);
              sum += glm::dvec3(table.at(x, y, z) * p);
            }
        return sum;
      },
      [](const glm::dvec3& x, const glm::dvec3& y) { return x + y; });
}

// The bottom row (r = bottom: the ground) of an irradiance table, summed
// over its sun angles, per channel.
glm::dvec3 ground_sums(const precompute::Table2D& irradiance) {
  glm::dvec3 sum(0.0);
  for (int x = 0; x < irradiance.width; ++x) sum += glm::dvec3(irradiance.at(x, 0));
  return sum;
}

// Whether a series of orders may stop after the order that added `added`
// (`previous` by the order before, 0 for the first) to a sum now `total`.
// The order must add less than `tolerance` of the sum (the criterion
// PrecomputeOptions states), and so must all the orders after it as far as
// they can be foreseen: where the orders decay geometrically with the ratio
// q = added / previous, the rest of the series adds q / (1 - q) times the
// last order. In a nearly conservative, optically thick medium q approaches
// 1 and the last order alone says little: on 100x Earth the 64th order
// still adds 0.975 of what the 63rd did, and stopping where one order added
// 0.1 % of the light (order 47) left out about 16 % of the light on the
// ground (measured against the reference). A ratio of 1 or more never
// converges (the cap and the tail solver take over).
bool series_converged(double added, double previous, double total, double tolerance) {
  const double bound = tolerance * std::abs(total);
  if (!(std::abs(added) <= bound)) return false;
  if (previous <= 0.0 || added <= 0.0) return true;
  const double q = added / previous;
  return q < 1.0 && added * q / (1.0 - q) <= bound;
}

// The same in every channel.
bool series_converged(const glm::dvec3& added, const glm::dvec3& previous, const glm::dvec3& total,
                      double tolerance) {
  for (int c = 0; c < 3; ++c)
    if (!series_converged(added[c], previous[c], total[c], tolerance)) return false;
  return true;
}

// Whether the series of series_converged() would still be short of its
// criterion after `orders_left` more orders, foreseen with the ratio q =
// added / previous of its last two orders (order m on adds added q^m). The
// forecast may err either way (the ratio of Venus's orders still grows after
// order 16; 10x Earth's sky light on the ground, with a tolerance of 1 %, is
// foreseen to outlast the cap at order 16 but converges at order 55); an
// error costs time, not light: the
// solver sums the same series (tests/spectral_test.cpp: 16 orders and the
// tail give 10x Earth the light of its 55 orders within 2e-4).
bool series_outlasts(double added, double previous, double total, double tolerance, int orders_left) {
  if (previous <= 0.0 || added <= 0.0) return false;
  const double q = added / previous;
  if (q >= 1.0) return true;
  // The order `orders_left` on, and the one before it, by the same ratio.
  const double later = added * std::pow(q, orders_left);
  return !series_converged(later, later / q, total, tolerance);
}

bool series_outlasts(const glm::dvec3& added, const glm::dvec3& previous, const glm::dvec3& total, double tolerance,
                     int orders_left) {
  for (int c = 0; c < 3; ++c)
    if (series_outlasts(added[c], previous[c], total[c], tolerance, orders_left)) return true;
  return false;
}

// With auto orders and the tail solver, the order from which a series that
// the forecast says would reach the cap unconverged is handed to the solver
// at once instead. Explicit orders are power iterations: after the first
// few, which carry the light's sharp features (the sunlit top, the sun's
// direction), they only work on the slow diffusion modes that the solver
// handles far better. Measured on Venus at the default sizes, three
// wavelengths (2026-11-26): 16 orders and the tail (105 solver steps) give
// the light on the ground and leaving the top within 1e-4 of 64 orders and
// the tail (115 steps), in 73 s instead of 135 s (12 orders: the same);
// tests/convergence_accuracy.cpp checks 16 orders and the tail against 600
// orders. Titan hands off at 16 too (its tail: 11 steps with the small
// tables of tests/presets_test.cpp).
constexpr int kEarliestTailHandoff = 16;

}  // namespace

Tables precompute_tables(const Atmosphere& atmosphere, const PrecomputeOptions& options) {
  using namespace precompute;
  using clock = std::chrono::steady_clock;
  atmosphere.validate();
  options.sizes.validate();
  const int K = options.scattering_orders;
  if (K < 1 || K > 100) throw Error("scattering orders must be in [1, 100], got " + std::to_string(K));
  if (options.auto_orders && !(options.auto_orders_tolerance > 0.0 && options.auto_orders_tolerance < 1.0))
    throw Error("the tolerance of auto orders must be in (0, 1)");
  const bool may_solve_tail = options.auto_orders && options.solve_tail;
  if (may_solve_tail && !(options.tail_tolerance > 0.0 && options.tail_tolerance < 1.0))
    throw Error("the tolerance of the tail solver must be in (0, 1)");
  if (may_solve_tail && (options.tail_iterations < 1 || options.tail_iterations > 1000))
    throw Error("the tail solver's iterations must be in [1, 1000], got " + std::to_string(options.tail_iterations));
  const std::vector<double>& wavelengths = atmosphere.wavelengths_nm;
  const int set_count = physics::spectral_set_count(wavelengths);
  if (set_count > SPECTRAL_SET_CAPACITY)
    throw Error("at most " + std::to_string(3 * SPECTRAL_SET_CAPACITY) + " working wavelengths are supported, got " +
                std::to_string(wavelengths.size()));
  const bool srgb = physics::srgb_channels(wavelengths);

  Tables tables;
  tables.sizes = options.sizes;
  tables.scattering_orders = 1;
  tables.wavelengths_nm = wavelengths;

  // Relative cost of the steps, for the progress fraction (with auto orders,
  // the estimate assumes the cap and a tail solved in all its iterations, and
  // the bar jumps at the end).
  const double cost_single = 1.0, cost_order = 1.6;
  const double cost_tail = may_solve_tail ? cost_order * options.tail_iterations : 0.0;
  const double cost_set = 0.05 + cost_single + cost_order * (K - 1) + cost_tail;
  const double cost_total = cost_set * set_count;
  double cost_done = 0.0;
  auto report = [&](const std::string& step, double step_cost, double fraction) {
    if (options.progress) options.progress(step, std::min(1.0, (cost_done + step_cost * fraction) / cost_total));
  };

  auto timed = [&](const std::string& name, double step_cost, auto&& body) {
    const auto start = clock::now();
    report(name, step_cost, 0.0);
    body([&](double f) { report(name, step_cost, f); });
    cost_done += step_cost;
    report(name, 0.0, 0.0);
    const double seconds = std::chrono::duration<double>(clock::now() - start).count();
    // Steps of all sets and orders add up under one name.
    for (auto& t : tables.timings)
      if (t.name == name) {
        t.seconds += seconds;
        return;
      }
    tables.timings.push_back({name, seconds});
  };

  // The render tables accumulate every set's tables in the channels (see
  // physics/definitions.glsl); the transmittance stays per set (the spectral
  // optical depth, which channel_transmittance weights at run time).
  TableSet& out = tables.set;
  const glm::vec3 luminance_of_srgb(0.2126f, 0.7152f, 0.0722f);
  const glm::mat3 to_srgb = physics::channels_to_srgb_matrix(wavelengths);
  // Per set, the light each order added and the light gathered up to it
  // (index order - 2), for the convergence report; and what the tail solver
  // added, in how many steps, with what residual.
  std::vector<std::vector<double>> set_added, set_total;
  std::vector<OrderContribution> set_tail(static_cast<size_t>(set_count));
  std::vector<double> set_total_before_tail(static_cast<size_t>(set_count), 0.0);
  // (With three wavelengths the one set is the render tables: moved, not converted.)
  auto accumulate = [&](std::vector<glm::vec3>& sum, std::vector<glm::vec3>& texels, const glm::mat3& m) {
    if (!srgb) {
      sum = std::move(texels);
      return;
    }
    if (sum.empty()) sum.assign(texels.size(), glm::vec3(0.0f));
    tbb::parallel_for(tbb::blocked_range<size_t>(0, texels.size()), [&](const tbb::blocked_range<size_t>& range) {
      for (size_t i = range.begin(); i != range.end(); ++i) sum[i] += m * texels[i];
    });
  };

  // The single aerosol table of sRGB channels. The run time multiplies its
  // value by the channel's aerosol phase function P_c (the render params',
  // make_render_params), but the phase function may change with wavelength
  // inside a channel (dust's forward lobe narrows towards the blue). So each
  // texel holds, for channel c,
  //   Σ_λ M_cλ S_λ P_λ(nu) / P_c(nu),
  // S_λ the phase-free single aerosol scattering at wavelength λ, M the
  // conversion to the channels, P_λ that wavelength's phase function: the
  // product at run time is then exact at the table's nu samples and
  // interpolated between them. nu is the texel's tile nu, as for the division
  // by the Rayleigh phase function in add_to_multiple (the run-time
  // interpolation between tiles weights them by their tile nu). With three
  // wavelengths P_λ = P_c and the table stays phase-free (untouched).
  // The tile nu depends on the texel's nu index only (x / mu_s size): the
  // phase functions are evaluated once per tile.
  const AtmosphereParams render = physics::make_render_params(atmosphere, options.sizes);
  auto tile_phases = [&](const AtmosphereParams& params) {
    std::vector<glm::vec3> phases;
    for (int i = 0; i < options.sizes.scattering_nu; ++i)
      phases.push_back(physics::aerosol_phase_function(
          params, physics::scattering_texel_tile_nu(params, physics::vec3(float(i * options.sizes.scattering_mu_s), 0.0f,
                                                                           0.0f))));
    return phases;
  };

  for (int set = 0; set < set_count; ++set) {
    const AtmosphereParams a = physics::make_atmosphere_params(atmosphere, options.sizes, set);
    const glm::mat3 to_channels = physics::set_to_channels(wavelengths, set);
    // Luminance per unit of this set's radiance at each of its wavelengths.
    const glm::vec3 luminance = glm::transpose(to_srgb * to_channels) * luminance_of_srgb;
    Table2D transmittance, direct_irradiance, indirect_irradiance(a.irradiance_mu_s_size, a.irradiance_r_size);
    Table2D delta_irradiance;
    Table3D single_rayleigh, single_aerosol, delta_multiple, density;

    timed("transmittance", 0.03, [&](auto&&) { transmittance = compute_transmittance_table(a); });
    timed("direct_irradiance", 0.02, [&](auto&&) {
      direct_irradiance = compute_direct_irradiance_table(a, transmittance);
    });
    // The orders >= 2 run in the delta-M scaled medium when the aerosol has a
    // forward lobe too sharp for the tables (physics/parameters.hpp,
    // delta_scaled_params): their own transmittance and single scattering
    // (the source of order 2), the scaled phase function in the densities.
    // The light the scaled medium carries in the δ is the part of the direct
    // beam that is really scattered within a few degrees of the sun: on the
    // ground it is sky light, E (T* - T) mu_s, added to the sky irradiance
    // (so the ground receives what the scaled medium transmits).
    vec3 forward_fraction;
    const AtmosphereParams ms = physics::delta_scaled_params(a, forward_fraction);
    const bool scaled = forward_fraction.x > 0.0f || forward_fraction.y > 0.0f || forward_fraction.z > 0.0f;
    Table2D scaled_transmittance;
    Table3D scaled_single_rayleigh, scaled_single_aerosol;
    if (scaled)
      timed("delta_m_transmittance", 0.05, [&](auto&&) {
        scaled_transmittance = compute_transmittance_table(ms);
        const Table2D scaled_direct = compute_direct_irradiance_table(ms, scaled_transmittance);
        for (size_t i = 0; i < indirect_irradiance.texels.size(); ++i)
          indirect_irradiance.texels[i] += max(scaled_direct.texels[i] - direct_irradiance.texels[i], vec3(0.0f));
      });
    const Table2D& ms_transmittance = scaled ? scaled_transmittance : transmittance;
    // The single scattering the run time adds, with the true phase functions
    // and medium, receives its sunlight through the scaled medium
    // (single_scattering_tile in definitions.glsl): the sunlight scattered
    // into the forward peak on its way to the scattering point still arrives
    // there, within a few degrees of the sun's direction, and the orders >= 2
    // of the scaled medium do not carry it. Nakajima & Tanaka (1988) also
    // scale the view ray's extinction; measured on the "mars" dust against
    // the reference (tests/mars_accuracy.cpp), that is better by day (4.3 %
    // against 9.4 % RMS beyond 20° of the sun at 60° up) but doubles the
    // blue of the glow around the setting sun (blue / red 2.5 against the
    // reference's 1.3, here 1.6) and makes the long view rays near the
    // horizon brighter still (tests/phase_spectrum_test.cpp: 25 % against
    // 15 % RMS); the true extinction is kept along view rays. The scaled
    // medium's own single scattering (the source of its order 2) comes from
    // the same pass.
    timed("single_scattering", cost_single, [&](auto&& progress) {
      if (scaled)
        compute_single_scattering_tables(a, ms_transmittance, single_rayleigh, single_aerosol, progress, ms,
                                         scaled_single_rayleigh, scaled_single_aerosol);
      else
        compute_single_scattering_tables(a, transmittance, single_rayleigh, single_aerosol, progress);
    });
    const Table3D& ms_single_rayleigh = scaled ? scaled_single_rayleigh : single_rayleigh;
    const Table3D& ms_single_aerosol = scaled ? scaled_single_aerosol : single_aerosol;

    Table3D multiple(single_rayleigh.width, single_rayleigh.height, single_rayleigh.depth);
    delta_multiple = Table3D(single_rayleigh.width, single_rayleigh.height, single_rayleigh.depth);
    // The light gathered so far and what the last order added, per channel,
    // in the whole scattering table and in the sky light on the ground (the
    // irradiance row at r = bottom), for auto orders (`series_converged`).
    // The convergence report and the check that the orders decrease use
    // their luminance over the whole table.
    const glm::dvec3 to_luminance(luminance);
    glm::dvec3 channels_total = channel_sums(a, single_rayleigh, 1) + channel_sums(a, single_aerosol, 2);
    glm::dvec3 channels_previous(0.0);
    glm::dvec3 ground_total = ground_sums(indirect_irradiance), ground_previous(0.0);
    // What the orders of this set share (view rays, density quadrature).
    std::shared_ptr<const OrderGeometry> geometry;
    // Adds the radiance of orders to `multiple`, stored divided by the
    // Rayleigh phase function so that one lookup and one phase function at
    // run time give single Rayleigh + all multiple (the `scattering` table
    // below). The division uses the nu of the texel's tile, not the clamped nu
    // the texel was computed for: the run-time interpolation between tiles
    // weights them by their tile nu, and a clamped nu there makes M / P_R
    // jump between neighbours (17 % errors in the second order towards the
    // sun, measured against the reference).
    auto add_to_multiple = [&](const Table3D& radiance) {
      tbb::parallel_for(0, multiple.depth, [&](int z) {
        for (int y = 0; y < multiple.height; ++y)
          for (int x = 0; x < multiple.width; ++x) {
            const float tile_nu = physics::scattering_texel_tile_nu(a, vec3(float(x), float(y), float(z)));
            multiple.at(x, y, z) += radiance.at(x, y, z) / physics::rayleigh_phase_function(tile_nu);
          }
      });
    };
    bool converged = false;
    int last_order = K;  // the last explicit order (before the tail)

    for (int order = 2; order <= K; ++order) {
      timed("scattering_density", cost_order * 0.45, [&](auto&& progress) {
        if (!geometry) geometry = make_order_geometry(ms);
        compute_scattering_density_table(ms, *geometry, ms_transmittance, ms_single_rayleigh, ms_single_aerosol,
                                         delta_multiple, delta_irradiance, order - 1, progress, density);
      });
      timed("indirect_irradiance", cost_order * 0.05, [&](auto&&) {
        delta_irradiance = compute_indirect_irradiance_table(ms, ms_transmittance, ms_single_rayleigh,
                                                             ms_single_aerosol, delta_multiple, order - 1);
        for (size_t i = 0; i < indirect_irradiance.texels.size(); ++i)
          indirect_irradiance.texels[i] += delta_irradiance.texels[i];
      });
      timed("multiple_scattering", cost_order * 0.5, [&](auto&& progress) {
        compute_multiple_scattering_table(ms, *geometry, density, progress, delta_multiple);
        // In optically thick atmospheres the source is read between radius
        // rows with cubic weights (source_function_lookup), which undershoot
        // next to sharp features of the source: a few texels of an order can
        // come out slightly negative (100x the dusty Mars: -0.6 % of the
        // table's largest value). Light is not negative. (The tail solver's
        // signed fields are not clamped: its operator must stay linear.)
        for (vec3& v : delta_multiple.texels) v = max(v, vec3(0.0f));
        add_to_multiple(delta_multiple);
      });
      const glm::dvec3 channels_added = channel_sums(a, delta_multiple, 0);
      const double added = glm::dot(to_luminance, channels_added);
      // Each order of a physical atmosphere adds less light than the one
      // before (some escapes to space or is absorbed). An order that adds
      // more means that the tables' discretisation creates energy (too dense
      // a medium for the table resolution: before the quadrature followed the
      // visible extinction, 30x Earth did from order 12). Refuse rather than
      // return tables that grow without bound.
      if (order > 2 && added > glm::dot(to_luminance, channels_previous) * (1.0 + 1e-6) && added > 0.0)
        throw Error(atmosphere.origin + ": scattering order " + std::to_string(order) +
                    " adds more light than order " + std::to_string(order - 1) +
                    ": the tables cannot represent an atmosphere this dense (wavelengths " +
                    std::to_string(int(physics::set_wavelengths(wavelengths, set)[0])) + "-" +
                    std::to_string(int(physics::set_wavelengths(wavelengths, set)[2])) +
                    " nm); use fewer orders, a lower --density-scale or larger tables");
      // The sky light on the ground of this step is order - 1's (from the
      // radiance of order - 1).
      const glm::dvec3 ground_added = ground_sums(delta_irradiance);
      channels_total += channels_added;
      ground_total += ground_added;
      const bool all_converged =
          series_converged(channels_added, channels_previous, channels_total, options.auto_orders_tolerance);
      const bool ground_converged =
          series_converged(ground_added, ground_previous, ground_total, options.auto_orders_tolerance);
      // Hand the rest to the tail solver now (kEarliestTailHandoff)?
      const bool hand_off =
          may_solve_tail && order == kEarliestTailHandoff && order < K &&
          (series_outlasts(channels_added, channels_previous, channels_total, options.auto_orders_tolerance,
                           K - order) ||
           series_outlasts(ground_added, ground_previous, ground_total, options.auto_orders_tolerance, K - order));
      channels_previous = channels_added;
      ground_previous = ground_added;
      const double total = glm::dot(to_luminance, channels_total);
      set_added.resize(size_t(set) + 1);
      set_total.resize(size_t(set) + 1);
      set_added[size_t(set)].push_back(added);
      set_total[size_t(set)].push_back(total);
      tables.scattering_orders = std::max(tables.scattering_orders, order);
      if (options.auto_orders && all_converged && ground_converged) {
        cost_done += cost_order * (K - order) + cost_tail;
        converged = true;
        break;
      }
      if (hand_off) {
        cost_done += cost_order * (K - order);
        last_order = order;
        break;
      }
    }

    // The cap is reached, or foreseen (kEarliestTailHandoff), and the orders
    // still add light: solve for the rest of the series (see tail.cpp), from
    // order last_order + 1, computed as the orders are (for K = 1, from the
    // single scattering).
    if (may_solve_tail && !converged) {
      timed("tail", cost_tail, [&](auto&& progress) {
        if (!geometry) geometry = make_order_geometry(ms);
        compute_scattering_density_table(ms, *geometry, ms_transmittance, ms_single_rayleigh, ms_single_aerosol,
                                         delta_multiple, delta_irradiance, last_order, nullptr, density);
        const Table2D next_irradiance = compute_indirect_irradiance_table(ms, ms_transmittance, ms_single_rayleigh,
                                                                          ms_single_aerosol, delta_multiple, last_order);
        Table3D next_radiance;
        compute_multiple_scattering_table(ms, *geometry, density, nullptr, next_radiance);
        density = Table3D();
        delta_multiple = Table3D();
        const ScatteringTail tail =
            solve_scattering_tail(ms, *geometry, ms_transmittance, next_radiance, next_irradiance,
                                  options.tail_tolerance, options.tail_iterations, kTailRestart, kTailDeflation,
                                  progress);
        add_to_multiple(tail.radiance);
        for (size_t i = 0; i < indirect_irradiance.texels.size(); ++i)
          indirect_irradiance.texels[i] += tail.irradiance.texels[i];
        // The solver's combination of signed fields can leave texels of
        // almost no light slightly below zero.
        for (auto* texels : {&multiple.texels, &indirect_irradiance.texels})
          for (vec3& v : *texels) v = max(v, vec3(0.0f));
        OrderContribution& c = set_tail[size_t(set)];
        c.tail = true;
        c.order = last_order + 1;
        c.added = glm::dot(to_luminance, channel_sums(a, tail.radiance, 0));
        c.iterations = tail.iterations;
        c.residual = std::max({tail.relative_residual.x, tail.relative_residual.y, tail.relative_residual.z});
        set_total_before_tail[size_t(set)] = glm::dot(to_luminance, channels_total);
      });
    }

    Table3D scattering = single_rayleigh;
    for (size_t i = 0; i < scattering.texels.size(); ++i) scattering.texels[i] += multiple.texels[i];

    accumulate(out.direct_irradiance, direct_irradiance.texels, to_channels);
    accumulate(out.indirect_irradiance, indirect_irradiance.texels, to_channels);
    accumulate(out.scattering, scattering.texels, to_channels);
    if (srgb) {
      // The phase ratio (see below): this set's phase function, per
      // wavelength, before the conversion to the channels. The set's own
      // table stays phase-free (its orders are done).
      const std::vector<glm::vec3> phases = tile_phases(a);
      tbb::parallel_for(0, single_aerosol.depth, [&](int z) {
        for (int y = 0; y < single_aerosol.height; ++y)
          for (int x = 0; x < single_aerosol.width; ++x)
            single_aerosol.at(x, y, z) *= phases[size_t(x / a.scattering_mu_s_size)];
      });
    }
    accumulate(out.single_aerosol, single_aerosol.texels, to_channels);
    accumulate(out.multiple_scattering, multiple.texels, to_channels);
    // Triple `set` is tile `set` of the spectral optical depth, and its
    // scaled medium tile set_count + set (rows of 2 set_count tiles side by side).
    const int w = transmittance.width, h = transmittance.height, tiles = 2 * set_count;
    if (tables.spectral_optical_depth.empty())
      tables.spectral_optical_depth.assign(size_t(w) * size_t(h) * size_t(tiles), glm::vec3(0.0f));
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        const size_t row = size_t(y) * size_t(w) * size_t(tiles) + size_t(x);
        tables.spectral_optical_depth[row + size_t(set) * size_t(w)] = transmittance.at(x, y);
        tables.spectral_optical_depth[row + size_t(set_count + set) * size_t(w)] =
            ms_transmittance.texels[size_t(y) * size_t(w) + size_t(x)];
      }
  }
  if (srgb) {
    const int width = options.sizes.scattering_nu * options.sizes.scattering_mu_s;
    const int height = options.sizes.scattering_mu, depth = options.sizes.scattering_r;
    const std::vector<glm::vec3> phases = tile_phases(render);
    tbb::parallel_for(0, depth, [&](int z) {
      for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x)
          out.single_aerosol[(size_t(z) * size_t(height) + size_t(y)) * size_t(width) + size_t(x)] /=
              phases[size_t(x / options.sizes.scattering_mu_s)];
    });
  }
  // Order n over all sets; a set that stopped earlier (auto orders) adds
  // nothing more but its light still counts in the total.
  for (int order = 2; order <= tables.scattering_orders; ++order) {
    double added = 0.0, total = 0.0;
    for (size_t k = 0; k < set_added.size(); ++k) {
      const size_t n = set_added[k].size();
      if (n == 0) continue;
      const size_t i = std::min(size_t(order - 2), n - 1);
      if (size_t(order - 2) < n) added += set_added[k][i];
      total += set_total[k][i];
    }
    tables.convergence.push_back({order, added, total != 0.0 ? added / total : 0.0});
  }
  // The tail, over the sets that solved one (each set's light counts in the total).
  OrderContribution tail;
  double total = 0.0;
  for (size_t k = 0; k < set_tail.size(); ++k) {
    const OrderContribution& c = set_tail[k];
    if (c.tail) {
      tail.tail = true;
      tail.order = std::max(tail.order, c.order);
      tail.added += c.added;
      tail.iterations = std::max(tail.iterations, c.iterations);
      tail.residual = std::max(tail.residual, c.residual);
      total += set_total_before_tail[k] + c.added;
    } else if (k < set_total.size() && !set_total[k].empty()) {
      total += set_total[k].back();
    }
  }
  if (tail.tail) {
    tail.relative = total != 0.0 ? tail.added / total : 0.0;
    tables.convergence.push_back(tail);
  }
  return tables;
}

}  // namespace atmos
