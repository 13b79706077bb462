#include "flags/loop_flags.h"

#include <cmath>
#include <fstream>
#include <sstream>

#include <sys/stat.h>

#include "io/atomic_file.h"
#include "io/loop_text.h"
#include "model/error.h"
#include "stability/velocity_filter.h"

namespace zwidth::flags {

void AddLoopFlags(CLI::App* cmd, LoopFlags* f) {
  cmd->add_option("--velocity-filter-hz", f->filter_hz,
                  "first-order low-pass on the velocity, cut-off [Hz]: F = (1 - a)/(1 - a z^-1), a = exp(-2 pi f T)");
  cmd->add_option("--velocity-filter-coeffs", f->filter_coeffs,
                  "velocity filter F(z) as 'b:b0,b1,..;a:1,a1,..' (powers of z^-1, a0 = 1, stable) or a file "
                  "holding that text");
  cmd->add_option("--hand", f->hands,
                  "the user's hand M,B,K (SI, at the measured coordinate); repeat for a range of hands: the "
                  "region reported is the one stable for all");
}

std::vector<stability::LoopOptions> ResolveLoops(const LoopFlags& f, double T) {
  stability::LoopOptions base;
  if (!std::isnan(f.filter_hz) && !f.filter_coeffs.empty()) {
    throw InputError("give --velocity-filter-hz or --velocity-filter-coeffs, not both");
  }
  if (!std::isnan(f.filter_hz)) stability::SetLowPassFilter(f.filter_hz, T, &base);
  if (!f.filter_coeffs.empty()) {
    const std::string& c = f.filter_coeffs;
    const size_t a = c.find_first_not_of(" \t");
    if (a != std::string::npos && c.compare(a, 2, "b:") == 0) {
      io::ParseFilterCoefficients(c, "--velocity-filter-coeffs", &base);
    } else {
      // A regular file only (a FIFO would block, /dev/zero never ends), read
      // at most 64 kB + 1 bytes; noted as an input, so no output replaces it.
      struct stat st;
      if (::stat(c.c_str(), &st) != 0) {
        throw InputError("--velocity-filter-coeffs '" + c + "': not 'b:..;a:..' and no such readable file");
      }
      io::CheckInputFile(c, "velocity filter file");
      std::ifstream in(c, std::ios::binary);
      if (!in) {
        throw InputError("--velocity-filter-coeffs '" + c + "': not 'b:..;a:..' and no such readable file");
      }
      constexpr std::streamsize kMaxFilterFileBytes = 65536;
      std::string text(kMaxFilterFileBytes + 1, '\0');
      in.read(text.data(), kMaxFilterFileBytes + 1);
      text.resize(static_cast<size_t>(in.gcount()));
      if (text.size() > static_cast<size_t>(kMaxFilterFileBytes)) {
        throw InputError("--velocity-filter-coeffs '" + c + "': file over 64 kB");
      }
      for (char& ch : text) if (ch == '\n' || ch == '\r') ch = ' ';
      io::ParseFilterCoefficients(text, "--velocity-filter-coeffs file '" + c + "'", &base);
    }
  }
  std::vector<stability::LoopOptions> out;
  if (f.hands.empty()) out.push_back(base);
  for (const std::string& h : f.hands) {
    stability::LoopOptions l = base;
    l.hand = io::ParseHand(h);
    out.push_back(l);
  }
  return out;
}

}  // namespace zwidth::flags
