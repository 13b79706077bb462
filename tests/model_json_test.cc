// io/model_json.h: the model file's nesting bound, ranges and file kind
// (written by the tests in a temporary folder). Moved from io_safety_test.cc.
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>

#include <sys/stat.h>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "io/export.h"
#include "io/model_json.h"
#include "model/error.h"
#include "tests/test_util.h"

namespace zwidth::io {
namespace {
namespace fs = std::filesystem;
using test::TempDir;
using test::WriteFile;

// depth nested JSON arrays.
std::string Nested(int depth) { return std::string(depth, '[') + std::string(depth, ']'); }

TEST(ModelJson, NestingIsBoundedBeforeParsing) {
  const std::string head = R"({"m": 1e-3, "b": 5e-3, "modes": [], "fit": )";
  // "fit" sits at depth 1, so its value may nest kMaxJsonDepth - 1 levels.
  EXPECT_NO_THROW(ParseModelJson(head + Nested(kMaxJsonDepth - 1) + "}", "ok.json"));
  EXPECT_THROW(ParseModelJson(head + Nested(kMaxJsonDepth) + "}", "deep.json"), InputError);
  EXPECT_THROW(ParseModelJson(Nested(100000), "deep.json"), InputError);
  // Brackets inside strings are text, not nesting.
  EXPECT_NO_THROW(ParseModelJson(R"({"m": 1e-3, "b": 5e-3, "modes": [], "name": ")" + std::string(1000, '[') +
                                     R"(\"]"})", "name.json"));
}

TEST(ModelJson, DelaysAndParametersOutsideTheirRangesAreRefused) {
  const std::string head = R"({"m": 1e-3, "b": 5e-3, "modes": [], "delay_samples": )";
  for (const char* d : {"4294967298", "2147483647", "18446744073709551615", "-1", "1001"}) {
    SCOPED_TRACE(d);
    EXPECT_THROW(ParseModelJson(head + d + "}", "model.json"), InputError);
  }
  EXPECT_EQ(ParseModelJson(head + "1000}", "model.json").plant.delay_samples, 1000);
  EXPECT_THROW(ParseModelJson(R"({"m": 1e-300, "b": 5e-3, "modes": []})", "model.json"), InputError);
  EXPECT_THROW(ParseModelJson(R"({"m": 1e-3, "b": 5e300, "modes": []})", "model.json"), InputError);
  std::string modes;
  for (size_t i = 0; i <= kMaxModes; ++i) modes += std::string(i ? "," : "") + R"({"omega": 400, "c": 80, "v": 380, "d": 70})";
  EXPECT_THROW(ParseModelJson(R"({"m": 1e-3, "b": 5e-3, "modes": [)" + modes + "]}", "model.json"), InputError);
}

// A standard error is >= 0 (null: unknown), in every key; a parameter out of
// range is refused with its own SI unit, not another key's.
TEST(ModelJson, NegativeStandardErrorsAreRefusedAndRangesNameTheirUnits) {
  const std::string mode = R"({"omega": 400, "c": 80, "v": 380, "d": 70})";
  const std::string head = R"({"m": 1e-3, "b": 5e-3, "modes": [)" + mode + R"(], "std": )";
  EXPECT_NO_THROW(ParseModelJson(head + R"({"m": 1e-5, "b": null, "modes": [{"omega": 1, "c": 0, "v": 2, "d": 3}]}})",
                                 "model.json"));
  for (const char* bad : {R"({"m": -1e-5, "b": 1e-4, "modes": [{"omega": 1, "c": 1, "v": 2, "d": 3}]})",
                          R"({"m": 1e-5, "b": 1e-4, "modes": [{"omega": 1, "c": 1, "v": -2, "d": 3}]})"}) {
    SCOPED_TRACE(bad);
    try {
      ParseModelJson(head + bad + "}", "model.json");
      ADD_FAILURE() << "accepted";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("standard error and must be >= 0"), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("key 'std."), std::string::npos) << e.what();
    }
  }
  auto refusal = [](const std::string& text) {
    try {
      ParseModelJson(text, "model.json");
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  EXPECT_NE(refusal(R"({"m": 1e-300, "b": 5e-3, "modes": []})").find("kg m^2"), std::string::npos);
  EXPECT_NE(refusal(R"({"m": 1e-3, "b": 5e300, "modes": []})").find("N m s/rad"), std::string::npos);
  EXPECT_NE(refusal(R"({"m": 1e-3, "b": 5e-3, "modes": [{"omega": -4, "c": 80, "v": 380, "d": 70}]})").find("rad/s"),
            std::string::npos);
}

// docs/usage.md names every top-level key the writer emits (issue 24: units,
// friction, format_version and provenance were missing). A model with every
// optional part set, written by WriteModelJson (which adds provenance); each
// of its keys must appear in backquotes in the usage page's key table.
TEST(ModelJson, UsageDocNamesEveryKeyTheWriterEmits) {
  const ModelFile mf = ParseModelJson(
      R"({"name": "n", "m": 1e-3, "b": 5e-3, "modes": [{"omega": 400, "c": 80, "v": 300, "d": 70}],
          "delay_samples": 1, "units": "linear", "sample_period_s": 0.001,
          "std": {"m": 1e-5, "b": 1e-4, "modes": [{"omega": 1, "c": 1, "v": 1, "d": 1}],
                  "friction": {"coulomb_pos": 1e-4, "coulomb_neg": 1e-4, "offset": 1e-4}},
          "friction": {"coulomb_pos": 0.008, "coulomb_neg": 0.006, "offset": 0}, "fit": {"quality": "good"}})",
      "all.json");
  ModelFile full = mf;
  const int p = 2 + 4 * static_cast<int>(full.plant.modes.size());
  full.log_covariance.assign(static_cast<size_t>(p * p), 0.0);
  for (int i = 0; i < p; ++i) full.log_covariance[static_cast<size_t>(i * p + i)] = 1e-4;
  TempDir dir;
  const std::string path = (dir.path() / "all.json").string();
  WriteModelJson(path, full);
  std::ifstream in(path);
  const nlohmann::json j = nlohmann::json::parse(in);
  std::ifstream doc_in(std::string(ZWIDTH_SOURCE_DIR) + "/docs/usage.md");
  ASSERT_TRUE(doc_in) << "docs/usage.md not found under " << ZWIDTH_SOURCE_DIR;
  const std::string doc((std::istreambuf_iterator<char>(doc_in)), std::istreambuf_iterator<char>());
  EXPECT_GE(j.size(), 12u) << j.dump();  // every optional key was written
  for (const auto& [key, value] : j.items()) {
    EXPECT_NE(doc.find("| `" + key + "`"), std::string::npos) << "docs/usage.md: no row for model key '" << key << "'";
  }
}

