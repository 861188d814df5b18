// Numerical quadrature shared by the precomputation (its scattering density
// and energy budgets) and the references: plain numerical analysis, no
// physics of the tables, so that the references may use it too and still
// share nothing with the table code but the planet description.
#pragma once

#include <vector>

namespace atmos::physics {

// Nodes (increasing) and weights of the n-point Gauss-Legendre rule on
// [a, b], exact for polynomials of degree 2n - 1 (Newton on P_n from
// Tricomi's initial guesses, to 1e-15).
void gauss_legendre(int n, double a, double b, std::vector<double>& nodes, std::vector<double>& weights);

}  // namespace atmos::physics
