// The tail solver of auto orders (PrecomputeOptions::solve_tail,
// src/precompute/tail.cpp): the orders after the cap, summed at once, against
// the same orders computed one by one. 4x Earth (optical depth 1 in the
// green: Rayleigh 0.39 and the continental aerosol 0.6; 1.6 in the blue)
// converges in 60 explicit orders to float precision (each order adds 0.74
// of the one before, the last 4e-10 of the light), so the explicit sum is
// the exact answer of the tables; the solver starts after 4 orders, where a
// visible part of the multiple scattering is still missing. (10x Earth keeps
// 0.875 per order with this aerosol and is not converged after 60.) Small tables,
// so the test takes seconds. Venus, where the solver matters, is compared
// with 600 explicit orders in convergence_accuracy.cpp (slow).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <tuple>
#include <utility>
#include <vector>

#include "atmos/atmosphere.hpp"
#include "atmos/planet_file.hpp"
#include "atmos/tables.hpp"
#include "physics/parameters.hpp"
#include "precompute/steps.hpp"

namespace {

using atmos::physics::AtmosphereParams;
using namespace atmos::precompute;

atmos::TableSizes small_sizes() { return atmos::TableSizes{64, 16, 32, 8, 4, 16, 32, 8}; }

// Small tables, auto orders up to `cap`.
atmos::PrecomputeOptions auto_orders(int cap) {
  atmos::PrecomputeOptions options;
  options.sizes = small_sizes();
  options.auto_orders = true;
  options.scattering_orders = cap;
  return options;
}

glm::dvec3 channel_sum(const std::vector<glm::vec3>& texels) {
  glm::dvec3 sum(0.0);
  for (const glm::vec3& v : texels) sum += glm::dvec3(v);
  return sum;
}

// The largest relative difference of the three channels of two sums.
double relative_difference(const glm::dvec3& a, const glm::dvec3& b) {
  double worst = 0.0;
  for (int c = 0; c < 3; ++c) worst = std::max(worst, std::abs(a[c] - b[c]) / std::abs(b[c]));
  return worst;
}

class DenseEarth : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    atmosphere_ = new atmos::Atmosphere(atmos::load_atmosphere("earth"));
    atmos::scale_density(*atmosphere_, 4.0);
    atmos::PrecomputeOptions options;
    options.sizes = small_sizes();
    options.scattering_orders = 60;
    explicit_ = new atmos::Tables(atmos::precompute_tables(*atmosphere_, options));
  }
  static void TearDownTestSuite() {
    delete atmosphere_;
    delete explicit_;
  }
  static atmos::Atmosphere* atmosphere_;
  static atmos::Tables* explicit_;  // 60 orders, one by one
};
atmos::Atmosphere* DenseEarth::atmosphere_ = nullptr;
atmos::Tables* DenseEarth::explicit_ = nullptr;

TEST_F(DenseEarth, ExplicitOrdersHaveConverged) {
  // The reference of the tests below: its last order adds 4e-10 of the light,
  // 0.74 times what the order before added (what is left out is 1.2e-9).
  const auto& c = explicit_->convergence;
  ASSERT_EQ(c.back().order, 60);
  EXPECT_FALSE(c.back().tail);
  EXPECT_LT(c.back().relative, 2e-7);
  EXPECT_LT(c.back().added, 0.85 * c[c.size() - 2].added);
}

