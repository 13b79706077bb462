// The fleet report of `zwidth batch --fleet-report FILE.html` (issue 28): one
// self-contained HTML file, as the run report is (its style; figures as
// inline SVG, nothing loaded from elsewhere): the counts, the table of
// failures and outliers with their reasons, every unit's region (K_CR(B) on
// the paper's loop, from the unit's fitted model in the table) overlaid with
// the design's, and per parameter and figure the distribution with its
// median, MAD sigma, the design's value and the specs' bounds.
#pragma once

#include <string>

#include "analysis/batch.h"
#include "analysis/population.h"
#include "io/batch_table.h"
#include "io/design_file.h"

namespace zwidth::report {

// The page's text. `design` may be null (no design: no overlay of its region).
std::string FleetHtml(const io::BatchTable& table, const analysis::Population& population, const io::Design* design,
                      const analysis::BatchOptions& options, const std::string& command_line);

}  // namespace zwidth::report
