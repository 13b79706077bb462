// Every options struct with an IsValid (model/, ident/, fit/, stability/): its
// defaults are valid, and one out-of-range field is refused with a message that
// names that field as Struct::field, the form the CLI maps to its flag.
#include <functional>
#include <string>

#include <gtest/gtest.h>

#include "fit/fit.h"
#include "ident/excitation.h"
#include "ident/welch.h"
#include "model/simulate.h"
#include "stability/haptic_loop.h"
#include "stability/loop_options.h"
#include "stability/relay.h"
#include "stability/uncertainty.h"
#include "stability/zwidth.h"

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
  return {"WelchOptions", Valid(ident::WelchOptions{}), Valid(bad), "WelchOptions::window_length"};
}
OptionsCase Band() {
  ident::BandOptions bad;
  bad.min_coherence = 1.0;
  return {"BandOptions", Valid(ident::BandOptions{}), Valid(bad), "BandOptions::min_coherence"};
}
OptionsCase Excitation() {
  ident::ExcitationOptions bad;
  bad.rms = -1.0;
  return {"ExcitationOptions", Valid(ident::ExcitationOptions{}), Valid(bad), "ExcitationOptions::rms"};
}
OptionsCase Fit() {
  fit::FitOptions bad;
  bad.max_modes = 9;
  return {"FitOptions", Valid(fit::FitOptions{}), Valid(bad), "FitOptions::max_modes"};
}
OptionsCase FitBand() {  // a FitOptions refuses its band's bad field by the band's name
  fit::FitOptions bad;
  bad.band.min_input_power_ratio = 2.0;
  return {"FitOptionsBand", Valid(fit::FitOptions{}), Valid(bad), "BandOptions::min_input_power_ratio"};
}

OptionsCase Simulate() {
  SimulateOptions bad;
  bad.seconds = -1.0;
  return {"SimulateOptions", Valid(SimulateOptions{}), Valid(bad), "SimulateOptions::seconds"};
}
OptionsCase Boundary() {
  stability::BoundaryOptions bad;
  bad.grid_points_per_delay = 4;
  return {"BoundaryOptions", Valid(stability::BoundaryOptions{}), Valid(bad), "BoundaryOptions::grid_points_per_delay"};
}
OptionsCase BGrid() {
  stability::BGridOptions bad;
  bad.b_points = 1;
  return {"BGridOptions", Valid(stability::BGridOptions{}), Valid(bad), "BGridOptions::b_points"};
}
OptionsCase Loop() {
  stability::LoopOptions bad;
  bad.hand.K = -1.0;
  return {"LoopOptions", Valid(stability::LoopOptions{}), Valid(bad), "hand.K"};
}
OptionsCase Relay() {
  stability::RelayOptions bad;
  bad.seconds = 0.0;
  return {"RelayOptions", Valid(stability::RelayOptions{}), Valid(bad), "RelayOptions::seconds"};
}
OptionsCase RelayLoop() {  // a RelayOptions refuses its loop's bad field by the loop's name
  stability::RelayOptions bad;
  bad.loop.filter_b = {1.0};
  return {"RelayOptionsLoop", Valid(stability::RelayOptions{}), Valid(bad), "RelayOptions::loop.filter_b"};
}
OptionsCase Passivity() {
  stability::PassivityOptions bad;
  bad.min_grid_points = 10;
  return {"PassivityOptions", Valid(stability::PassivityOptions{}), Valid(bad), "PassivityOptions::min_grid_points"};
}
OptionsCase Uncertainty() {
  stability::UncertaintyOptions bad;
  bad.log_step = 0.5;
  return {"UncertaintyOptions", Valid(stability::UncertaintyOptions{}), Valid(bad), "UncertaintyOptions::log_step"};
}

INSTANTIATE_TEST_SUITE_P(EveryOptionsStruct, Options, ::testing::Values(Welch(), Band(), Excitation(), Fit(), FitBand(), Simulate(), Boundary(), BGrid(),
                                                          Loop(), Relay(), RelayLoop(), Passivity(), Uncertainty()),
                         [](const ::testing::TestParamInfo<OptionsCase>& i) { return i.param.name; });

}  // namespace
}  // namespace zwidth