// Four orders, then the tail: every table and the convergence report agree
// with 60 explicit orders. Measured: the table sums within 3e-6 and the
// texels within 5e-6 of the largest (the solver's residual is 7e-6); 6
// solver steps instead of 56 orders.
TEST_F(DenseEarth, FourOrdersAndTheTailEqualSixtyOrders) {
  const atmos::PrecomputeOptions options = auto_orders(4);
  const atmos::Tables t = atmos::precompute_tables(*atmosphere_, options);
  ASSERT_EQ(t.scattering_orders, 4);
  ASSERT_EQ(t.convergence.size(), 4u);  // orders 2, 3, 4 and the tail
  const atmos::OrderContribution& tail = t.convergence.back();
  std::printf("tail: orders >= %d add %.3e of the light (%.3e), %d solver steps, residual %.1e\n", tail.order,
              tail.relative, tail.added, tail.iterations, tail.residual);
  EXPECT_TRUE(tail.tail);
  EXPECT_EQ(tail.order, 5);
  EXPECT_LE(tail.residual, options.tail_tolerance);
  EXPECT_GT(tail.iterations, 0);
  EXPECT_LT(tail.iterations, 20);
  // What the tail adds is what orders 5..60 add.
  double explicit_tail = 0.0;
  for (const atmos::OrderContribution& c : explicit_->convergence)
    if (c.order >= 5) explicit_tail += c.added;
  EXPECT_NEAR(tail.added, explicit_tail, 1e-5 * explicit_tail);
  const double explicit_total = explicit_->convergence.back().added / explicit_->convergence.back().relative;
  EXPECT_NEAR(tail.relative, explicit_tail / explicit_total, 1e-4 * tail.relative);
  EXPECT_GT(tail.relative, 0.01);  // a test of something: a visible part of the light

  for (const auto& [name, solved, exact] :
       {std::tuple{"scattering", &t.set.scattering, &explicit_->set.scattering},
        std::tuple{"multiple_scattering", &t.set.multiple_scattering, &explicit_->set.multiple_scattering},
        std::tuple{"indirect_irradiance", &t.set.indirect_irradiance, &explicit_->set.indirect_irradiance}}) {
    SCOPED_TRACE(name);
    const glm::dvec3 a = channel_sum(*solved), b = channel_sum(*exact);
    std::printf("%-20s sums differ by %.2e\n", name, relative_difference(a, b));
    EXPECT_LT(relative_difference(a, b), 1e-5);
    glm::dvec3 largest(0.0);
    for (const glm::vec3& v : *exact)
      for (int c = 0; c < 3; ++c) largest[c] = std::max(largest[c], double(v[c]));
    double worst = 0.0;
    for (size_t i = 0; i < exact->size(); ++i)
      for (int c = 0; c < 3; ++c)
        worst = std::max(worst, std::abs(double((*solved)[i][c]) - double((*exact)[i][c])) / largest[c]);
    std::printf("%-20s texels differ by at most %.2e of the largest\n", name, worst);
    EXPECT_LT(worst, 2e-4);
  }
  EXPECT_EQ(t.set.single_aerosol, explicit_->set.single_aerosol);
  EXPECT_EQ(t.set.direct_irradiance, explicit_->set.direct_irradiance);
}

// Auto orders stop when what is left of the series is below the tolerance,
// both in the whole scattering table and in the sky light on the ground
// (the bottom row of the irradiance table), in every channel. The ground is
// the test's point: there the light has been scattered most often and each
// order adds most of what the one before did, so an order that adds a
// fraction of all the light smaller than the tolerance may still leave
// several times the tolerance of the ground's sky light out.
TEST_F(DenseEarth, AutoOrdersStopWhenTheGroundsSkyLightHasConverged) {
  auto ground = [](const atmos::Tables& t) {
    glm::dvec3 sum(0.0);
    for (int x = 0; x < t.sizes.irradiance_mu_s; ++x) sum += glm::dvec3(t.set.indirect_irradiance[size_t(x)]);
    return sum;
  };
  for (double tolerance : {1e-2, 1e-3}) {
    SCOPED_TRACE(tolerance);
    atmos::PrecomputeOptions options = auto_orders(64);
    options.auto_orders_tolerance = tolerance;
    const atmos::Tables t = atmos::precompute_tables(*atmosphere_, options);
    EXPECT_FALSE(t.convergence.back().tail);
    const glm::dvec3 a = ground(t), b = ground(*explicit_);
    const glm::dvec3 s = channel_sum(t.set.scattering), e = channel_sum(explicit_->set.scattering);
    std::printf("tolerance %.0e: %d orders, ground's sky light short by %.2e %.2e %.2e, all light by %.2e %.2e %.2e\n",
                tolerance, t.scattering_orders, 1.0 - a.x / b.x, 1.0 - a.y / b.y, 1.0 - a.z / b.z, 1.0 - s.x / e.x,
                1.0 - s.y / e.y, 1.0 - s.z / e.z);
    EXPECT_LT(relative_difference(a, b), tolerance);
    EXPECT_LT(relative_difference(s, e), tolerance);
  }
}

