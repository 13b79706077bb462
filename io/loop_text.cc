#include "io/loop_text.h"

#include <cmath>
#include <cstdlib>
#include <sstream>
#include <vector>

#include "model/error.h"

namespace zwidth::io {

using stability::Hand;
using stability::LoopOptions;

namespace {

std::vector<double> ParseNumbers(const std::string& list, const std::string& what) {
  std::vector<double> out;
  std::stringstream ss(list);
  std::string item;
  while (std::getline(ss, item, ',')) {
    const size_t a = item.find_first_not_of(" \t\r\n"), b = item.find_last_not_of(" \t\r\n");
    if (a == std::string::npos) throw InputError(what + ": empty number in '" + list + "'");
    const std::string t = item.substr(a, b - a + 1);
    char* end = nullptr;
    const double v = std::strtod(t.c_str(), &end);
    if (end != t.c_str() + t.size() || !std::isfinite(v)) {
      throw InputError(what + ": '" + t + "' is not a finite number");
    }
    out.push_back(v);
  }
  return out;
}

}  // namespace

void ParseFilterCoefficients(const std::string& text, const std::string& what, LoopOptions* loop) {
  const size_t semi = text.find(';');
  const std::string hint = " (expected 'b:b0,b1,...;a:1,a1,...', powers of z^-1)";
  if (semi == std::string::npos) throw InputError(what + ": no ';' between the b and a lists" + hint);
  auto part = [&](std::string p, char key) {
    const size_t a = p.find_first_not_of(" \t\r\n");
    if (a == std::string::npos || p.size() < a + 2 || p[a] != key || p[a + 1] != ':') {
      throw InputError(what + ": the " + std::string(1, key) + " list must start with '" + key + ":'" + hint);
    }
    std::vector<double> v = ParseNumbers(p.substr(a + 2), what);
    if (v.empty()) throw InputError(what + ": the " + std::string(1, key) + " list is empty" + hint);
    return v;
  };
  LoopOptions l = *loop;
  l.filter_b = part(text.substr(0, semi), 'b');
  l.filter_a = part(text.substr(semi + 1), 'a');
  std::string why;
  if (!l.IsValid(&why)) throw InputError(what + ": " + why);
  *loop = l;
}

Hand ParseHand(const std::string& text) {
  const std::vector<double> v = ParseNumbers(text, "LoopOptions::hand");
  if (v.size() != 3) throw InputError("LoopOptions::hand '" + text + "': expected three numbers M,B,K (SI, at the measured coordinate)");
  Hand h{v[0], v[1], v[2]};
  if (h.M < 0 || h.B < 0 || h.K < 0) throw InputError("LoopOptions::hand '" + text + "': M, B and K must be >= 0");
  LoopOptions l;
  l.hand = h;
  std::string why;
  if (!l.IsValid(&why)) throw InputError("LoopOptions::hand '" + text + "': " + why);
  return h;
}

}  // namespace zwidth::io
