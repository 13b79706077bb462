// period_rule_print MODEL PERIOD DELAY: K_CR(0) of MODEL used at PERIOD with
// the loop delay DELAY through the C++ API (analysis::AnalysePlantStability),
// printed to the last digit (%.17g), for tests/period_rule_test.sh to compare
// with the CLI and Python. Exit 2 with the message on a refused input.
#include <cstdio>
#include <cstdlib>
#include <exception>

#include "analysis/plant_stability.h"
#include "io/model_json.h"

int main(int argc, char** argv) {
  if (argc != 4) {
    std::fprintf(stderr, "usage: period_rule_print MODEL PERIOD DELAY\n");
    return 2;
  }
  try {
    const zwidth::io::ModelFile m = zwidth::io::ReadModelJson(argv[1]);
    const auto r = zwidth::analysis::AnalysePlantStability(m, std::strtod(argv[2], nullptr),
                                                           {.delays = {std::atoi(argv[3])}});
    std::printf("%.17g\n", r.summaries.at(0).K_cr_at_zero_B);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 2;
  }
  return 0;
}
