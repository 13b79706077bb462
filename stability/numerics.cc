#include "stability/numerics_internal.h"

namespace zwidth::stability::internal {

double GoldenExtremum(const std::function<double(double)>& f, double a, double b, double sign,
                      double tol) {
  const double g = 0.5 * (std::sqrt(5.0) - 1.0);
  double x1 = b - g * (b - a), x2 = a + g * (b - a);
  double f1 = sign * f(x1), f2 = sign * f(x2);
  while (b - a > tol) {
    if (f1 > f2) { b = x2; x2 = x1; f2 = f1; x1 = b - g * (b - a); f1 = sign * f(x1); }
    else { a = x1; x1 = x2; f1 = f2; x2 = a + g * (b - a); f2 = sign * f(x2); }
  }
  return 0.5 * (a + b);
}

std::vector<double> PolyMul(const std::vector<double>& a, const std::vector<double>& b) {
  std::vector<double> r(a.size() + b.size() - 1, 0.0);
  for (size_t i = 0; i < a.size(); ++i)
    for (size_t j = 0; j < b.size(); ++j) r[i + j] += a[i] * b[j];
  return r;
}

}  // namespace zwidth::stability::internal
