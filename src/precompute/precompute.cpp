// The precomputation pipeline (Bruneton & Neyret 2008, §4; Elek & Kmoch
// 2010, §4.2), one wavelength triple at a time: the transmittance and the
// direct irradiance, the single scattering, then the scattering orders
// n = 2..K (the scattering density of order n, the sky irradiance of order
// n - 1 and the multiple scattering of order n), with auto orders the tail of
// the series solved for at once (tail.cpp); then the render tables, every
// triple converted to the channels and summed, and the convergence report.
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "atmos/colour.hpp"
#include "atmos/tables.hpp"
#include "physics/parameters.hpp"
#include "physics/precomputation_integrands_cpp.hpp"
#include "precompute/ground_albedo.hpp"
#include "precompute/steps.hpp"

namespace atmos {

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
  const GroundAlbedoResponse& g = tables.ground_response;
  if (!g.empty() && (g.indirect_irradiance.size() != irradiance || g.scattering.size() != scattering ||
                     g.multiple_scattering.size() != scattering))
    throw Error("the tables' ground albedo response holds fewer or more texels than their sizes say");
  if (tables.spectral_sets() > SPECTRAL_SET_CAPACITY)
    throw Error("the tables have more wavelengths than the run time supports");
}

namespace {

using namespace precompute;

// Fields kept by the tail solver between restarts (memory: 31 tables of the
// scattering table's size, 390 MB with the default sizes), of which 10 are
// carried over each restart (tail.cpp: the deflated restart).
constexpr int kTailRestart = 30;
constexpr int kTailDeflation = 10;

// With auto orders and the tail solver, the order from which a series that
// the forecast (series_outlasts) says would reach the cap unconverged is
// handed to the solver at once. Explicit orders are a power iteration: after
// the first few, which carry the light's sharp features (the sunlit top, the
// sun's direction), they only work on the slow diffusion modes that the
// solver reduces far faster (tail.cpp). On Venus, 16 orders and the tail give
// the light on the ground and leaving the top within 1e-4 of 64 orders and
// the tail; tests/convergence_accuracy.cpp checks 16 orders and the tail
// against 600 orders.
constexpr int kEarliestTailHandoff = 16;

// The least difference between the ground albedos of Tables::set and of the
// ground response per channel: the series' G per texel is the difference of
// the two tables divided by that of their albedo terms.
constexpr float kLeastResponseAlbedoDifference = 0.25f;

// --- Checks -----------------------------------------------------------------

// Throws Error for an atmosphere, table sizes or options the precomputation
// cannot use; returns the number of wavelength triples.
int checked_set_count(const Atmosphere& atmosphere, const PrecomputeOptions& options) {
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
  return set_count;
}

// --- Progress and timings ---------------------------------------------------

// The relative cost of the steps of one wavelength triple, for the progress
// fraction. With auto orders it assumes the cap and a tail solved in all its
// iterations; orders and a tail that are not needed are counted as done
// when the series stops (the progress jumps).
struct StepCosts {
  double single = 1.0;  // the single scattering
  double order = 1.6;   // one scattering order: density 0.45, sky irradiance 0.05, multiple scattering 0.5
  double tail = 0.0;    // the tail solver, at most tail_iterations steps of about one order's cost
  double set = 0.0;     // all the steps of one triple

  StepCosts(const PrecomputeOptions& options, bool may_solve_tail) {
    tail = may_solve_tail ? order * options.tail_iterations : 0.0;
    set = 0.05 + single + order * (options.scattering_orders - 1) + tail;
    // The second ground albedo's orders and tail (ground_albedo_response).
    if (options.ground_albedo_response) set += order * (options.scattering_orders - 1) + tail;
  }
};

// Runs the named steps of the precomputation: reports their progress to
// PrecomputeOptions::progress as the fraction of the whole precomputation's
// cost done, and adds their time to Tables::timings (the steps of all triples
// and orders add up under one name).
class StepRunner {
 public:
  StepRunner(const PrecomputeOptions& options, double total_cost, std::vector<StepTiming>& timings)
      : progress_(options.progress), total_(total_cost), timings_(timings) {}

