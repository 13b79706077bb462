#include "stability/sampled_plant.h"

#include <cmath>
#include <numbers>
#include <string>

#include <Eigen/Eigenvalues>

#include "model/error.h"
#include "stability/closed_loop.h"
#include "stability/haptic_loop.h"

namespace zwidth::stability {
namespace {

// How far the double pole-residue sum may stray from its long double
// evaluation at a check point for the form to be used (see the constructor):
// a tenth of the 1e-10 its agreement with the state space is held to, for the
// points between the checks.
constexpr double kModalRoundingTolerance = 1e-11;

std::vector<double> PolyMul(const std::vector<double>& a, const std::vector<double>& b) {
  std::vector<double> r(a.size() + b.size() - 1, 0.0);
  for (size_t i = 0; i < a.size(); ++i)
    for (size_t j = 0; j < b.size(); ++j) r[i + j] += a[i] * b[j];
  return r;
}

model::StateSpace Sampled(const model::Plant& plant, double period_s, const Hand& hand) {
  plant.Validate();
  LoopOptions l;
  l.hand = hand;
  std::string why;
  if (!l.IsValid(&why)) throw InputError("loop options: " + why);
  model::StateSpace d = hand.IsNone() ? model::DiscretizeZoh(plant, period_s)
                               : DiscretizeZohStateSpace(ContinuousStateSpaceWithHand(plant, hand), period_s);
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
  d->g_minus_one = d->response.AtZ(-1.0);
  d->conditioning = Conditioning(discrete.A, d->has_integrator);
  d_ = std::move(d);
}

std::complex<double> SampledPlant::Gd(std::complex<double> z) const {
  if (!d_->use_modal) return d_->response.AtZ(z);
  const model::Cx<double> g = d_->modal.At(z.real(), z.imag());
  return {g.re, g.im};
}

std::complex<double> SampledPlant::AtTheta(double theta) const {
  const std::complex<double> z = std::polar(1.0, theta);
  return d_->response.AtZ(z) * std::polar(1.0, -theta * d_->plant.delay_samples);
}

}  // namespace zwidth::stability