// Without the solver, the same cap leaves the tail out; and fixed orders
// never solve it (K orders are light scattered at most K times).
TEST_F(DenseEarth, NoTailWithoutTheSolverOrWithFixedOrders) {
  atmos::PrecomputeOptions options = auto_orders(4);
  options.solve_tail = false;
  const atmos::Tables without = atmos::precompute_tables(*atmosphere_, options);
  EXPECT_EQ(without.convergence.size(), 3u);
  EXPECT_FALSE(without.convergence.back().tail);
  options.auto_orders = false;
  options.solve_tail = true;
  const atmos::Tables fixed = atmos::precompute_tables(*atmosphere_, options);
  EXPECT_EQ(fixed.set.scattering, without.set.scattering);
  EXPECT_EQ(fixed.convergence.size(), 3u);
  // What the tail would add is missing.
  for (int c = 0; c < 3; ++c) {
    EXPECT_GT(channel_sum(explicit_->set.scattering)[c], 1.01 * channel_sum(without.set.scattering)[c]) << c;
    EXPECT_GT(channel_sum(explicit_->set.indirect_irradiance)[c], 1.01 * channel_sum(without.set.indirect_irradiance)[c])
        << c;
  }
}

// Earth converges long before the cap: the solver never runs and the tables
// are those of plain auto orders.
TEST(Convergence, EarthAutoOrdersAreUnchangedByTheSolver) {
  const atmos::Atmosphere earth = atmos::load_atmosphere("earth");
  atmos::PrecomputeOptions options = auto_orders(64);
  const atmos::Tables with = atmos::precompute_tables(earth, options);
  options.solve_tail = false;
  const atmos::Tables without = atmos::precompute_tables(earth, options);
  EXPECT_LT(with.scattering_orders, 20);
  EXPECT_FALSE(with.convergence.back().tail);
  EXPECT_EQ(with.set.scattering, without.set.scattering);
  EXPECT_EQ(with.set.indirect_irradiance, without.set.indirect_irradiance);
}

