// A model file to its Z-width: reads model.json (as `zwidth fit` writes it,
// or datasets/phantom/table1.json) and prints, per loop delay, K_CR at B = 0,
// the transition damping B_t, the largest K_CR and the largest stable B.
// Links zwidth::io and zwidth::stability only: neither libhdf5 nor libmatio.
//
//   model_zwidth MODEL.json [DELAY_SAMPLES ...]     (default: 1 2)
#include <cstdio>
#include <cstdlib>
#include <optional>
#include <string>
#include <vector>

#include <zwidth/io/model_json.h>
#include <zwidth/stability/zwidth.h>

#include "example_main.h"

int main(int argc, char** argv) {
  return RunExample(argc, argv, 2, "MODEL.json [DELAY_SAMPLES ...]", [&] {
    zwidth::io::ModelFile model = zwidth::io::ReadModelJson(argv[1]);
    // The model's own sample period (1 ms when it has none), as the CLI's default.
    std::string note;
    const double T = zwidth::io::ResolveModelPeriod(std::nullopt, &model, &note);
    std::vector<int> delays;
    for (int i = 2; i < argc; ++i) delays.push_back(std::atoi(argv[i]));
    if (delays.empty()) delays = {1, 2};
    std::printf("model %s at T = %g s\n", argv[1], T);
    for (int d : delays) {
      const zwidth::stability::DelaySummary s = zwidth::stability::ZWidth(model.plant, T, d).Summarize();
      std::printf("delay %d: K_cr_at_zero_B %.9g f_at_zero_B_hz %.9g B_t %.9g K_cr_max %.9g B_max %.9g\n", d,
                  s.K_cr_at_zero_B, s.f_at_zero_B_hz, s.B_t, s.K_cr_max, s.B_max);
    }
    return 0;
  });
}