  // Runs body(progress) as the step `name`, of relative cost `cost`;
  // progress(f) reports the fraction f of the step done.
  template <class Body>
  void run(const std::string& name, double cost, Body&& body) {
    using clock = std::chrono::steady_clock;
    const auto start = clock::now();
    report(name, cost, 0.0);
    body([&](double f) { report(name, cost, f); });
    done_ += cost;
    report(name, 0.0, 0.0);
    const double seconds = std::chrono::duration<double>(clock::now() - start).count();
    for (auto& t : timings_)
      if (t.name == name) {
        t.seconds += seconds;
        return;
      }
    timings_.push_back({name, seconds});
  }

  // Counts steps that will not run (the orders and the tail after a series
  // stopped) as done.
  void skip(double cost) { done_ += cost; }

 private:
  void report(const std::string& step, double step_cost, double fraction) const {
    if (progress_) progress_(step, std::min(1.0, (done_ + step_cost * fraction) / total_));
  }

  const std::function<void(const std::string&, double)>& progress_;
  double total_;
  double done_ = 0.0;
  std::vector<StepTiming>& timings_;
};

// --- One wavelength triple's tables -----------------------------------------

struct SetTables {
  Table2D transmittance;        // optical depth to the top of the atmosphere
  Table2D direct_irradiance;    // the sun on a horizontal surface
  Table2D indirect_irradiance;  // the sky light of orders 1..K-1 (and of the tail) on a horizontal surface
  Table3D single_rayleigh, single_aerosol;  // single scattering, without the phase functions
  Table3D multiple;             // orders >= 2 (and the tail) divided by the Rayleigh phase function
  // The medium of the orders >= 2 (medium_of_orders): its transmittance and
  // single scattering when it is the delta-M scaled one.
  bool scaled = false;
  Table2D scaled_transmittance;
  Table3D scaled_single_rayleigh, scaled_single_aerosol;

