// Every options struct of ident/ and fit/: its defaults are valid, and one
// out-of-range field is refused with a message that names that field.
#include <functional>
#include <string>

#include <gtest/gtest.h>

#include "fit/fit.h"
#include "ident/excitation.h"
#include "ident/welch.h"

namespace zwidth {
namespace {

struct OptionsCase {
  std::string name;
  std::function<bool(std::string*)> defaults_valid;  // IsValid of a default-constructed struct
  std::function<bool(std::string*)> bad_valid;       // IsValid with `field` out of range
  std::string field;
};

class Options : public ::testing::TestWithParam<OptionsCase> {};

TEST_P(Options, DefaultOptionsAreValid) {
  std::string why;
  EXPECT_TRUE(GetParam().defaults_valid(&why)) << why;
}

TEST_P(Options, AnOutOfRangeFieldIsRefusedByName) {
  std::string why;
  EXPECT_FALSE(GetParam().bad_valid(&why));
  EXPECT_NE(why.find(GetParam().field), std::string::npos) << why;
}

template <typename O>
std::function<bool(std::string*)> Valid(O o) {
  return [o](std::string* why) { return o.IsValid(why); };
}

OptionsCase Welch() {
  ident::WelchOptions bad;
  bad.window_length = 8;
  return {"WelchOptions", Valid(ident::WelchOptions{}), Valid(bad), "window_length"};
}
OptionsCase Band() {
  ident::BandOptions bad;
  bad.min_coherence = 1.0;
  return {"BandOptions", Valid(ident::BandOptions{}), Valid(bad), "min_coherence"};
}
OptionsCase Excitation() {
  ident::ExcitationOptions bad;
  bad.rms = -1.0;
  return {"ExcitationOptions", Valid(ident::ExcitationOptions{}), Valid(bad), "rms"};
}
OptionsCase Fit() {
  fit::FitOptions bad;
  bad.max_modes = 9;
  return {"FitOptions", Valid(fit::FitOptions{}), Valid(bad), "max_modes"};
}
OptionsCase FitBand() {  // a FitOptions refuses its band's bad field by the band's name
  fit::FitOptions bad;
  bad.band.min_input_power_ratio = 2.0;
  return {"FitOptionsBand", Valid(fit::FitOptions{}), Valid(bad), "min_input_power_ratio"};
}

INSTANTIATE_TEST_SUITE_P(IdentAndFit, Options, ::testing::Values(Welch(), Band(), Excitation(), Fit(), FitBand()),
                         [](const ::testing::TestParamInfo<OptionsCase>& i) { return i.param.name; });

}  // namespace
}  // namespace zwidth
