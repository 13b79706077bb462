// io/design_file.h: a design for `zwidth batch --reference`, parsed from the
// header's example, each value compared with the text it came from; and each
// mistake refused with the key's name and its line, the line found here by
// searching the test's own text (not by the parser's line table).
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>

#include <unistd.h>

#include <gtest/gtest.h>

#include "model/error.h"
#include "model/plant.h"
#include "io/design_file.h"

namespace zwidth::io {
namespace {

const char* kDesign = R"({"format": "zwidth-design", "format_version": 1, "name": "PHANToM axis 1",
 "model": "table1",
 "tolerances": [
  {"parameter": "m", "relative": 0.15},
  {"parameter": "b", "min": 1e-3, "max": 0.02},
  {"parameter": "mode1_omega", "absolute": 40},
  {"figure": "K_cr_max", "delay": 2, "min": 1.2},
  {"figure": "B_t", "delay": 4, "relative": 0.3}]})";

// 1-based line of the first occurrence of `needle` in `text`.
int LineOf(const std::string& text, const std::string& needle) {
  const size_t at = text.find(needle);
  EXPECT_NE(at, std::string::npos) << needle;
  int line = 1;
  for (size_t i = 0; i < at; ++i) line += text[i] == '\n';
  return line;
}

TEST(DesignFile, TheHeadersExampleParsesToItsValues) {
  const Design d = ParseDesign(kDesign, "design.json", ".");
  EXPECT_EQ(d.name, "PHANToM axis 1");
  EXPECT_TRUE(d.model_is_table1);
  const model::Plant t = model::PhantomTable1();
  EXPECT_EQ(d.model.plant.m, t.m);
  EXPECT_EQ(d.model.plant.modes.size(), t.modes.size());
  ASSERT_EQ(d.tolerances.size(), 5u);
  const DesignTolerance& m = d.tolerances[0];
  EXPECT_EQ(m.column, "m");
  EXPECT_FALSE(m.is_figure);
  EXPECT_EQ(m.relative, 0.15);
  EXPECT_FALSE(m.min || m.max || m.absolute);
  EXPECT_EQ(d.tolerances[1].min, 1e-3);
  EXPECT_EQ(d.tolerances[1].max, 0.02);
  EXPECT_EQ(d.tolerances[2].column, "mode1_omega");
  EXPECT_EQ(d.tolerances[2].absolute, 40.0);
  const DesignTolerance& k = d.tolerances[3];
  EXPECT_TRUE(k.is_figure);
  EXPECT_EQ(k.figure, "K_cr_max");
  EXPECT_EQ(k.delay, 2);
  EXPECT_EQ(k.column, "d2_K_cr_max");
  EXPECT_EQ(k.min, 1.2);
  EXPECT_FALSE(k.max);
  EXPECT_EQ(d.tolerances[4].column, "d4_B_t");
  EXPECT_EQ(d.tolerances[4].relative, 0.3);
}

// One mistake at a time, written into the example: the message names the key
// (or what to give) and the line where the mistake stands.
TEST(DesignFile, MistakesNameTheKeyAndItsLine) {
  struct Case { std::string from, to, needle, says; };
  const Case cases[] = {
      {"\"relative\": 0.15", "\"relative\": -0.15", "-0.15", "relative"},
      {"\"relative\": 0.15", "\"relativ\": 0.15", "relativ\"", "unknown key"},
      {"\"delay\": 2, ", "", "K_cr_max", "delay"},
      {"\"mode1_omega\"", "\"mode0_omega\"", "mode0_omega", "no parameter"},
      {"\"K_cr_max\"", "\"K_max\"", "K_max", "no Z-width figure"},
      {"\"min\": 1e-3, \"max\": 0.02", "\"min\": 0.02, \"max\": 1e-3", "\"max\": 1e-3", "swap"},
      {"{\"parameter\": \"m\", \"relative\": 0.15}", "{\"parameter\": \"m\", \"relative\": 0.15, \"absolute\": 2}",
       "\"absolute\": 2", "more than one kind"},
      {"\"parameter\": \"b\"", "\"parameter\": \"m\"", "\"min\": 1e-3", "second tolerance on m"},
      {"\"name\"", "\"nmae\"", "nmae", "unknown key"},
  };
  for (const Case& c : cases) {
    std::string text = kDesign;
    const size_t at = text.find(c.from);
    ASSERT_NE(at, std::string::npos) << c.from;
    text.replace(at, c.from.size(), c.to);
    try {
      ParseDesign(text, "design.json", ".");
      ADD_FAILURE() << "accepted: " << c.to;
    } catch (const InputError& e) {
      const std::string what = e.what();
      EXPECT_NE(what.find(c.says), std::string::npos) << what;
      EXPECT_NE(what.find("design.json line " + std::to_string(LineOf(text, c.needle))), std::string::npos)
          << what << " (expected line " << LineOf(text, c.needle) << ")";
    }
  }
  EXPECT_THROW(ParseDesign("{\"format\": \"zwidth-design\"", "design.json", "."), InputError);  // truncated
  EXPECT_THROW(ParseDesign("[1, 2]", "design.json", "."), InputError);
}

TEST(DesignFile, IsDesignFileTellsADesignFromAModel) {
  const std::filesystem::path dir = std::filesystem::temp_directory_path() / ("design_file_test_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const std::string design = (dir / "d.json").string(), other = (dir / "m.json").string();
  std::ofstream(design) << kDesign;
  std::ofstream(other) << R"({"format": "zwidth-model", "m": 1})";
  EXPECT_TRUE(IsDesignFile(design));
  EXPECT_FALSE(IsDesignFile(other));
  EXPECT_FALSE(IsDesignFile("table1"));
  EXPECT_FALSE(IsDesignFile((dir / "missing.json").string()));
  EXPECT_EQ(ReadDesign(design).tolerances.size(), 5u);
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace zwidth::io