  const Table2D& orders_transmittance() const { return scaled ? scaled_transmittance : transmittance; }
  const Table3D& orders_single_rayleigh() const { return scaled ? scaled_single_rayleigh : single_rayleigh; }
  const Table3D& orders_single_aerosol() const { return scaled ? scaled_single_aerosol : single_aerosol; }
};

// The transmittance T = exp(-τ) from every (r, mu) to the top of the
// atmosphere, stored as the optical depth τ = ∫ β_ext ds (Collienne 2013,
// eq. 3.8-3.9; Elek & Kmoch 2010, eq. 6), and the direct irradiance of the
// sun on a horizontal surface at every (r, mu_s), E_sun T mu_s averaged over
// the solar disc.
void compute_transmittance_and_direct_irradiance(const AtmosphereParams& a, StepRunner& steps, SetTables& t) {
  t.indirect_irradiance = Table2D(a.irradiance_mu_s_size, a.irradiance_r_size);
  steps.run("transmittance", 0.03, [&](auto&&) { t.transmittance = compute_transmittance_table(a); });
  steps.run("direct_irradiance", 0.02, [&](auto&&) {
    t.direct_irradiance = compute_direct_irradiance_table(a, t.transmittance);
  });
}

// The medium of the orders >= 2: the delta-M scaled medium (Wiscombe 1977;
// physics/parameters.hpp, delta_scaled_params) when the aerosol has a
// forward lobe too sharp for the tables, else `a` itself. The scaled medium
// gets its own transmittance (its single scattering comes with the true
// one's, compute_single_scattering). The light the scaled medium carries in
// the δ is the part of the direct beam scattered within a few degrees of the
// sun: on the ground it is sky light, E_sun (T* - T) mu_s, added to the sky
// irradiance (so that the ground receives what the scaled medium transmits).
AtmosphereParams medium_of_orders(const AtmosphereParams& a, StepRunner& steps, SetTables& t) {
  vec3 forward_fraction;
  const AtmosphereParams ms = physics::delta_scaled_params(a, forward_fraction);
  t.scaled = forward_fraction.x > 0.0f || forward_fraction.y > 0.0f || forward_fraction.z > 0.0f;
  if (t.scaled)
    steps.run("delta_m_transmittance", 0.05, [&](auto&&) {
      t.scaled_transmittance = compute_transmittance_table(ms);
      const Table2D scaled_direct = compute_direct_irradiance_table(ms, t.scaled_transmittance);
      for (size_t i = 0; i < t.indirect_irradiance.texels.size(); ++i)
        t.indirect_irradiance.texels[i] += max(scaled_direct.texels[i] - t.direct_irradiance.texels[i], vec3(0.0f));
    });
  return ms;
}

// The single scattering at every 4D texel (Elek & Kmoch 2010, eq. 7;
// Bruneton & Neyret 2008, §4), without the phase functions: for Rayleigh
// scattering and the aerosol, ∫ β_s(y) T(x, y) T_sun(y) E_sun dy along the
// view ray. The run time adds it with the true phase functions and medium,
// and it receives its sunlight through the medium of the orders
// (single_scattering_tile in definitions.glsl): the sunlight scattered into
// the forward peak on its way to the scattering point still arrives there,
// within a few degrees of the sun's direction, and the scaled orders >= 2 do
// not carry it. Nakajima & Tanaka (1988) also scale the extinction along the
// view ray; against the reference (tests/mars_accuracy.cpp,
// tests/phase_spectrum_test.cpp) that is better by day but doubles the blue of
// the glow around the setting sun and brightens the long view rays near the
// horizon, so the true extinction is kept along view rays. With the scaled
// medium, its own single scattering (the source of its order 2) comes from
// the same pass.
void compute_single_scattering(const AtmosphereParams& a, const AtmosphereParams& ms, const StepCosts& costs,
                               StepRunner& steps, SetTables& t) {
  steps.run("single_scattering", costs.single, [&](auto&& progress) {
    if (t.scaled)
      compute_single_scattering_tables(a, t.scaled_transmittance, t.single_rayleigh, t.single_aerosol, progress, ms,
                                       t.scaled_single_rayleigh, t.scaled_single_aerosol);
    else
      compute_single_scattering_tables(a, t.transmittance, t.single_rayleigh, t.single_aerosol, progress);
  });
}

// --- The scattering orders --------------------------------------------------

// Radiance summed over the texels of a scattering table, per channel of
// the set, with the phase function of each texel's nu tile for phase-free
// tables (`phase` 0: none, 1: Rayleigh, 2: aerosol). A measure of how much
// light an order adds, for auto orders and the convergence report.
glm::dvec3 channel_sums(const physics::AtmosphereParams& a, const Table3D& table, int phase) {
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
glm::dvec3 ground_sums(const Table2D& irradiance) {
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
// 1 and the last order alone says little (on 100x Earth the 64th order still
// adds 0.975 of what the 63rd did, and the orders after one that adds 0.1 %
// of the light still hold a sixth of the light on the ground). A ratio of 1
// or more never converges (the cap and the tail solver take over).
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
// error costs time, not light: the solver sums the same series
// (tests/spectral_test.cpp: 16 orders and the tail give 10x Earth the light
// of its 55 orders within 2e-4).
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

// Adds radiance to `multiple`, stored divided by the Rayleigh phase function
// so that one lookup and one phase function at run time give single Rayleigh
// + all multiple (the render tables' `scattering`). The division uses the nu
// of the texel's tile, not the clamped nu the texel was computed for: the
// run-time interpolation between tiles weights them by their tile nu, and a
// clamped nu there would make M / P_R jump between neighbours.
void add_to_multiple(const AtmosphereParams& a, const Table3D& radiance, Table3D& multiple) {
  tbb::parallel_for(0, multiple.depth, [&](int z) {
    for (int y = 0; y < multiple.height; ++y)
      for (int x = 0; x < multiple.width; ++x) {
        const float tile_nu = physics::scattering_texel_tile_nu(a, vec3(float(x), float(y), float(z)));
        multiple.at(x, y, z) += radiance.at(x, y, z) / physics::rayleigh_phase_function(tile_nu);
      }
  });
}

// How a triple's series of orders went, for the tail and the convergence report.
struct OrderSeries {
  // Per order n >= 2 (index n - 2): the luminance it added, and that of all
  // the light up to it (from the single scattering on).
  std::vector<double> added, total;
  glm::dvec3 channels_total{0.0};    // the light of all orders computed, per channel
  bool converged = false;            // auto orders: stopped by the tolerance
  int last_order = 0;                // the last explicit order
  OrderContribution tail;            // what the tail solver added (tail true), in luminance
  double total_before_tail = 0.0;    // the luminance of the single scattering and the explicit orders
};

// What one order passes on to the next: its radiance (multiple scattering)
// and the sky irradiance on the ground from the order before, with the
// density buffer and what the steps of all orders share.
struct OrderTables {
  Table3D radiance, density;
  Table2D irradiance;
  std::shared_ptr<const OrderGeometry> geometry;
};

// The orders n = 2..K of multiple scattering (Bruneton & Neyret 2008, §4;
// Elek & Kmoch 2010, eq. 9-12), each from the one before: the scattering
// density of order n, J_n(y, v) = ∫ β_s(y) P(v.w) L_{n-1}(y, w) dw (with the
// ground's reflection of the sky irradiance of order n - 1 in L_{n-1}), the
// sky irradiance of order n - 1, E_{n-1} = ∫ L_{n-1}(w) (w.n) dw, and the
// radiance of order n, L_n(x, v) = ∫ T(x, y) J_n(y, v) dy along the view
// ray. With auto orders the series stops when an order adds less than the
// tolerance of the light (series_converged), over the whole table and in the
// sky light on the ground; with the tail solver too, it hands the rest over
// at kEarliestTailHandoff when the forecast says the cap would not be enough.
OrderSeries compute_scattering_orders(const Atmosphere& atmosphere, const PrecomputeOptions& options, int set,
                                      const AtmosphereParams& a, const AtmosphereParams& ms,
                                      const glm::dvec3& to_luminance, const StepCosts& costs, StepRunner& steps,
                                      SetTables& t, OrderTables& order_tables) {
  const int K = options.scattering_orders;
  const bool may_solve_tail = options.auto_orders && options.solve_tail;
  const Table2D& transmittance = t.orders_transmittance();
  const Table3D& single_rayleigh = t.orders_single_rayleigh();
  const Table3D& single_aerosol = t.orders_single_aerosol();
  Table3D& radiance = order_tables.radiance;
  Table3D& density = order_tables.density;
  Table2D& irradiance = order_tables.irradiance;
  radiance = Table3D(t.single_rayleigh.width, t.single_rayleigh.height, t.single_rayleigh.depth);

  OrderSeries series;
  series.last_order = K;
  // The light gathered so far and what the last order added, per channel,
  // in the whole scattering table and in the sky light on the ground (the
  // irradiance row at r = bottom), for auto orders (series_converged). The
  // convergence report and the check that the orders decrease use their
  // luminance over the whole table.
  series.channels_total = channel_sums(a, t.single_rayleigh, 1) + channel_sums(a, t.single_aerosol, 2);
  glm::dvec3 channels_previous(0.0);
  glm::dvec3 ground_total = ground_sums(t.indirect_irradiance), ground_previous(0.0);
  for (int order = 2; order <= K; ++order) {
    steps.run("scattering_density", costs.order * 0.45, [&](auto&& progress) {
      if (!order_tables.geometry) order_tables.geometry = make_order_geometry(ms);
      compute_scattering_density_table(ms, *order_tables.geometry, transmittance, single_rayleigh, single_aerosol,
                                       radiance, irradiance, order - 1, progress, density);
    });
    steps.run("indirect_irradiance", costs.order * 0.05, [&](auto&&) {
      irradiance = compute_indirect_irradiance_table(ms, transmittance, single_rayleigh, single_aerosol, radiance,
                                                     order - 1);
      for (size_t i = 0; i < t.indirect_irradiance.texels.size(); ++i)
        t.indirect_irradiance.texels[i] += irradiance.texels[i];
    });
    steps.run("multiple_scattering", costs.order * 0.5, [&](auto&& progress) {
      compute_multiple_scattering_table(ms, *order_tables.geometry, density, progress, radiance);
      // In optically thick atmospheres the source is read between radius
      // rows with cubic weights (source_function_lookup), which undershoot
      // next to sharp features of the source: a few texels of an order can
      // come out slightly negative. Light is not negative. (The tail
      // solver's signed fields are not clamped: its operator must stay
      // linear.)
      for (vec3& v : radiance.texels) v = max(v, vec3(0.0f));
      add_to_multiple(a, radiance, t.multiple);
    });
    const glm::dvec3 channels_added = channel_sums(a, radiance, 0);
    const double added = glm::dot(to_luminance, channels_added);
    // Each order of a physical atmosphere adds less light than the one
    // before (some escapes to space or is absorbed). An order that adds more
    // means that the tables' discretisation creates energy (too dense a
    // medium for the table resolution). Refuse rather than return tables
    // that grow without bound.
    if (order > 2 && added > glm::dot(to_luminance, channels_previous) * (1.0 + 1e-6) && added > 0.0)
      throw Error(atmosphere.origin + ": scattering order " + std::to_string(order) +
                  " adds more light than order " + std::to_string(order - 1) +
                  ": the tables cannot represent an atmosphere this dense (wavelengths " +
                  std::to_string(int(physics::set_wavelengths(atmosphere.wavelengths_nm, set)[0])) + "-" +
                  std::to_string(int(physics::set_wavelengths(atmosphere.wavelengths_nm, set)[2])) +
                  " nm); use fewer orders, a lower --density-scale or larger tables");
    // The sky light on the ground of this step is order - 1's (from the
    // radiance of order - 1).
    const glm::dvec3 ground_added = ground_sums(irradiance);
    series.channels_total += channels_added;
    ground_total += ground_added;
    const bool all_converged =
        series_converged(channels_added, channels_previous, series.channels_total, options.auto_orders_tolerance);
    const bool ground_converged =
        series_converged(ground_added, ground_previous, ground_total, options.auto_orders_tolerance);
    const bool hand_off =
        may_solve_tail && order == kEarliestTailHandoff && order < K &&
        (series_outlasts(channels_added, channels_previous, series.channels_total, options.auto_orders_tolerance,
                         K - order) ||
         series_outlasts(ground_added, ground_previous, ground_total, options.auto_orders_tolerance, K - order));
    channels_previous = channels_added;
    ground_previous = ground_added;
    series.added.push_back(added);
    series.total.push_back(glm::dot(to_luminance, series.channels_total));
    if (options.auto_orders && all_converged && ground_converged) {
      steps.skip(costs.order * (K - order) + costs.tail);
      series.converged = true;
      break;
    }
    if (hand_off) {
      steps.skip(costs.order * (K - order));
      series.last_order = order;
      break;
    }
  }
  return series;
}

// The orders after the last explicit one K', summed at once: T = Σ_{n > K'}
// of the orders' radiance and sky irradiance, the solution of the transport
// equation (I - A) T = v_{K'+1} with A one scattering order and v_{K'+1} the
// first order left out, computed as the orders are (for K' = 1, from the
// single scattering); GMRES with deflated restarts (Saad & Schultz 1986;
// Morgan 2002; tail.cpp).
void solve_tail(const PrecomputeOptions& options, const AtmosphereParams& a, const AtmosphereParams& ms,
                const glm::dvec3& to_luminance, const StepCosts& costs, StepRunner& steps, SetTables& t,
                OrderTables& order_tables, OrderSeries& series) {
  steps.run("tail", costs.tail, [&](auto&& progress) {
    const Table2D& transmittance = t.orders_transmittance();
    const Table3D& single_rayleigh = t.orders_single_rayleigh();
    const Table3D& single_aerosol = t.orders_single_aerosol();
    const int last_order = series.last_order;
    if (!order_tables.geometry) order_tables.geometry = make_order_geometry(ms);
    const OrderGeometry& geometry = *order_tables.geometry;
    Table3D& density = order_tables.density;
    compute_scattering_density_table(ms, geometry, transmittance, single_rayleigh, single_aerosol,
                                     order_tables.radiance, order_tables.irradiance, last_order, nullptr, density);
    const Table2D next_irradiance = compute_indirect_irradiance_table(ms, transmittance, single_rayleigh,
                                                                      single_aerosol, order_tables.radiance, last_order);
    Table3D next_radiance;
    compute_multiple_scattering_table(ms, geometry, density, nullptr, next_radiance);
    density = Table3D();
    order_tables.radiance = Table3D();
    const ScatteringTail tail = solve_scattering_tail(ms, geometry, transmittance, next_radiance, next_irradiance,
                                                      options.tail_tolerance, options.tail_iterations, kTailRestart,
                                                      kTailDeflation, progress);
    add_to_multiple(a, tail.radiance, t.multiple);
    for (size_t i = 0; i < t.indirect_irradiance.texels.size(); ++i)
      t.indirect_irradiance.texels[i] += tail.irradiance.texels[i];
    // The solver's combination of signed fields can leave texels of almost
    // no light slightly below zero.
    for (auto* texels : {&t.multiple.texels, &t.indirect_irradiance.texels})
      for (vec3& v : *texels) v = max(v, vec3(0.0f));
    OrderContribution& c = series.tail;
    c.tail = true;
    c.order = last_order + 1;
    c.added = glm::dot(to_luminance, channel_sums(a, tail.radiance, 0));
    c.iterations = tail.iterations;
    c.residual = std::max({tail.relative_residual.x, tail.relative_residual.y, tail.relative_residual.z});
    series.total_before_tail = glm::dot(to_luminance, series.channels_total);
  });
}

// --- The render tables ------------------------------------------------------

// The aerosol phase function at the tile nu of each nu index.
std::vector<glm::vec3> tile_phases(const AtmosphereParams& params, const TableSizes& sizes) {
  std::vector<glm::vec3> phases;
  for (int i = 0; i < sizes.scattering_nu; ++i)
    phases.push_back(physics::aerosol_phase_function(
        params, physics::scattering_texel_tile_nu(params, physics::vec3(float(i * sizes.scattering_mu_s), 0.0f, 0.0f))));
  return phases;
}

// Adds one triple's tables to the render tables (physics/definitions.glsl):
// its irradiance and scattering converted to the channels and summed over
// the triples (with three wavelengths the one triple's tables are the render
// tables: moved, not converted); its transmittance stays per triple, as a
// tile of the spectral optical depth (which channel_transmittance weights at
// run time): tile `set` for the true medium, set_count + set for the medium
// of the orders, in rows of 2 set_count tiles side by side.
//
// The single aerosol table of sRGB channels: the run time multiplies its
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
// interpolation between tiles weights them by their tile nu). Here the
// triple's table is multiplied by P_λ; divide_single_aerosol_by_render_phase
// divides the sum by P_c. With three wavelengths P_λ = P_c and the table
// stays phase-free (untouched).
void add_to_render_tables(const std::vector<double>& wavelengths, int set, int set_count, const AtmosphereParams& a,
                          SetTables& t, Tables& tables) {
  const bool srgb = physics::srgb_channels(wavelengths);
  const glm::mat3 to_channels = physics::set_to_channels(wavelengths, set);
  TableSet& out = tables.set;
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

  Table3D scattering = t.single_rayleigh;
  for (size_t i = 0; i < scattering.texels.size(); ++i) scattering.texels[i] += t.multiple.texels[i];

  accumulate(out.direct_irradiance, t.direct_irradiance.texels, to_channels);
  accumulate(out.indirect_irradiance, t.indirect_irradiance.texels, to_channels);
  accumulate(out.scattering, scattering.texels, to_channels);
  if (srgb) {
    // The tile phase functions of each wavelength (the tile nu depends on
    // the texel's nu index only, x / mu_s size).
    const std::vector<glm::vec3> phases = tile_phases(a, tables.sizes);
    Table3D& single_aerosol = t.single_aerosol;
    tbb::parallel_for(0, single_aerosol.depth, [&](int z) {
      for (int y = 0; y < single_aerosol.height; ++y)
        for (int x = 0; x < single_aerosol.width; ++x)
          single_aerosol.at(x, y, z) *= phases[size_t(x / a.scattering_mu_s_size)];
    });
  }
  accumulate(out.single_aerosol, t.single_aerosol.texels, to_channels);
  accumulate(out.multiple_scattering, t.multiple.texels, to_channels);

  const Table2D& transmittance = t.transmittance;
  const Table2D& orders_transmittance = t.orders_transmittance();
  const int w = transmittance.width, h = transmittance.height, tiles = 2 * set_count;
  if (tables.spectral_optical_depth.empty())
    tables.spectral_optical_depth.assign(size_t(w) * size_t(h) * size_t(tiles), glm::vec3(0.0f));
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const size_t row = size_t(y) * size_t(w) * size_t(tiles) + size_t(x);
      tables.spectral_optical_depth[row + size_t(set) * size_t(w)] = transmittance.at(x, y);
      tables.spectral_optical_depth[row + size_t(set_count + set) * size_t(w)] =
          orders_transmittance.texels[size_t(y) * size_t(w) + size_t(x)];
    }
}

// The sum Σ_λ M_cλ S_λ P_λ(nu) of the single aerosol tables of sRGB channels
// divided by the channel's phase function P_c(nu) (see add_to_render_tables).
void divide_single_aerosol_by_render_phase(const Atmosphere& atmosphere, const TableSizes& sizes, Tables& tables) {
  const AtmosphereParams render = physics::make_render_params(atmosphere, sizes);
  const int width = sizes.scattering_nu * sizes.scattering_mu_s;
  const int height = sizes.scattering_mu, depth = sizes.scattering_r;
  const std::vector<glm::vec3> phases = tile_phases(render, sizes);
  std::vector<glm::vec3>& single_aerosol = tables.set.single_aerosol;
  tbb::parallel_for(0, depth, [&](int z) {
    for (int y = 0; y < height; ++y)
      for (int x = 0; x < width; ++x)
        single_aerosol[(size_t(z) * size_t(height) + size_t(y)) * size_t(width) + size_t(x)] /=
            phases[size_t(x / sizes.scattering_mu_s)];
  });
}

// --- The convergence report -------------------------------------------------

// What each order n >= 2 added over all triples, as luminance and as a
// fraction of all the light up to it (a triple that stopped earlier with auto
// orders adds nothing more, but its light still counts in the total); then,
// if a triple solved a tail, what the tails added (Tables::convergence).
std::vector<OrderContribution> convergence_report(const std::vector<OrderSeries>& sets, int scattering_orders) {
  std::vector<OrderContribution> report;
  for (int order = 2; order <= scattering_orders; ++order) {
    double added = 0.0, total = 0.0;
    for (const OrderSeries& s : sets) {
      const size_t n = s.added.size();
      if (n == 0) continue;
      const size_t i = std::min(size_t(order - 2), n - 1);
      if (size_t(order - 2) < n) added += s.added[i];
      total += s.total[i];
    }
    report.push_back({order, added, total != 0.0 ? added / total : 0.0});
  }
  OrderContribution tail;
  double total = 0.0;
  for (const OrderSeries& s : sets) {
    const OrderContribution& c = s.tail;
    if (c.tail) {
      tail.tail = true;
      tail.order = std::max(tail.order, c.order);
      tail.added += c.added;
      tail.iterations = std::max(tail.iterations, c.iterations);
      tail.residual = std::max(tail.residual, c.residual);
      total += s.total_before_tail + c.added;
    } else if (!s.total.empty()) {
      total += s.total.back();
    }
  }
  if (tail.tail) {
    tail.relative = total != 0.0 ? tail.added / total : 0.0;
    report.push_back(tail);
  }
  return report;
}

}  // namespace

Tables precompute_tables(const Atmosphere& atmosphere, const PrecomputeOptions& options) {
  const int set_count = checked_set_count(atmosphere, options);
  const std::vector<double>& wavelengths = atmosphere.wavelengths_nm;
  const bool may_solve_tail = options.auto_orders && options.solve_tail;
  const StepCosts costs(options, may_solve_tail);

  Tables tables;
  tables.sizes = options.sizes;
  tables.scattering_orders = 1;
  tables.wavelengths_nm = wavelengths;
  StepRunner steps(options, costs.set * set_count, tables.timings);
  const glm::vec3 luminance_of_srgb(0.2126f, 0.7152f, 0.0722f);
  const glm::mat3 to_srgb = physics::channels_to_srgb_matrix(wavelengths);
  std::vector<OrderSeries> series(static_cast<size_t>(set_count));
  // The response's ground: at each wavelength the far end of [0, 1] from
  // the planet's albedo, so that the series is interpolated over most
  // albedos, not extrapolated. Its albedo per channel is weighted by the
  // sunlight as the planet's (physics::make_render_params).
  Tables response;
  response.sizes = options.sizes;
  glm::dvec3 response_reflected(0.0), response_sun(0.0);

  for (int set = 0; set < set_count; ++set) {
    const AtmosphereParams a = physics::make_atmosphere_params(atmosphere, options.sizes, set);
    // Luminance per unit of this triple's radiance at each of its wavelengths.
    const glm::vec3 luminance = glm::transpose(to_srgb * physics::set_to_channels(wavelengths, set)) * luminance_of_srgb;
    const glm::dvec3 to_luminance(luminance);
    SetTables t;
    compute_transmittance_and_direct_irradiance(a, steps, t);
    const AtmosphereParams ms = medium_of_orders(a, steps, t);
    compute_single_scattering(a, ms, costs, steps, t);
    t.multiple = Table3D(t.single_rayleigh.width, t.single_rayleigh.height, t.single_rayleigh.depth);
    // The response's orders start from the same transmittance and single
    // scattering, which do not see the ground.
    std::optional<SetTables> bright;
    if (options.ground_albedo_response) bright = t;
    OrderTables order_tables;
    OrderSeries& s = series[size_t(set)];
    s = compute_scattering_orders(atmosphere, options, set, a, ms, to_luminance, costs, steps, t, order_tables);
    tables.scattering_orders = std::max(tables.scattering_orders, 1 + int(s.added.size()));
    if (may_solve_tail && !s.converged) solve_tail(options, a, ms, to_luminance, costs, steps, t, order_tables, s);
    add_to_render_tables(wavelengths, set, set_count, a, t, tables);
    if (bright) {
      AtmosphereParams a_bright = a, ms_bright = ms;
      for (int c = 0; c < 3; ++c) a_bright.ground_albedo[c] = a.ground_albedo[c] < 0.5f ? 1.0f : 0.0f;
      ms_bright.ground_albedo = a_bright.ground_albedo;
      const glm::dmat3 m(physics::set_to_channels(wavelengths, set));
      response_reflected += m * glm::dvec3(a_bright.ground_albedo * a.solar_irradiance);
      response_sun += m * glm::dvec3(a.solar_irradiance);
      OrderTables bright_tables;
      OrderSeries s_bright = compute_scattering_orders(atmosphere, options, set, a_bright, ms_bright, to_luminance,
                                                       costs, steps, *bright, bright_tables);
      if (may_solve_tail && !s_bright.converged)
        solve_tail(options, a_bright, ms_bright, to_luminance, costs, steps, *bright, bright_tables, s_bright);
      add_to_render_tables(wavelengths, set, set_count, a_bright, *bright, response);
    }
  }
  if (physics::srgb_channels(wavelengths)) divide_single_aerosol_by_render_phase(atmosphere, options.sizes, tables);
  tables.convergence = convergence_report(series, tables.scattering_orders);
  if (options.ground_albedo_response) {
    GroundAlbedoResponse& g = tables.ground_response;
    g.albedo = glm::clamp(glm::vec3(response_reflected / response_sun), 0.0f, 1.0f);
    g.planet_albedo = physics::make_render_params(atmosphere, options.sizes).ground_albedo;
    for (int c = 0; c < 3; ++c)
      if (!(std::abs(g.albedo[c] - g.planet_albedo[c]) >= kLeastResponseAlbedoDifference))
        throw Error(atmosphere.origin + ": the ground albedo response needs a second ground albedo at least " +
                    std::to_string(kLeastResponseAlbedoDifference) +
                    " from the planet's in every colour channel, and the planet's albedo spectrum crosses 0.5 "
                    "within channel " + std::to_string(c));
    g.spherical_albedo = spherical_albedo_from_below(options.sizes, tables.set, response.set, g.planet_albedo, g.albedo);
    g.indirect_irradiance = std::move(response.set.indirect_irradiance);
    g.scattering = std::move(response.set.scattering);
    g.multiple_scattering = std::move(response.set.multiple_scattering);
  }
  return tables;
}

}  // namespace atmos
