// The exact ZOH-sampled plant in pole-residue form, templated on the scalar so
// that ceres::Jet can differentiate it (fit/) while the same code serves
// doubles. Derivation (partial fractions of G(s)/s):
//
//   G(s)/s = A2/s^2 + A1/s + sum_k R_k/(s - p_k),  A2 = 1/b (unit-DC sections),
//   G_d(z) = (1 - z^-1) Z{G(s)/s}
//          = A2 T/(z - 1) + A1 + sum_k R_k (z - 1)/(z - e^{p_k T})
//          = T/(b (z - 1)) + sum_k R_k (e^{p_k T} - 1)/(z - e^{p_k T}),
//
// since A1 + sum_k R_k = 0 (G(s)/s decays as s^-3). Poles p_k: the rigid-body
// pole -a = -b/m and each section's pair -c/2 +- j sqrt(w^2 - c^2/4).
// e^{pT} - 1 is formed with expm1 so that slow poles keep their digits.
//
// Precondition: every section underdamped (c < 2 w) and no two sections with
// the same pole pair; otherwise Build returns false and the caller should use
// the state-space path (model/state_space.h), which has no such restriction.
#pragma once

#include <cmath>
#include <vector>

namespace zwidth::model {

// Minimal complex arithmetic over any scalar with +,-,*,/ (std::complex is
// unspecified for user types such as ceres::Jet).
template <typename T>
struct Cx {
  T re, im;
  Cx() : re(0.0), im(0.0) {}
  Cx(T r, T i) : re(r), im(i) {}
  explicit Cx(T r) : re(r), im(0.0) {}
};
template <typename T> Cx<T> operator+(const Cx<T>& a, const Cx<T>& b) { return {a.re + b.re, a.im + b.im}; }
template <typename T> Cx<T> operator-(const Cx<T>& a, const Cx<T>& b) { return {a.re - b.re, a.im - b.im}; }
template <typename T> Cx<T> operator*(const Cx<T>& a, const Cx<T>& b) {
  return {a.re * b.re - a.im * b.im, a.re * b.im + a.im * b.re};
}
template <typename T> Cx<T> operator*(const T& s, const Cx<T>& a) { return {s * a.re, s * a.im}; }
template <typename T> Cx<T> operator/(const Cx<T>& a, const Cx<T>& b) {
  const T den = b.re * b.re + b.im * b.im;
  return {(a.re * b.re + a.im * b.im) / den, (a.im * b.re - a.re * b.im) / den};
}
template <typename T> Cx<T> Conj(const Cx<T>& a) { return {a.re, -a.im}; }

template <typename T>
struct ZohModalForm {
  T integrator;             // T/b: G_d has integrator/(z - 1)
  T rigid_pole;             // e^{-aT}, real
  T rigid_coeff;            // R_a (e^{-aT} - 1), real
  std::vector<Cx<T>> pole;  // e^{p_k T} for the upper pole of each section
  std::vector<Cx<T>> coeff; // R_k (e^{p_k T} - 1); the conjugate pole has the conjugate

  // m, b, and 4 values per section in the order omega, c, v, d.
  bool Build(const T& m, const T& b, const T* sections, int num_sections,
             double period_s) {
    using std::cos; using std::exp; using std::expm1; using std::sin; using std::sqrt;
    const T a = b / m;
    const T Ts(period_s);
    integrator = Ts / b;
    // Section response H_i(s) at a complex point.
    auto section = [&](int i, const Cx<T>& s) {
      const T& w = sections[4 * i];
      const T& c = sections[4 * i + 1];
      const T& v = sections[4 * i + 2];
      const T& d = sections[4 * i + 3];
      const Cx<T> s2 = s * s;
      const Cx<T> num = s2 + d * s + Cx<T>(v * v);
      const Cx<T> den = s2 + c * s + Cx<T>(w * w);
      return ((w * w) / (v * v)) * (num / den);
    };
    // Rigid-body pole -a: R_a = prod H_i(-a) / (m a^2).
    Cx<T> prod(T(1.0));
    const Cx<T> minus_a(-a);
    for (int i = 0; i < num_sections; ++i) prod = prod * section(i, minus_a);
    rigid_pole = exp(-a * Ts);
    rigid_coeff = (prod.re / (m * a * a)) * expm1(-a * Ts);
    pole.assign(num_sections, Cx<T>());
    coeff.assign(num_sections, Cx<T>());
    for (int i = 0; i < num_sections; ++i) {
      const T& w = sections[4 * i];
      const T& c = sections[4 * i + 1];
      const T& v = sections[4 * i + 2];
      const T& d = sections[4 * i + 3];
      const T disc = w * w - c * c / T(4.0);
      if (!(disc > T(0.0))) return false;
      const T wd = sqrt(disc);
      const Cx<T> p(-c / T(2.0), wd);
      // Residue of G(s)/s at p.
      Cx<T> r = ((w * w) / (v * v)) * (p * p + d * p + Cx<T>(v * v));
      r = r / Cx<T>(T(0.0), T(2.0) * wd);
      for (int j = 0; j < num_sections; ++j) {
        if (j == i) continue;
        r = r * section(j, p);
      }
      r = r / (m * (p * p * (p + Cx<T>(a))));
      const T decay = exp(-c * Ts / T(2.0));
      const T ang = wd * Ts;
      const T half = sin(ang / T(2.0));
      pole[i] = Cx<T>(decay * cos(ang), decay * sin(ang));
      const Cx<T> em1(expm1(-c * Ts / T(2.0)) * cos(ang) - T(2.0) * half * half,
                      decay * sin(ang));
      coeff[i] = r * em1;
    }
    return true;
  }

  // G_d(z), without any delay factor.
  Cx<T> At(double z_re, double z_im) const {
    const Cx<T> z{T(z_re), T(z_im)};
    Cx<T> g = Cx<T>(integrator) / (z - Cx<T>(T(1.0)));
    g = g + Cx<T>(rigid_coeff) / (z - Cx<T>(rigid_pole));
    for (size_t k = 0; k < pole.size(); ++k) {
      g = g + coeff[k] / (z - pole[k]) + Conj(coeff[k]) / (z - Conj(pole[k]));
    }
    return g;
  }
};

}  // namespace zwidth::model
