// The haptic loop's options from text (io/loop_text.h): filter coefficients
// and a hand, against the values written in the text and LoopOptions' rules.
#include <string>

#include <gtest/gtest.h>

#include "io/loop_text.h"
#include "model/error.h"

namespace zwidth::io {
namespace {

TEST(LoopText, FilterCoefficientsAreReadOrRefusedWithTheirSource) {
  stability::LoopOptions l;
  EXPECT_THROW(ParseFilterCoefficients("b:1;a:1,x", "--velocity-filter-coeffs", &l), InputError);
  EXPECT_THROW(ParseFilterCoefficients("0.5;1,-0.5", "--velocity-filter-coeffs", &l), InputError);
  // A pole outside the unit circle: LoopOptions::IsValid's message, after the source.
  try {
    ParseFilterCoefficients("b:0.5;a:1,-1.2", "--velocity-filter-coeffs", &l);
    ADD_FAILURE() << "an unstable filter was accepted";
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()).rfind("--velocity-filter-coeffs: filter_a:", 0), 0u) << e.what();
  }
  EXPECT_TRUE(l.filter_b.empty());  // unchanged by a refused text
  ParseFilterCoefficients("b:0.25, 0.25 ; a:1,-0.5", "x", &l);
  ASSERT_EQ(l.filter_b.size(), 2u);
  EXPECT_EQ(l.filter_b[0], 0.25);
  EXPECT_EQ(l.filter_b[1], 0.25);
  ASSERT_EQ(l.filter_a.size(), 2u);
  EXPECT_EQ(l.filter_a[0], 1.0);
  EXPECT_EQ(l.filter_a[1], -0.5);
}

TEST(LoopText, HandIsThreeNonNegativeNumbers) {
  EXPECT_THROW(ParseHand("1,2"), InputError);
  EXPECT_THROW(ParseHand("1,2,3,4"), InputError);
  EXPECT_THROW(ParseHand("1,-2,3"), InputError);
  EXPECT_THROW(ParseHand("1,nan,3"), InputError);
  const stability::Hand h = ParseHand(" 0.5, 2e-3 ,40");
  EXPECT_EQ(h.M, 0.5);
  EXPECT_EQ(h.B, 2e-3);
  EXPECT_EQ(h.K, 40.0);
}

}  // namespace
}  // namespace zwidth::io
