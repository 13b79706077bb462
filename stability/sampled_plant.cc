#include "stability/sampled_plant.h"

#include <array>
#include <cmath>
#include <limits>
#include <memory>
#include <numbers>
#include <string>

#include <Eigen/Eigenvalues>

#include "model/error.h"
#include "model/state_space.h"
#include "model/state_space_internal.h"
#include "stability/closed_loop.h"
#include "stability/hand.h"
#include "stability/loop_options.h"
#include "stability/numerics_internal.h"

namespace zwidth::stability {
namespace {

using internal::PolyMul;

// How far the double pole-residue sum may stray from its long double
// evaluation at a check point for the form to be used (see the constructor):
// a tenth of the 1e-10 its agreement with the state space is held to, for the
// points between the checks.
constexpr double kModalRoundingTolerance = 1e-11;

model::StateSpace Sampled(const model::Plant& plant, double period_s, const Hand& hand) {
  plant.Validate();
  LoopOptions l;
  l.hand = hand;
  std::string why;
  if (!l.IsValid(&why)) throw InputError("loop options: " + why);
  model::StateSpace d = hand.IsNone() ? model::DiscretizeZoh(plant, period_s)
                               : model::DiscretizeZoh(ContinuousStateSpaceWithHand(plant, hand), period_s);
  d.delay_samples = 0;  // delays are handled by the caller
  return d;
}

// D(z) / (z - 1) (without the integrator's pole when has_integrator) from the
// exactly known discrete poles e^{pT}; *hand_poles gets the continuous poles
// with Im > 0 of the plant with the hand (none without a hand).
std::vector<double> DiscreteDenominator(const model::Plant& plant, double T, const Hand& hand_in, bool has_integrator,
                                        std::vector<std::complex<double>>* hand_poles,
                                        std::vector<std::complex<double>>* roots) {
  const bool hand = !hand_in.IsNone();
  std::vector<double> den1 = {1.0};
  if (!hand) {
    den1 = PolyMul(den1, {-std::exp(-plant.b / plant.m * T), 1.0});
    roots->push_back(std::exp(-plant.b / plant.m * T));
    for (const model::Mode& md : plant.modes) {
      const double disc = md.c * md.c / 4.0 - md.omega * md.omega;
      if (disc < 0.0) {
        const double r = std::exp(-md.c * T / 2.0), wd = std::sqrt(-disc);
        den1 = PolyMul(den1, {r * r, -2.0 * r * std::cos(wd * T), 1.0});
        roots->push_back(std::polar(r, wd * T));
        roots->push_back(std::polar(r, -wd * T));
      } else {
        const double s = std::sqrt(disc);
        den1 = PolyMul(den1, {-std::exp((-md.c / 2.0 + s) * T), 1.0});
        den1 = PolyMul(den1, {-std::exp((-md.c / 2.0 - s) * T), 1.0});
        roots->push_back(std::exp((-md.c / 2.0 + s) * T));
        roots->push_back(std::exp((-md.c / 2.0 - s) * T));
      }
    }
  } else {
    // With the hand the poles are the eigenvalues of the continuous A_h (the
    // ZOH maps each to e^{lambda T}). Without hand stiffness the position state
    // is not fed back: A_h keeps an exact zero eigenvalue, the integrator.
    Eigen::VectorXcd ev = ContinuousStateSpaceWithHand(plant, hand_in).A.eigenvalues();
    int skip = -1;
    if (has_integrator) {
      ev.cwiseAbs().minCoeff(&skip);
    }
    for (int i = 0; i < ev.size(); ++i) {
      if (i == skip) continue;
      const std::complex<double> l = ev(i);
      if (l.imag() > 0.0) {
        const double r = std::exp(l.real() * T);
        den1 = PolyMul(den1, {r * r, -2.0 * r * std::cos(l.imag() * T), 1.0});
        hand_poles->push_back(l);
        roots->push_back(std::exp(l * T));
        roots->push_back(std::exp(std::conj(l) * T));
      } else if (l.imag() == 0.0) {
        den1 = PolyMul(den1, {-std::exp(l.real() * T), 1.0});
        roots->push_back(std::exp(l.real() * T));
      }
    }
  }
  return den1;
}

// The eigenvalues of the balanced discrete A, their condition numbers from the
// right eigenvectors V and the left ones (the rows of V^-1), and LAPACK's
// error bound eps |A|_F kappa_i against each pole's distance to the circle.
PoleConditioning Conditioning(const Eigen::MatrixXd& A, bool has_integrator) {
  PoleConditioning c;
  const Eigen::VectorXd sc = model::internal::BalancingScales(A);
  const Eigen::MatrixXd Ab = sc.cwiseInverse().asDiagonal() * A * sc.asDiagonal();
  Eigen::EigenSolver<Eigen::MatrixXd> es(Ab, true);
  if (es.info() != Eigen::Success) return c;
  const Eigen::VectorXcd z = es.eigenvalues();
  const Eigen::MatrixXcd V = es.eigenvectors();
  const Eigen::MatrixXcd W = V.inverse();
  const int n = static_cast<int>(z.size());
  int integrator = -1;
  if (has_integrator) (z.array() - 1.0).abs().minCoeff(&integrator);
  const double norm = Ab.norm();
  double min_gap = std::numeric_limits<double>::infinity(), spread = 0.0;
  c.eigenvalue_condition = 0.0;
  c.eigenvalue_shift = 0.0;
  for (int i = 0; i < n; ++i) {
    for (int j = i + 1; j < n; ++j) {
      const double g = std::abs(z(i) - z(j));
      min_gap = std::min(min_gap, g);
      spread = std::max(spread, g);
    }
    const double kappa = V.col(i).norm() * W.row(i).norm();
    c.eigenvalue_condition = std::max(c.eigenvalue_condition, kappa);
    if (i == integrator) continue;
    const double shift = 2.220446049250313e-16 * norm * kappa / (1.0 - std::abs(z(i)));
    c.eigenvalue_shift = std::max(c.eigenvalue_shift, shift >= 0.0 ? shift : INFINITY);
  }
  c.relative_separation = n > 1 && spread > 0.0 ? min_gap / spread : 1.0;
  return c;
}

}  // namespace

namespace internal {
#if defined(__SIZEOF_FLOAT128__)
// IEEE binary128 (113-bit significand, eps 2^-112 = 1.9e-34) through GCC's and
// clang's __float128: the arithmetic is libgcc's, and the functions that
// ZohModalForm::Build needs are written here (no libquadmath), each to a few
// eps: exp and expm1 by Taylor series after halving the argument below 1/2,
// sin and cos by Taylor series after reducing by 2 pi (2 pi as a sum of two
// doubles, exact to ~1e-32).
struct Quad {
  __float128 v = 0;
  Quad() = default;
  Quad(double d) : v(d) {}  // NOLINT: ZohModalForm writes T(2.0)
  static Quad Of(__float128 q) { Quad r; r.v = q; return r; }
  friend Quad operator+(Quad a, Quad b) { return Of(a.v + b.v); }
  friend Quad operator-(Quad a, Quad b) { return Of(a.v - b.v); }
  friend Quad operator*(Quad a, Quad b) { return Of(a.v * b.v); }
  friend Quad operator/(Quad a, Quad b) { return Of(a.v / b.v); }
  friend Quad operator-(Quad a) { return Of(-a.v); }
  friend bool operator>(Quad a, Quad b) { return a.v > b.v; }
  friend Quad sqrt(Quad x) {
    if (!(x.v > 0)) return Of(x.v == 0 ? 0.0 : std::numeric_limits<double>::quiet_NaN());
    __float128 y = std::sqrt(static_cast<double>(x.v));
    for (int i = 0; i < 3; ++i) y = 0.5 * (y + x.v / y);  // Newton: 53 -> 106 -> 113 bits
    return Of(y);
  }
  friend Quad expm1(Quad x) {
    if (!(x.v < 0.5 && x.v > -0.5)) {
      const Quad e = expm1(Of(x.v / 2));  // e^x - 1 = (e^{x/2} - 1)(e^{x/2} + 1)
      return e * (e + Of(2));
    }
    __float128 sum = 0, term = 1;
    for (int k = 1; k < 60; ++k) {
      term *= x.v / k;
      sum += term;
      if (!(term > 1e-38 * (sum > 0 ? sum : -sum) || -term > 1e-38 * (sum > 0 ? sum : -sum))) break;
    }
    return Of(sum);
  }
  friend Quad exp(Quad x) {
    int halvings = 0;
    while (!(x.v < 0.5 && x.v > -0.5) && halvings < 64) { x.v /= 2; ++halvings; }
    Quad e = Of(1) + expm1(x);  // relative error a few eps, doubled by each squaring
    for (int i = 0; i < halvings; ++i) e = e * e;
    return e;
  }
  static Quad Reduced(Quad x) {  // x - 2 pi k in [-pi, pi]
    const __float128 two_pi = static_cast<__float128>(6.283185307179586) + static_cast<__float128>(2.4492935982947064e-16);
    const double k = std::nearbyint(static_cast<double>(x.v / two_pi));
    return Of(x.v - static_cast<__float128>(k) * two_pi);
  }
  friend Quad sin(Quad x) {
    const __float128 r = Reduced(x).v, r2 = r * r;
    __float128 sum = r, term = r;
    for (int k = 1; k < 40; ++k) { term *= -r2 / ((2 * k) * (2 * k + 1)); sum += term; }
    return Of(sum);
  }
  friend Quad cos(Quad x) {
    const __float128 r = Reduced(x).v, r2 = r * r;
    __float128 sum = 1, term = 1;
    for (int k = 1; k < 40; ++k) { term *= -r2 / ((2 * k - 1) * (2 * k)); sum += term; }
    return Of(sum);
  }
};
#endif

#if defined(__SIZEOF_FLOAT128__)
// Double-double (Dekker 1971; Hida, Li and Bailey's QD library): hi + lo with
// |lo| <= ulp(hi) / 2, ~106 bits from double operations alone (Dekker's split,
// no FMA assumed). The binary128 form's poles and residues are rounded to it
// once, and each evaluation sums in it: ~4 times faster than libgcc's soft
// binary128, its rounding 2^-104 per operation.
struct DD {
  double hi = 0.0, lo = 0.0;
};
inline DD TwoSum(double a, double b) {
  const double s = a + b, bb = s - a;
  return {s, (a - (s - bb)) + (b - bb)};
}
inline DD QuickTwoSum(double a, double b) {
  const double s = a + b;
  return {s, b - (s - a)};
}
inline DD TwoProd(double a, double b) {
  const double p = a * b;
  const double ta = 134217729.0 * a, ah = ta - (ta - a), al = a - ah;
  const double tb = 134217729.0 * b, bh = tb - (tb - b), bl = b - bh;
  return {p, ((ah * bh - p) + ah * bl + al * bh) + al * bl};
}
inline DD operator+(DD a, DD b) {
  DD s = TwoSum(a.hi, b.hi);
  s.lo += a.lo + b.lo;
  return QuickTwoSum(s.hi, s.lo);
}
inline DD operator-(DD a, DD b) { return a + DD{-b.hi, -b.lo}; }
inline DD operator*(DD a, DD b) {
  DD p = TwoProd(a.hi, b.hi);
  p.lo += a.hi * b.lo + a.lo * b.hi;
  return QuickTwoSum(p.hi, p.lo);
}
inline DD Reciprocal(DD b) {  // 1 / b by two corrections of the double quotient
  const double q1 = 1.0 / b.hi;
  DD r = DD{1.0, 0.0} - DD{q1, 0.0} * b;
  const double q2 = r.hi / b.hi;
  r = r - DD{q2, 0.0} * b;
  return QuickTwoSum(q1, q2) + DD{r.hi / b.hi, 0.0};
}
inline DD ToDD(__float128 q) {
  const double hi = static_cast<double>(q);
  return {hi, static_cast<double>(q - hi)};
}
#endif

}  // namespace internal

struct SampledPlant::Binary128Modal {
#if defined(__SIZEOF_FLOAT128__)
  model::ZohModalForm<internal::Quad> form;
  // Each term n / (z - p) of the form, upper poles and their conjugates, in
  // double-double: re n, im n, re p, im p.
  std::vector<std::array<internal::DD, 4>> terms;
#endif
};

namespace {

#if defined(__SIZEOF_FLOAT128__)
using internal::Quad;
using internal::DD;
using internal::ToDD;

// G_d(z) = the pole-residue sum in binary128 at z = c + j s, and in *abs_sum
// (when given) sum |t_k| of its terms (|re| + |im|).
std::complex<double> Binary128At(const model::ZohModalForm<Quad>& f, double c, double s, double* abs_sum) {
  using Q = __float128;
  const Q zr = c, zi = s;
  Q gr = 0, gi = 0;
  double mag = 0.0;
  auto add = [&](Q nr, Q ni, Q pr, Q pi) {  // (nr + j ni) / (z - (pr + j pi))
    const Q dr = zr - pr, di = zi - pi, inv = 1 / (dr * dr + di * di);
    const Q tr = (nr * dr + ni * di) * inv, ti = (ni * dr - nr * di) * inv;
    gr += tr;
    gi += ti;
    if (abs_sum) mag += std::abs(static_cast<double>(tr)) + std::abs(static_cast<double>(ti));
  };
  add(f.integrator.v, 0, 1, 0);
  add(f.rigid_coeff.v, 0, f.rigid_pole.v, 0);
  for (size_t k = 0; k < f.pole.size(); ++k) {
    add(f.coeff[k].re.v, f.coeff[k].im.v, f.pole[k].re.v, f.pole[k].im.v);
    add(f.coeff[k].re.v, -f.coeff[k].im.v, f.pole[k].re.v, -f.pole[k].im.v);
  }
  if (abs_sum) *abs_sum = mag;
  return {static_cast<double>(gr), static_cast<double>(gi)};
}

// The same sum in double-double from Binary128Modal::terms.
std::complex<double> DoubleDoubleAt(const std::vector<std::array<DD, 4>>& terms, double c, double s) {
  const DD zr{c, 0.0}, zi{s, 0.0};
  DD gr, gi;
  for (const std::array<DD, 4>& t : terms) {
    const DD dr = zr - t[2], di = zi - t[3], inv = Reciprocal(dr * dr + di * di);
    gr = gr + (t[0] * dr + t[1] * di) * inv;
    gi = gi + (t[1] * dr - t[0] * di) * inv;
  }
  return {gr.hi + gr.lo, gi.hi + gi.lo};
}
#endif

}  // namespace

// Where the pole-residue form fails in double (its terms cancel: crowded,
// lightly damped modes), the same form in binary128 when its rounding stays
// below 1e-12 of |G_d| at the check points (16 uniform, every 160th mode-patch
// point: each patch's centre and edges, where the cancellation peaks): each
// term comes from exact parameters through ~n + 6 roundings and the sum adds
// one per term, so the error is at most 4 (n + 3) 2^-112 sum |t_k|. 64
// sections 1 % apart at damping 1e-4 cancel by 2e14: 1e-17 of |G_d|, where the
// double state space errs by 1e-3 (its poles rounded; conditioning()) and its
// rounding makes B(theta) jagged (23844 extrema on the boundary grid; 128 in
// binary128). Evaluated in double-double (DD above, checked against the
// binary128 sum). nullptr where binary128 is not available or a check fails.
std::shared_ptr<const SampledPlant::Binary128Modal> SampledPlant::Binary128Form(const model::Plant& plant, double T,
                                                                                 const std::vector<double>& patch_theta) {
#if defined(__SIZEOF_FLOAT128__)
  auto q = std::make_shared<Binary128Modal>();
  std::vector<Quad> sec;
  for (const model::Mode& md : plant.modes) sec.insert(sec.end(), {md.omega, md.c, md.v, md.d});
  if (!q->form.Build(Quad(plant.m), Quad(plant.b), sec.data(), static_cast<int>(plant.modes.size()), T)) return nullptr;
  std::vector<double> check;
  for (int k = 1; k <= 16; ++k) check.push_back(std::numbers::pi * (k - 0.5) / 16.0);
  for (size_t i = 0; i < patch_theta.size(); i += 2 * kModePatchHalfWidth / 4) check.push_back(patch_theta[i]);
  const double bound = 4.0 * (static_cast<double>(plant.modes.size()) + 3.0) * 1.925929944387236e-34;
  for (double th : check) {
    double mag = 0.0;
    const std::complex<double> g = Binary128At(q->form, std::cos(th), std::sin(th), &mag);
    if (!(bound * mag <= 1e-12 * std::abs(g))) return nullptr;
  }
  // The evaluations sum in double-double: its rounding (~12 operations of
  // 2^-104 per term, 4e-31 sum |t_k|) is checked against the binary128 sum
  // at the same points.
  const model::ZohModalForm<Quad>& f = q->form;
  q->terms.push_back({ToDD(f.integrator.v), DD{}, DD{1.0, 0.0}, DD{}});
  q->terms.push_back({ToDD(f.rigid_coeff.v), DD{}, ToDD(f.rigid_pole.v), DD{}});
  for (size_t k = 0; k < f.pole.size(); ++k) {
    for (const __float128 sign : {1, -1}) {
      q->terms.push_back({ToDD(f.coeff[k].re.v), ToDD(sign * f.coeff[k].im.v), ToDD(f.pole[k].re.v),
                          ToDD(sign * f.pole[k].im.v)});
    }
  }
  for (double th : check) {
    const std::complex<double> a = DoubleDoubleAt(q->terms, std::cos(th), std::sin(th));
    const std::complex<double> b = Binary128At(f, std::cos(th), std::sin(th), nullptr);
    if (!(std::abs(a - b) <= 1e-13 * std::abs(b))) return nullptr;
  }
  return q;
#else
  (void)plant; (void)T; (void)patch_theta;
  return nullptr;
#endif
}

namespace {

// The double pole-residue sum against the same sum in long double at the 16
// uniform points and every 40th point of the mode patches (see the
// constructor): within kModalRoundingTolerance, relative, at every one.
bool ModalRoundingIsSmall(const model::Plant& plant, double T, const model::ZohModalForm<double>& modal,
                          const std::vector<double>& patch_theta) {
  std::vector<long double> sec;
  for (const model::Mode& md : plant.modes) sec.insert(sec.end(), {md.omega, md.c, md.v, md.d});
  model::ZohModalForm<long double> wide;
  if (!wide.Build(plant.m, plant.b, sec.data(), static_cast<int>(plant.modes.size()), T)) return false;
  std::vector<double> check;
  for (int k = 1; k <= 16; ++k) check.push_back(std::numbers::pi * (k - 0.5) / 16.0);
  for (size_t i = 0; i < patch_theta.size(); i += 40) check.push_back(patch_theta[i]);
  for (double th : check) {
    const double c = std::cos(th), s = std::sin(th);
    const model::Cx<double> a = modal.At(c, s);
    const model::Cx<long double> b = wide.At(c, s);
    const long double dr = a.re - b.re, di = a.im - b.im;
    if (!(std::sqrt(dr * dr + di * di) <= kModalRoundingTolerance * std::sqrt(b.re * b.re + b.im * b.im))) {
      return false;
    }
  }
  return true;
}

}  // namespace

SampledPlant::SampledPlant(const model::Plant& plant, double period_s, const Hand& hand_in) {
  const model::StateSpace discrete = Sampled(plant, period_s, hand_in);
  auto d = std::make_shared<Data>(discrete);
  d->discrete = discrete;
  d->plant = plant;
  d->period_s = period_s;
  d->hand = hand_in;
  const double T = period_s;
  const bool hand = !hand_in.IsNone();
  bool modal_built = false;
  d->has_integrator = !(hand_in.K > 0.0);
  // The rigid body's position (m theta) is the cascade's last state but one
  // (model/state_space.h); nothing else depends on it without hand stiffness.
  d->position_state = d->has_integrator ? static_cast<int>(discrete.A.rows()) - 2 : -1;
  if (!hand) {
    std::vector<double> sec;
    for (const model::Mode& md : plant.modes) sec.insert(sec.end(), {md.omega, md.c, md.v, md.d});
    modal_built = d->modal.Build(plant.m, plant.b, sec.data(), static_cast<int>(plant.modes.size()), T);
    d->use_modal = modal_built;
    // Trust the faster form only where it agrees with the state-space response
    // (near-coincident poles make its residues cancel).
    for (int k = 1; d->use_modal && k <= 16; ++k) {
      const std::complex<double> z = std::polar(1.0, std::numbers::pi * (k - 0.5) / 16.0);
      const model::Cx<double> a = d->modal.At(z.real(), z.imag());
      const std::complex<double> b = d->response.AtZ(z);
      if (!(std::abs(std::complex<double>(a.re, a.im) - b) <= 1e-10 * std::abs(b))) d->use_modal = false;
    }
    // Where they disagree either form can be the wrong one. The pole-residue
    // form is exact algebra on the modes' parameters (model/zoh_modal.h): its
    // only error is rounding, chiefly the cancellation among its terms, which
    // grows with crowding (sum |t_k| / |G_d| ~ 1e14 for 64 sections 1 % apart
    // at damping 1e-4). The state space's error is the matrix exponential's:
    // with many modes over a wide band |A T| is large (64 sections 8 % apart
    // reach 6 kHz at 1 kHz sampling, |A T| ~ 38) and its response is off by
    // 1.7e-8 against the pole-residue form in long double, where the double
    // pole-residue sum is within 7e-13 of it (cancellation 5e2). So the form is
    // also kept when its double sum stays within kModalRoundingTolerance of
    // the same sum in long double (3 more digits) at the check points: the
    // uniform 16 and every 40th point of the mode patches, where the
    // cancellation peaks; it is then exact to ~1e-10 between them, and each
    // point costs O(n) instead of the Hessenberg solve's O(n^2).
  }
  // Denominator from the exactly known discrete poles e^{pT}.
  std::vector<std::complex<double>> hand_poles;  // continuous poles with Im > 0 (hand only)
  std::vector<std::complex<double>> poles;
  d->den1 = DiscreteDenominator(plant, T, hand_in, d->has_integrator, &hand_poles, &poles);
  const std::vector<double>& den1 = d->den1;
  d->den = d->has_integrator ? PolyMul(den1, {-1.0, 1.0}) : den1;
  for (const std::complex<double>& r : poles) {
    const double shift = RootDisplacementBound(d->den, {r}) / (1.0 - std::abs(r));
    d->denominator_pole_shift = std::max(d->denominator_pole_shift, shift >= 0.0 ? shift : INFINITY);
  }
  // Numerator by interpolation at n rotated roots of unity (none is a pole).
  const int n = static_cast<int>(d->den.size()) - 1;
  d->num.assign(n, 0.0);
  for (int k = 0; k < n; ++k) {
    const std::complex<double> z = std::polar(1.0, (2.0 * std::numbers::pi * k + std::numbers::pi) / n);
    std::complex<double> dz = 0.0, zp = 1.0;
    for (double c : d->den) { dz += c * zp; zp *= z; }
    const std::complex<double> nz = d->response.AtZ(z) * dz;
    std::complex<double> zm = 1.0;
    for (int m = 0; m < n; ++m) { d->num[m] += (nz / zm).real() / n; zm *= z; }
  }
  // Dense patches around every resonance and antiresonance (width ~ damping
  // * T), so that the boundary grid resolves sharp modes; inside the grid's
  // ends pi 1e-7 and pi (1 - 1e-9).
  const double pi = std::numbers::pi;
  // Every point of a patch inside the grid's ends is kept (641 points, +-20
  // c T around the damped frequency).
  const double first = pi * 1e-7, last = pi * (1.0 - 1e-9);
  auto patch = [&](double w, double c) {
    const double disc = w * w - c * c / 4.0;
    if (disc <= 0.0) return;
    const double center = std::sqrt(disc) * T;
    const double h = std::max(c * T / 16.0, 1e-9);
    for (int k = -kModePatchHalfWidth; k <= kModePatchHalfWidth; ++k) {
      const double t = center + k * h;
      if (t > first && t < last) d->patch_theta.push_back(t);
    }
  };
  for (const model::Mode& md : plant.modes) {
    if (!hand) patch(md.omega, md.c);
    patch(md.v, md.d);  // the hand leaves G's zeros where they are
  }
  for (const std::complex<double>& l : hand_poles) patch(std::abs(l), -2.0 * l.real());
  if (modal_built && !d->use_modal) d->use_modal = ModalRoundingIsSmall(plant, T, d->modal, d->patch_theta);
  if (modal_built && !d->use_modal) d->quad = Binary128Form(plant, T, d->patch_theta);
  d->g_minus_one = d->response.AtZ(-1.0);
  d->conditioning = Conditioning(discrete.A, d->has_integrator);
  d_ = std::move(d);
}

std::complex<double> SampledPlant::Gd(std::complex<double> z) const {
#if defined(__SIZEOF_FLOAT128__)
  if (d_->quad) return DoubleDoubleAt(d_->quad->terms, z.real(), z.imag());
#endif
  if (!d_->use_modal) return d_->response.AtZ(z);
  const model::Cx<double> g = d_->modal.At(z.real(), z.imag());
  return {g.re, g.im};
}

std::complex<double> SampledPlant::AtTheta(double theta) const {
  const std::complex<double> z = std::polar(1.0, theta);
  return d_->response.AtZ(z) * std::polar(1.0, -theta * d_->plant.delay_samples);
}

}  // namespace zwidth::stability
