// K_CR^max of Table I at T = 1 ms, d = 2 (36.735 N m/rad, what `zwidth
// boundary` gives; the installed package against the project), and an HDF5 log written and read back
// through zwidth::hdf5: every sample as written.
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include <zwidth/io/log.h>
#include <zwidth/model/plant.h>
#include <zwidth/stability/zwidth.h>

int main(int argc, char** argv) {
  const zwidth::stability::DelaySummary s =
      zwidth::stability::ZWidth(zwidth::model::PhantomTable1(), 1e-3, 2).Summarize();
  std::printf("K_cr_max = %.4f\n", s.K_cr_max);
  if (std::abs(s.K_cr_max - 36.735) >= 0.01) return 1;
  const std::string path = std::string(argc > 1 ? argv[1] : ".") + "/consumer_log.h5";
  std::vector<double> u, y;
  for (int i = 0; i < 100; ++i) {
    u.push_back(std::sin(0.1 * i));
    y.push_back(std::cos(0.3 * i) / (1.0 + i));
  }
  zwidth::io::WriteLog(path, 1000.0, u, y);
  const zwidth::io::Log log = zwidth::io::ReadLog(path);
  const bool same = log.input == u && log.output == y && log.info.sample_rate_hz == 1000.0;
  std::printf("HDF5 log round trip: %s\n", same ? "every sample as written" : "DIFFERS");
  return same ? 0 : 1;
}