TEST(ModelJson, FrictionRoundTripsAndIsChecked) {
  const std::string head = R"({"m": 1e-3, "b": 5e-3, "modes": [], )";
  const ModelFile mf = ParseModelJson(
      head + R"("friction": {"coulomb_pos": 0.008, "coulomb_neg": 0.006, "offset": -0.001, "breakaway_pos": 0.01}})",
      "f.json");
  ASSERT_TRUE(mf.friction.has_value());
  EXPECT_EQ(mf.friction->coulomb_pos, 0.008);
  EXPECT_EQ(mf.friction->coulomb_neg, 0.006);
  EXPECT_EQ(mf.friction->offset, -0.001);
  EXPECT_EQ(mf.friction->breakaway_pos, 0.01);
  EXPECT_EQ(mf.friction->breakaway_neg, 0.0);
  EXPECT_DOUBLE_EQ(mf.friction->MeanCoulomb(), 0.007);
  const ModelFile back = ParseModelJson(ModelToJson(mf).dump(), "back.json");
  ASSERT_TRUE(back.friction.has_value());
  EXPECT_EQ(back.friction->offset, -0.001);
  EXPECT_EQ(back.friction->StaticNeg(), 0.006);  // 0 = the Coulomb level
  EXPECT_FALSE(ParseModelJson(head + R"("name": "x"})", "n.json").friction.has_value());
  // A negative level, a breakaway below its Coulomb level, an unknown key, a std without a value.
  EXPECT_THROW(ParseModelJson(head + R"("friction": {"coulomb_pos": -1}})", "f.json"), InputError);
  EXPECT_THROW(ParseModelJson(head + R"("friction": {"coulomb_pos": 0.01, "breakaway_pos": 0.005}})", "f.json"),
               InputError);
  EXPECT_THROW(ParseModelJson(head + R"("friction": {"coulomb": 0.01}})", "f.json"), InputError);
  EXPECT_THROW(ParseModelJson(head + R"("std": {"m": 1e-5, "b": 1e-5, "modes": [], "friction": {"offset": 1}}})",
                              "f.json"),
               InputError);
}

