// The population of a batch (issue 28): per parameter and per Z-width figure
// a robust centre and spread, and each unit's robust Mahalanobis distance
// from the population with the columns that make it an outlier. Reads the
// table `zwidth batch` writes (analysis/batch.h); prints nothing.
//
// Centre and spread of a column over the units with status ok and a finite
// value: the median x~ and the MAD scaled to a normal's sigma,
//   s = 1.4826 median_i |x_i - x~|.
// The population's covariance S (the orthogonalized Gnanadesikan-Kettenring
// estimate, Maronna & Zamar 2002, one step): with y_j = (x_j - x~_j) / s_j,
//   r_jk = (s(y_j + y_k)^2 - s(y_j - y_k)^2) / (s(y_j + y_k)^2 + s(y_j - y_k)^2)
// (s() the scaled MAD), R = [r_jk] made positive definite by raising its
// eigenvalues to at least 1e-3 of the largest, S = D R D with D = diag(s_j).
// A unit's distance uses its own covariance C_i too (the table holds each
// value's std, so C_i = diag(std_ij^2); a std not known counts 0):
//   D_i^2 = (x_i - x~)^T (S + C_i)^{-1} (x_i - x~),
// so a deviation within the unit's own noise counts less. Without defects
// D_i^2 is about chi-square with p (the columns) degrees of freedom; a unit is
// an outlier when D_i^2 exceeds its quantile at `outlier_quantile` (by
// Wilson-Hilferty: p (1 - 2/(9p) + z sqrt(2/(9p)))^3, z the normal quantile),
// or when it lacks a column of the distance (a mode fewer), or has another
// number of modes than the population's median, or its fit is poor where
// most of the population's are not (the model lacks what its response has:
// an extra mode forced into the design's order, friction). The reasons name the columns
// whose own z_ij = (x_ij - x~_j) / sqrt(S_jj + C_i,jj) exceeds reason_z.
#pragma once

#include <string>
#include <vector>

#include "io/batch_table.h"

namespace zwidth::analysis {

struct PopulationOptions {
  // D^2 above the chi-square quantile at this probability is an outlier; in (0.5, 1).
  double outlier_quantile = 0.999;
  // A column is named in an outlier's reasons when |z| exceeds this; > 0.
  double reason_z = 3.0;
  // Fewest units with status ok for statistics (and distances); >= 3.
  size_t min_units = 5;
  bool IsValid(std::string* why) const;
};

struct PopulationColumn {
  std::string column;   // a value column of the table: m, b, mode<i>_<field>, d<d>_<figure>
  size_t units = 0;     // units with a finite value
  double median = 0.0;  // the robust centre
  double mad_sigma = 0.0;  // 1.4826 MAD: the robust spread (a normal's sigma)
  double min = 0.0, max = 0.0;
  bool in_distance = false;  // one of the distance's columns
};

struct PopulationUnit {
  std::string serial;
  bool ok = false;          // status ok (else no distance: the unit failed)
  double distance2 = 0.0;   // D_i^2 (nan when not computed)
  bool outlier = false;
  std::string reasons;      // why an outlier ('; ' between), "" otherwise
};

enum class PopulationStatus { kNotRun, kOk, kTooFewUnits };
std::string ToString(PopulationStatus s);

struct Population {
  PopulationStatus status = PopulationStatus::kNotRun;  // kOk: the numbers can be used
  std::string message;
  size_t ok_units = 0;
  double median_modes = 0.0;                // the population's number of modes
  std::vector<PopulationColumn> columns;    // every value column, in the table's order
  std::vector<std::string> distance_columns;
  double threshold = 0.0;                   // the chi-square quantile of D^2 for outliers
  std::vector<PopulationUnit> units;        // one per row, in the table's order
};

// InputError for invalid options (naming PopulationOptions::field).
Population AnalysePopulation(const io::BatchTable& table, const PopulationOptions& options = {});

// The quantile of chi-square with k degrees of freedom at probability q (Wilson-Hilferty).
double ChiSquareQuantile(double q, int k);

// The population table: one row per column (column, units, median, mad_sigma,
// min, max, in_distance) then the outlier threshold as a row "D2_threshold".
io::BatchTable PopulationTable(const Population& p);
// The table's rows with the columns outlier (yes | no | ""), outlier_d2 and
// outlier_reasons set from p (its units in the table's order).
void AddOutlierColumns(const Population& p, io::BatchTable* table);

}  // namespace zwidth::analysis
