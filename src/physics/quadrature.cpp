#include "physics/quadrature.hpp"

#include <cmath>
#include <numbers>

namespace atmos::physics {

void gauss_legendre(int n, double a, double b, std::vector<double>& nodes, std::vector<double>& weights) {
  nodes.assign(size_t(n), 0.0);
  weights.assign(size_t(n), 0.0);
  for (int i = 0; i < n; ++i) {
    // Newton iteration on P_n from Tricomi's initial guess.
    double x = std::cos(std::numbers::pi * (i + 0.75) / (n + 0.5));
    double dp = 1.0;
    for (int iteration = 0; iteration < 100; ++iteration) {
      double p0 = 1.0, p1 = x;
      for (int k = 2; k <= n; ++k) {
        const double p2 = ((2.0 * k - 1.0) * x * p1 - (k - 1.0) * p0) / k;
        p0 = p1;
        p1 = p2;
      }
      if (n == 1) { p1 = x; p0 = 1.0; }
      dp = n * (x * p1 - p0) / (x * x - 1.0);
      const double dx = p1 / dp;
      x -= dx;
      if (std::abs(dx) < 1e-15) break;
    }
    nodes[size_t(i)] = 0.5 * (a + b) + 0.5 * (b - a) * (-x);
    weights[size_t(i)] = (b - a) / ((1.0 - x * x) * dp * dp);
  }
}

}  // namespace atmos::physics