// "units": "linear" is kept by the file and by every export's labels (the
// MATLAB and Python comments, the HDF5 units attributes); a rotary model's
// file has no "units" key (files written before it are unchanged), and a word
// other than rotary or linear is refused naming the key.
TEST(ModelJson, UnitsRoundTripAndEveryExportFollowsThem) {
  const std::string head = R"({"m": 1.2, "b": 3.4, "modes": [])";
  const ModelFile linear = ParseModelJson(head + R"(, "units": "linear"})", "l.json");
  EXPECT_TRUE(linear.linear);
  EXPECT_FALSE(ParseModelJson(head + R"(, "units": "rotary"})", "r.json").linear);
  EXPECT_FALSE(ParseModelJson(head + "}", "r.json").linear);
  EXPECT_EQ(ModelToJson(linear).at("units"), "linear");
  EXPECT_TRUE(ParseModelJson(ModelToJson(linear).dump(), "back.json").linear);
  EXPECT_FALSE(ModelToJson(ParseModelJson(head + "}", "r.json")).contains("units"));
  for (const char* bad : {R"("metric")", "1", "null", R"(["linear"])"}) {
    try {
      ParseModelJson(head + R"(, "units": )" + bad + "}", "u.json");
      ADD_FAILURE() << bad << " was accepted";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("'units'"), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("u.json"), std::string::npos) << e.what();
    }
  }
  EXPECT_THROW(ParseUnitsWord("Linear", "--units"), InputError);
  EXPECT_TRUE(ParseUnitsWord("linear", "--units"));
  const TempDir dir;
  auto read = [](const fs::path& p) {
    std::ifstream in(p, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(in), {});
  };
  for (const bool lin : {false, true}) {
    ModelFile mf = linear;
    mf.linear = lin;
    const std::string tag = lin ? "lin" : "rot";
    ExportModel(mf, ExportFormat::kMatlab, 1e-3, dir / (tag + ".m"));
    ExportModel(mf, ExportFormat::kPython, 1e-3, dir / (tag + ".py"));
    const std::string m = read(dir / (tag + ".m")), py = read(dir / (tag + ".py"));
    EXPECT_EQ(m.find("kg m^2") == std::string::npos, lin) << m.substr(0, 400);
    EXPECT_EQ(m.find("N m s/rad") == std::string::npos, lin) << m.substr(0, 800);
    EXPECT_EQ(py.find("# kg m^2") == std::string::npos, lin) << py.substr(0, 400);
    EXPECT_EQ(m.find("inertia [kg]") != std::string::npos, lin) << m.substr(0, 400);
    EXPECT_EQ(py.find("# N s/m") != std::string::npos, lin) << py.substr(0, 600);
  }
}

TEST(ModelJson, AModelFileMustBeARegularFile) {
  EXPECT_THROW(ReadModelJson("/dev/zero"), InputError);
  TempDir dir("zwidth_model_json_test_");
  ASSERT_EQ(::mkfifo((dir / "model.json").c_str(), 0600), 0);
  EXPECT_THROW(ReadModelJson(dir / "model.json"), InputError);  // refused at once, never opened
}

}  // namespace
}  // namespace zwidth::io
