// flags/loop_flags.h: the haptic loop's flags resolved into loops, against
// references built here: --velocity-filter-hz is SetLowPassFilter's formula
// (b = 1 - a, a = e^{-2 pi f_c T}); coefficients given inline and in a file
// (newlines as spaces) give the same loop; one loop per hand, each with the
// filter and the hand's M, B, K as typed; both filter flags, a missing file
// and a file over 64 kB refused by name.
#include <cmath>
#include <numbers>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "flags/loop_flags.h"
#include "model/error.h"
#include "tests/test_util.h"

namespace zwidth::flags {
namespace {

TEST(LoopFlags, CutoffIsTheLowPassFormulaAndOneLoopPerHand) {
  LoopFlags f;
  f.filter_hz = 40.0;
  f.hands = {"0.001,0.002,3", "0,0.5,0"};
  const std::vector<stability::LoopOptions> l = ResolveLoops(f, 1e-3);
  ASSERT_EQ(l.size(), 2u);
  const double a = std::exp(-2 * std::numbers::pi * 40.0 * 1e-3);
  for (const stability::LoopOptions& x : l) {
    ASSERT_EQ(x.filter_b.size(), 1u);
    EXPECT_DOUBLE_EQ(x.filter_b[0], 1 - a);
    ASSERT_EQ(x.filter_a.size(), 2u);
    EXPECT_DOUBLE_EQ(x.filter_a[1], -a);
  }
  EXPECT_EQ(l[0].hand.M, 0.001);
  EXPECT_EQ(l[0].hand.B, 0.002);
  EXPECT_EQ(l[0].hand.K, 3.0);
  EXPECT_EQ(l[1].hand.B, 0.5);
  EXPECT_TRUE(l[1].hand.M == 0.0 && l[1].hand.K == 0.0);
  const std::vector<stability::LoopOptions> plain = ResolveLoops(LoopFlags{}, 1e-3);
  ASSERT_EQ(plain.size(), 1u);
  EXPECT_TRUE(IsPlainLoop(plain[0]));
  EXPECT_FALSE(IsPlainLoop(l[0]));
}

TEST(LoopFlags, CoefficientsInlineAndFromAFileAreTheSame) {
  const test::TempDir dir("zwidth_loop_flags_");
  LoopFlags inl;
  inl.filter_coeffs = "b:0.1,0.1;a:1,-0.8";
  LoopFlags file;
  file.filter_coeffs = dir.Write("f.txt", "b:0.1,0.1;\na:1,-0.8\n");
  const stability::LoopOptions a = ResolveLoops(inl, 1e-3).at(0), b = ResolveLoops(file, 1e-3).at(0);
  EXPECT_EQ(a.filter_b, (std::vector<double>{0.1, 0.1}));
  EXPECT_EQ(a.filter_a, (std::vector<double>{1.0, -0.8}));
  EXPECT_EQ(b.filter_b, a.filter_b);
  EXPECT_EQ(b.filter_a, a.filter_a);
  auto refusal = [](const LoopFlags& f) {
    try {
      ResolveLoops(f, 1e-3);
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  LoopFlags both = inl;
  both.filter_hz = 30.0;
  EXPECT_NE(refusal(both).find("not both"), std::string::npos) << refusal(both);
  LoopFlags missing;
  missing.filter_coeffs = (dir.path() / "none.txt").string();
  EXPECT_NE(refusal(missing).find("no such readable file"), std::string::npos) << refusal(missing);
  LoopFlags big;
  big.filter_coeffs = dir.Write("big.txt", "b:1;a:1" + std::string(70000, ' '));
  EXPECT_NE(refusal(big).find("over 64 kB"), std::string::npos) << refusal(big);
  LoopFlags nyquist;
  nyquist.filter_hz = 600.0;
  EXPECT_NE(refusal(nyquist).find("cutoff_hz"), std::string::npos) << refusal(nyquist);
}

}  // namespace
}  // namespace zwidth::flags
