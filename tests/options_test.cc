// Every options struct with an IsValid (model/, ident/, fit/, stability/): its
// defaults are valid, and one out-of-range field is refused with a message that
// names that field as Struct::field, the form the CLI maps to its flag.
#include <functional>
#include <string>
#include <utility>

#include <gtest/gtest.h>

#include "fit/fit.h"
#include "ident/excitation.h"
#include "ident/welch.h"
#include "model/simulate.h"
#include "stability/loop_options.h"
#include "stability/passivity.h"
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

// O's defaults, and an O with one field put out of range by spoil(&o).
template <typename O, typename Spoil>
OptionsCase Case(std::string name, Spoil spoil, std::string field) {
  O bad;
  spoil(&bad);
  return {std::move(name), Valid(O{}), Valid(bad), std::move(field)};
}

INSTANTIATE_TEST_SUITE_P(
    EveryOptionsStruct, Options,
    ::testing::Values(
        Case<ident::WelchOptions>("WelchOptions", [](auto* o) { o->window_length = 8; }, "WelchOptions::window_length"),
        Case<ident::BandOptions>("BandOptions", [](auto* o) { o->min_coherence = 1.0; }, "BandOptions::min_coherence"),
        Case<ident::ExcitationOptions>("ExcitationOptions", [](auto* o) { o->rms = -1.0; }, "ExcitationOptions::rms"),
        Case<fit::FitOptions>("FitOptions", [](auto* o) { o->max_modes = 9; }, "FitOptions::max_modes"),
        // A FitOptions refuses its band's bad field by the band's name.
        Case<fit::FitOptions>("FitOptionsBand", [](auto* o) { o->band.min_input_power_ratio = 2.0; },
                              "BandOptions::min_input_power_ratio"),
        Case<model::SimulateOptions>("SimulateOptions", [](auto* o) { o->seconds = -1.0; }, "SimulateOptions::seconds"),
        Case<stability::BoundaryOptions>("BoundaryOptions", [](auto* o) { o->grid_points_per_delay = 4; },
                                         "BoundaryOptions::grid_points_per_delay"),
        Case<stability::BGridOptions>("BGridOptions", [](auto* o) { o->b_points = 1; }, "BGridOptions::b_points"),
        Case<stability::LoopOptions>("LoopOptions", [](auto* o) { o->hand.K = -1.0; }, "hand.K"),
        Case<stability::RelayOptions>("RelayOptions", [](auto* o) { o->seconds = 0.0; }, "RelayOptions::seconds"),
        // A RelayOptions refuses its loop's bad field by the loop's name.
        Case<stability::RelayOptions>("RelayOptionsLoop", [](auto* o) { o->loop.filter_b = {1.0}; },
                                      "RelayOptions::loop.filter_b"),
        Case<stability::PassivityOptions>("PassivityOptions", [](auto* o) { o->min_grid_points = 10; },
                                          "PassivityOptions::min_grid_points"),
        Case<stability::UncertaintyOptions>("UncertaintyOptions", [](auto* o) { o->log_step = 0.5; },
                                            "UncertaintyOptions::log_step")),
    [](const ::testing::TestParamInfo<OptionsCase>& i) { return i.param.name; });

}  // namespace
}  // namespace zwidth
