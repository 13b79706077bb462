// --modes auto: fits 0..max_modes sections and keeps the order with the lowest
// BIC among those without a spurious section; the stabilisation table.
#include <algorithm>
#include <cassert>
#include <cmath>
#include <iomanip>
#include <limits>
#include <sstream>
#include <vector>

#include "fit/fit_internal.h"

namespace zwidth::fit::internal {
namespace {

// BIC on the weighted residual: chi2 / (kappa s2) + p ln(N / kappa), with
// kappa the bins' correlation (N / kappa independent residuals) and s2 the
// noise level that the per-bin std misses, read from the largest model (as
// Mallows' Cp does): the lowest chi2/dof of all orders tried, at least 1.
double Bic(const FitResult& r, double kappa, double s2) {
  kappa = std::max(1.0, kappa);
  return 2.0 * r.cost / (kappa * std::max(1.0, s2)) + r.num_parameters * std::log(r.num_residuals / kappa);
}

// One row of the stabilisation table for the fit fx of n sections; prev is
// the row of n - 1 sections (nullptr for n = 0).
OrderTrial TableRow(const Fixed& fx, int n, const OrderTrial* prev, const FitOptions& o) {
  OrderTrial t;
  t.num_modes = n;
  t.converged = fx.res.status == FitStatus::kConverged;
  t.chi2_per_dof = fx.res.chi2_per_dof;
  t.delay_samples = fx.res.plant.delay_samples;
  for (const model::Mode& md : fx.res.plant.modes) t.pole_hz.push_back(md.omega / kHz);
  for (double f : t.pole_hz) {
    bool persists = false;
    if (prev) for (double g : prev->pole_hz) persists |= std::abs(f / g - 1) < 0.02;
    t.persists.push_back(persists);
  }
  t.spurious = SpuriousSections(fx.res, o);
  if (!t.converged) t.spurious.push_back("the solver did not converge");
  return t;
}

// Why order `pick` was chosen, and the first larger order rejected.
std::string OrderChoice(const std::vector<OrderTrial>& table, int pick) {
  std::ostringstream os;
  os << pick << " modes: the lowest BIC (" << std::setprecision(6) << table[pick].bic
     << ") among the orders 0.." << table.size() - 1 << " without a spurious section";
  for (const OrderTrial& t : table) {
    if (t.num_modes > pick && !t.spurious.empty()) {
      os << "; " << t.num_modes << " rejected (" << t.spurious.front() << ")";
      break;
    }
  }
  return os.str();
}

}  // namespace

Fixed FitOrders(const ident::FrequencyResponse& sub, const ident::ExcitedBand& band, double sample_rate_hz,
                const FitOptions& o) {
  std::vector<Fixed> fits;
  std::vector<OrderTrial> table;
  for (int n = 0; n <= o.max_modes; ++n) {
    if (2 * band.num_used <= 2 + 4 * n) break;
    std::vector<model::Plant> extra;
    if (n > 0 && fits.back().res.status == FitStatus::kConverged) extra = GrowStarts(fits.back());
    fits.push_back(FitFixed(sub, o, n, extra, /*rescreen_poor=*/false));
    Fixed& fx = fits.back();
    fx.res.band = band;
    fx.res.band_sample_rate_hz = sample_rate_hz;
    table.push_back(TableRow(fx, n, n > 0 ? &table.back() : nullptr, o));
  }
  assert(!fits.empty());
  double s2 = std::numeric_limits<double>::infinity();
  for (const Fixed& fx : fits) if (fx.res.status == FitStatus::kConverged) s2 = std::min(s2, fx.res.chi2_per_dof);
  if (!std::isfinite(s2)) s2 = 1.0;
  const double kappa = std::max(1.0, sub.bin_correlation);
  int pick = -1;
  for (size_t i = 0; i < table.size(); ++i) {
    table[i].bic = Bic(fits[i].res, kappa, s2);
    if (table[i].spurious.empty() && (pick < 0 || table[i].bic < table[pick].bic)) pick = static_cast<int>(i);
  }
  if (pick < 0) pick = 0;
  // The orders were fitted without the delay search's re-screening of a poor
  // fit (the orders below the right one are all poor): the chosen one gets
  // it when it is poor.
  if (o.auto_delay && fits[pick].res.status == FitStatus::kConverged &&
      fits[pick].res.chi2_per_dof > Chi2Limit(fits[pick].res, sub)) {
    std::vector<model::Plant> extra;
    if (pick > 0 && fits[pick - 1].res.status == FitStatus::kConverged) extra = GrowStarts(fits[pick - 1]);
    Fixed again = FitFixed(sub, o, pick, extra);
    if (again.res.status == FitStatus::kConverged && again.res.cost < fits[pick].res.cost) {
      again.res.band = band;
      again.res.band_sample_rate_hz = sample_rate_hz;
      table[pick].delay_samples = again.res.plant.delay_samples;
      table[pick].chi2_per_dof = again.res.chi2_per_dof;
      fits[pick] = std::move(again);
    }
  }
  Fixed chosen = std::move(fits[pick]);
  chosen.res.order_table = table;
  chosen.res.order_choice = OrderChoice(table, pick);
  return chosen;
}

}  // namespace zwidth::fit::internal
