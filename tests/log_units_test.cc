// Units of a text log's columns (io/log_units.h): a header that says
// "torque [mNm]", "pos (deg)", "x_mm", a units row under the header, encoder
// counts, a decimal comma. The same seeded signals are written in SI and in
// the other unit (the value times the factor written here from the unit's
// definition, not from zwidth), and must read back as the SI file does.
#include <cmath>
#include <cstdio>
#include <numbers>
#include <random>
#include <string>

#include <gtest/gtest.h>

#include "io/log.h"
#include "model/error.h"
#include "tests/test_util.h"

namespace zwidth::io {
namespace {

struct Signals {
  std::vector<double> t, u, y;
};

// A torque of three sines plus seeded noise (values of both signs and many
// magnitudes) and a position that integrates it.
Signals MakeSignals(size_t n = 2000) {
  std::mt19937_64 rng(29);
  std::uniform_real_distribution<double> noise(-0.01, 0.01);
  Signals s;
  double pos = 0;
  for (size_t k = 0; k < n; ++k) {
    const double t = k / 1000.0;
    s.t.push_back(t);
    s.u.push_back(0.05 * std::sin(2 * std::numbers::pi * 3 * t) + 0.02 * std::cos(2 * std::numbers::pi * 41 * t) +
                  noise(rng));
    pos += 2e-3 * s.u.back();
    s.y.push_back(pos);
  }
  return s;
}

std::string Num(double v) {
  char b[40];
  std::snprintf(b, sizeof b, "%.17g", v);
  return b;
}

// Rows t, u * fu, y * fy with delimiter d; a decimal comma when asked.
std::string Rows(const Signals& s, double fu, double fy, const std::string& d = ",", bool comma = false) {
  std::string out;
  for (size_t k = 0; k < s.u.size(); ++k) {
    std::string row = Num(s.t[k]) + d + Num(s.u[k] * fu) + d + Num(s.y[k] * fy);
    if (comma) {
      for (char& c : row) c = c == '.' ? ',' : c;
    }
    out += row + "\n";
  }
  return out;
}

class LogUnits : public ::testing::Test {
 protected:
  void ExpectSi(const Log& log, const Signals& s) {
    ASSERT_EQ(log.input.size(), s.u.size());
    for (size_t k = 0; k < s.u.size(); ++k) {
      ASSERT_NEAR(log.input[k], s.u[k], 1e-14 * std::abs(s.u[k]) + 1e-300) << "sample " << k;
      ASSERT_NEAR(log.output[k], s.y[k], 1e-14 * std::abs(s.y[k]) + 1e-300) << "sample " << k;
    }
  }
  std::string Refusal(const std::string& path, const LogSelect& sel = {}) {
    try {
      ReadLog(path, sel);
    } catch (const InputError& e) {
      return e.what();
    }
    ADD_FAILURE() << path << " was accepted";
    return "";
  }
  test::TempDir dir_{"zwidth_logunits_"};
  Signals s_ = MakeSignals();
};

constexpr double kDeg = 180.0 / std::numbers::pi;  // degrees per rad

TEST_F(LogUnits, UnitsInHeaderNamesAreConverted) {
  struct Case {
    const char* header;
    double fu, fy;  // file value = SI value * f
  };
  const Case cases[] = {
      {"t,torque [mNm],position [deg]", 1e3, kDeg},
      {"t,torque (mN m),position (rad)", 1e3, 1.0},
      {"t,torque [N mm],position [mrad]", 1e3, 1e3},
      {"t,torque [N*m],position [rev]", 1.0, 1.0 / (2 * std::numbers::pi)},
      {"t,torque [N],position [mm]", 1.0, 1e3},
      {"t,torque [mN],position [um]", 1e3, 1e6},
      {"t,torque_mNm,position_deg", 1e3, kDeg},
  };
  for (const Case& c : cases) {
    LogSelect sel;
    sel.input_column = std::string(c.header).substr(2, std::string(c.header).find(',', 2) - 2);
    sel.output_column = std::string(c.header).substr(std::string(c.header).rfind(',') + 1);
    const Log log = ReadLog(dir_.Write("u.csv", std::string(c.header) + "\n" + Rows(s_, c.fu, c.fy)), sel);
    SCOPED_TRACE(c.header);
    ExpectSi(log, s_);
    EXPECT_NE(log.info.layout.find("unit '"), std::string::npos) << log.info.layout;  // says what it read
  }
}

// The default column names ('t', 'torque', 'position') find columns whose
// header carries a bracketed unit; the unit is still converted.
TEST_F(LogUnits, DefaultNamesFindColumnsWithBracketedUnits) {
  ExpectSi(ReadLog(dir_.Write("b.csv", "t [s],torque [mNm],position [deg]\n" + Rows(s_, 1e3, kDeg))), s_);
  LogSelect time;
  time.time_column = "time";
  ExpectSi(ReadLog(dir_.Write("b2.csv", "Time (s);Torque (N m);Position (mrad)\n" + Rows(s_, 1, 1e3, ";")), time), s_);
}

// A name that two columns answer is refused, by each matching rule, naming
// both columns and the flag that picks one by position; the other columns
// of the same file still read.
TEST_F(LogUnits, ANameTwoColumnsAnswerIsRefused) {
  std::string four;  // t, u, u, y: the torque twice
  for (size_t k = 0; k < s_.u.size(); ++k) four += Num(s_.t[k]) + "," + Num(s_.u[k]) + "," + Num(s_.u[k]) + "," + Num(s_.y[k]) + "\n";
  for (const char* header : {"t,torque,torque,position", "t,TORQUE,Torque,position", "t,torque [N m],torque [mNm],position"}) {
    SCOPED_TRACE(header);
    const std::string why = Refusal(dir_.Write("dup.csv", std::string(header) + "\n" + four));
    EXPECT_NE(why.find("2 columns answer to 'torque'"), std::string::npos) << why;
    EXPECT_NE(why.find("columns 2 and 3"), std::string::npos) << why;
    EXPECT_NE(why.find("LogSelect::input_column"), std::string::npos) << why;
  }
  LogSelect by_position;
  by_position.input_column = "3";
  ExpectSi(ReadLog(dir_.Write("dup.csv", "t,torque,torque,position\n" + four), by_position), s_);
}

TEST_F(LogUnits, AUnitsRowUnderTheHeaderIsRead) {
  const Log log = ReadLog(dir_.Write("r.csv", "t;torque;position\ns;mN m;deg\n" + Rows(s_, 1e3, kDeg, ";")));
  ExpectSi(log, s_);
  EXPECT_NE(log.info.layout.find("units row at line 2"), std::string::npos) << log.info.layout;
  // A bracketed units row and a comment-marked header.
  ExpectSi(ReadLog(dir_.Write("r2.csv", "#t,torque,position\n[s],[N m],[rad]\n" + Rows(s_, 1, 1))), s_);
}

TEST_F(LogUnits, DecimalCommaIsDetectedOrGiven) {
  ExpectSi(ReadLog(dir_.Write("d.csv", "t;torque;position\n" + Rows(s_, 1, 1, ";", true))), s_);
  ExpectSi(ReadLog(dir_.Write("d2.txt", "t\ttorque\tposition\n" + Rows(s_, 1, 1, "\t", true))), s_);
  LogSelect sel;
  sel.decimal_comma = true;
  ExpectSi(ReadLog(dir_.Write("d3.txt", "t torque position\n" + Rows(s_, 1, 1, " ", true)), sel), s_);
  // A first row of integers reads with a point; the commas later are named.
  const std::string mixed = "t;torque;position\n0;1;2\n" + Rows(s_, 1, 1, ";", true);
  EXPECT_NE(Refusal(dir_.Write("d4.csv", mixed)).find("LogSelect::decimal_comma"), std::string::npos);
  ExpectSi(ReadLog(dir_.Write("d5.csv", "t;torque;position\n" + Rows(s_, 1, 1, ";", true)), sel), s_);
}

TEST_F(LogUnits, CountsNeedTheirResolution) {
  const double cpr = 4096;  // counts per turn
  const std::string p = dir_.Write("c.csv", "t,torque,position [counts]\n" + Rows(s_, 1, cpr / (2 * std::numbers::pi)));
  LogSelect sel;
  sel.output_column = "position [counts]";
  const std::string m = Refusal(p, sel);
  EXPECT_NE(m.find("LogSelect::counts_per_rev"), std::string::npos) << m;
  sel.counts_per_rev = cpr;
  ExpectSi(ReadLog(p, sel), s_);
  LogSelect lin;
  lin.output_column = "position [counts]";
  lin.counts_per_m = cpr / (2 * std::numbers::pi);  // the same numbers read as metres
  ExpectSi(ReadLog(p, lin), s_);
}

TEST_F(LogUnits, AnUnknownUnitIsRefusedWithTheFlag) {
  LogSelect sel;
  sel.input_column = "torque [oz in]";
  const std::string p = dir_.Write("x.csv", "t,torque [oz in],position\n" + Rows(s_, 1, 1));
  const std::string m = Refusal(p, sel);
  EXPECT_NE(m.find("LogSelect::input_unit"), std::string::npos) << m;
  EXPECT_NE(m.find("oz in"), std::string::npos) << m;
  sel.input_unit = "si";  // as is
  ExpectSi(ReadLog(p, sel), s_);
  // A scale the user gives converts a unit zwidth does not know (volts to N m here).
  LogSelect volts;
  volts.input_column = "torque [oz in]";
  volts.input_scale = 0.5;
  const Log v = ReadLog(p, volts);
  EXPECT_NEAR(v.input[7], 0.5 * s_.u[7], 1e-15);
  // The flag wins over the header.
  LogSelect given;
  given.output_column = "position [deg]";
  given.output_unit = "rad";
  ExpectSi(ReadLog(dir_.Write("g.csv", "t,torque,position [deg]\n" + Rows(s_, 1, 1)), given), s_);
}

TEST_F(LogUnits, PlainNamesStaySi) {
  ExpectSi(ReadLog(dir_.Write("p.csv", "t,torque,position\n" + Rows(s_, 1, 1))), s_);
  LogSelect sel;
  sel.input_column = "motor_torque";
  sel.output_column = "pos_cmd";
  ExpectSi(ReadLog(dir_.Write("p2.csv", "t,motor_torque,pos_cmd\n" + Rows(s_, 1, 1)), sel), s_);
}

// The header's units say the axis (io::HeaderUnits): N m and rad rotary, N
// and m linear; a flag's unit, a plain name or "si" say nothing.
TEST_F(LogUnits, TheHeaderSaysTheAxis) {
  struct Case {
    const char* header;
    HeaderUnits units;
    double fu, fy;
  };
  const Case cases[] = {
      {"t,torque [N m],position [rad]", HeaderUnits::kRotary, 1, 1},
      {"t,torque [Nm],position [deg]", HeaderUnits::kRotary, 1, kDeg},
      {"t,torque [N],position [m]", HeaderUnits::kLinear, 1, 1},
      {"t,torque [mN],position [mm]", HeaderUnits::kLinear, 1e3, 1e3},
      {"t,torque [N],position", HeaderUnits::kLinear, 1, 1},   // one column says it
      {"t,torque [N m],position [m]", HeaderUnits::kMixed, 1, 1},
      {"t,torque,position", HeaderUnits::kNone, 1, 1},
      {"t,torque [si],position [si]", HeaderUnits::kNone, 1, 1},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.header);
    const Log log = ReadLog(dir_.Write("h.csv", std::string(c.header) + "\n" + Rows(s_, c.fu, c.fy)));
    EXPECT_EQ(log.info.header_units, c.units);
    EXPECT_EQ(log.info.header_units_text.empty(), c.units == HeaderUnits::kNone) << log.info.header_units_text;
  }
  // A units row says it too; a unit given by the caller is the caller's, not the header's.
  EXPECT_EQ(ReadLog(dir_.Write("r.csv", "t;force;x\ns;N;mm\n" + Rows(s_, 1, 1e3, ";")),
                    [] { LogSelect s; s.input_column = "force"; s.output_column = "x"; return s; }())
                .info.header_units,
            HeaderUnits::kLinear);
  LogSelect given;
  given.input_unit = "N";
  given.output_unit = "m";
  EXPECT_EQ(ReadLog(dir_.Write("g.csv", "t,torque,position\n" + Rows(s_, 1, 1)), given).info.header_units,
            HeaderUnits::kNone);
}

// The default input column is 'torque', else 'force': the header `zwidth
// simulate` writes for a linear model ("t,force [N],position [m]") is read
// without a flag, in its units; a log with both takes 'torque'.
TEST_F(LogUnits, ADefaultReadsAForceColumn) {
  const Log log = ReadLog(dir_.Write("f.csv", "t,force [mN],position [mm]\n" + Rows(s_, 1e3, 1e3)));
  ExpectSi(log, s_);
  EXPECT_EQ(log.info.header_units, HeaderUnits::kLinear);
  std::string four;
  for (size_t k = 0; k < s_.u.size(); ++k) four += Num(s_.t[k]) + ",0," + Num(s_.u[k]) + "," + Num(s_.y[k]) + "\n";
  ExpectSi(ReadLog(dir_.Write("b.csv", "t,force,torque,position\n" + four)), s_);
}

// LinearUnitsOf: the caller's choice, else the headers', else rotary; a header
// that mixes, contradicts the caller, or disagrees with another run is refused.
TEST_F(LogUnits, TheModelsUnitsFollowTheHeaderUnlessGiven) {
  auto info = [](HeaderUnits u, const std::string& source) {
    LogInfo i;
    i.source = source;
    i.header_units = u;
    i.header_units_text = u == HeaderUnits::kNone ? "" : "input column 'f' in N (linear)";
    return i;
  };
  const LogInfo lin = info(HeaderUnits::kLinear, "lin.csv"), rot = info(HeaderUnits::kRotary, "rot.csv"),
                none = info(HeaderUnits::kNone, "none.h5"), mixed = info(HeaderUnits::kMixed, "mixed.csv");
  EXPECT_TRUE(LinearUnitsOf(std::nullopt, {lin}, "ModelFile::linear"));
  EXPECT_FALSE(LinearUnitsOf(std::nullopt, {rot}, "ModelFile::linear"));
  EXPECT_FALSE(LinearUnitsOf(std::nullopt, {none}, "ModelFile::linear"));
  EXPECT_FALSE(LinearUnitsOf(std::nullopt, {}, "ModelFile::linear"));
  EXPECT_TRUE(LinearUnitsOf(true, {none}, "ModelFile::linear"));
  EXPECT_TRUE(LinearUnitsOf(true, {lin, none}, "ModelFile::linear"));
  EXPECT_TRUE(LinearUnitsOf(std::nullopt, {none, lin}, "ModelFile::linear"));
  auto refusal = [](std::optional<bool> given, const std::vector<LogInfo>& infos) {
    try {
      LinearUnitsOf(given, infos, "ModelFile::linear");
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    ADD_FAILURE() << "accepted";
    return std::string();
  };
  std::string why = refusal(false, {lin});
  EXPECT_NE(why.find("lin.csv: the header says linear units"), std::string::npos) << why;
  EXPECT_NE(why.find("ModelFile::linear rotary was given"), std::string::npos) << why;
  why = refusal(std::nullopt, {mixed});
  EXPECT_NE(why.find("mixed.csv: the header mixes rotary and linear"), std::string::npos) << why;
  why = refusal(true, {mixed});
  EXPECT_NE(why.find("mixes"), std::string::npos) << why;
  why = refusal(std::nullopt, {lin, rot});
  EXPECT_NE(why.find("rot.csv: the header says rotary"), std::string::npos) << why;
  EXPECT_NE(why.find("lin.csv's says linear"), std::string::npos) << why;
}

}  // namespace
}  // namespace zwidth::io
