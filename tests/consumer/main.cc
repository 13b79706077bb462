#include <cmath>
#include <cstdio>

#include "model/plant.h"
#include "stability/zwidth.h"

int main() {
  const zwidth::stability::DelaySummary s =
      zwidth::stability::ZWidth(zwidth::model::PhantomTable1(), 1e-3, 2).Summarize();
  std::printf("K_cr_max = %.4f\n", s.K_cr_max);
  return std::abs(s.K_cr_max - 36.735) < 0.01 ? 0 : 1;
}