// The tail solver itself (tail.cpp) on the small Venus tables, from the
// 17th order: deflated restarts (30 fields, 10 kept, as precompute_tables
// uses it), plain restarts (30 fields, none kept) and the degenerate sizes
// (a basis of 2 fields, more vectors asked for than fit) solve the same
// equation, so they must give the same tail wherever they converge, and
// a run cut short must still be finite and no worse than its start.
TEST(ConvergenceTail, TailSolverRestartsAgree) {
  atmos::Atmosphere venus = atmos::load_atmosphere("venus");
  atmos::TableSizes sizes = small_sizes();
  sizes.scattering_r = 32;
  const AtmosphereParams a = atmos::physics::make_atmosphere_params(venus, sizes, 0);
  const Table2D transmittance = compute_transmittance_table(a);
  Table3D single_rayleigh, single_aerosol;
  compute_single_scattering_tables(a, transmittance, single_rayleigh, single_aerosol, nullptr);
  const auto geometry = make_order_geometry(a);
  Table3D radiance, density;
  Table2D irradiance;
  for (int order = 2; order <= 17; ++order) {
    compute_scattering_density_table(a, *geometry, transmittance, single_rayleigh, single_aerosol, radiance,
                                     irradiance, order - 1, nullptr, density);
    irradiance = compute_indirect_irradiance_table(a, transmittance, single_rayleigh, single_aerosol, radiance,
                                                   order - 1);
    compute_multiple_scattering_table(a, *geometry, density, nullptr, radiance);
  }
  const double tolerance = 1e-6;
  auto solve = [&](int iterations, int restart, int deflation) {
    const ScatteringTail t =
        solve_scattering_tail(a, *geometry, transmittance, radiance, irradiance, tolerance, iterations, restart,
                              deflation, nullptr);
    std::printf("restart %d, deflation %d: %d steps, residual %.1e %.1e %.1e\n", restart, deflation, t.iterations,
                t.relative_residual.x, t.relative_residual.y, t.relative_residual.z);
    return t;
  };
  const ScatteringTail deflated = solve(400, 30, 10);
  const ScatteringTail plain = solve(400, 30, 0);
  for (const ScatteringTail* t : {&deflated, &plain}) EXPECT_LE(std::max({t->relative_residual.x,
                                                                            t->relative_residual.y,
                                                                            t->relative_residual.z}), tolerance);
  // Measured: about 140 steps deflated, 190-200 plain.
  EXPECT_LT(deflated.iterations, plain.iterations);
  // The same tail: the ground's sky light and the light of the table, per
  // channel. Two solutions agree only as well as their residuals allow: a
  // residual r may leave up to r / (1 - 0.9975) in the slowest mode. With
  // the 1e-5 of precompute_tables the blue ground light of the two was
  // 4.6e-4 apart (5.0e-4 in the baseline x86-64 code, the sanitizer build),
  // so the test solves to 1e-6: measured at most 4e-8, 3e-7 and 3.3e-5
  // apart (red, green, blue; 1e-5 in the blue with x86-64-v3). Bound 1e-4.
  auto sums = [](const ScatteringTail& t) {
    glm::dvec3 ground(0.0), light(0.0);
    for (int x = 0; x < t.irradiance.width; ++x) ground += glm::dvec3(t.irradiance.texels[size_t(x)]);
    for (const glm::vec3& v : t.radiance.texels) light += glm::dvec3(v);
    return std::pair(ground, light);
  };
  const auto [ground_d, light_d] = sums(deflated);
  const auto [ground_p, light_p] = sums(plain);
  for (int c = 0; c < 3; ++c) {
    std::printf("channel %d: ground %+.1e, light %+.1e\n", c, ground_d[c] / ground_p[c] - 1.0,
                light_d[c] / light_p[c] - 1.0);
    EXPECT_NEAR(ground_d[c], ground_p[c], 1e-4 * ground_p[c]) << c;
    EXPECT_NEAR(light_d[c], light_p[c], 1e-4 * light_p[c]) << c;
  }
  // Cut short, and with degenerate sizes: finite, and the residual below 1.
  for (const auto& [iterations, restart, deflation] :
       std::vector<std::tuple<int, int, int>>{{1, 30, 10}, {5, 2, 10}, {12, 4, 10}, {12, 1, 0}}) {
    const ScatteringTail t = solve(iterations, restart, deflation);
    EXPECT_EQ(t.iterations, iterations);
    for (int c = 0; c < 3; ++c) EXPECT_LT(t.relative_residual[c], 1.0) << c;
    for (const glm::vec3& v : t.radiance.texels) ASSERT_TRUE(std::isfinite(v.x + v.y + v.z));
    for (const glm::vec3& v : t.irradiance.texels) ASSERT_TRUE(std::isfinite(v.x + v.y + v.z));
  }
}

TEST(Convergence, RejectsBadTailOptions) {
  const atmos::Atmosphere earth = atmos::load_atmosphere("earth");
  atmos::PrecomputeOptions options = auto_orders(64);
  options.tail_tolerance = 0.0;
  EXPECT_THROW(atmos::precompute_tables(earth, options), atmos::Error);
  options.tail_tolerance = 1e-5;
  options.tail_iterations = 0;
  EXPECT_THROW(atmos::precompute_tables(earth, options), atmos::Error);
}

}  // namespace
