// io/log_text.cc: the text dialects of io/log.h (moved from log_test.cc, tests
// unchanged): files written here byte by byte, read back, compared sample for
// sample with what was written (printed with %.17g: exact).
#include <cmath>
#include <filesystem>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "io/log.h"
#include "model/error.h"
#include "tests/log_formats.h"

namespace zwidth::io {
namespace {

namespace fs = std::filesystem;

TEST_F(LogFormats, CommaHeaderLf) {
  const Signals s = MakeSignals();
  const Log log = ReadLog(Write("a.csv", "t,torque,position\n" + Rows(s, ",", "\n")));
  ExpectSame(log, s);
  EXPECT_NE(log.info.layout.find("','-separated"), std::string::npos) << log.info.layout;
  EXPECT_NE(log.info.layout.find("header at line 1"), std::string::npos) << log.info.layout;
}

TEST_F(LogFormats, TrailingDelimiterOfSpreadsheetExports) {
  const Signals s = MakeSignals();
  ExpectSame(ReadLog(Write("tr.csv", "t,torque,position,\n" + Rows(s, ",", ",\n"))), s);
}

TEST_F(LogFormats, SemicolonCrlfGivenOrDetected) {
  const Signals s = MakeSignals();
  const std::string p = Write("b.txt", "t;torque;position\r\n" + Rows(s, ";", "\r\n"));
  ExpectSame(ReadLog(p), s);
  LogSelect sel;
  sel.delimiter = ";";
  ExpectSame(ReadLog(p, sel), s);
  sel.delimiter = ",";  // wrong: said so, with the line
  EXPECT_NE(Refusal(p, sel).find("does not split it into numbers"), std::string::npos);
}

// The file: '#' lines first, the header in the last of them, tab
// separated; CR-only line ends (old Mac / some loggers).
TEST_F(LogFormats, TabCommentedHeaderCrOnly) {
  const Signals s = MakeSignals();
  const std::string p =
      Write("c.dat", "# SLFR RTP OL_Test\r# operator: x\r#t\ttorque\tposition\r" + Rows(s, "\t", "\r"));
  const Log log = ReadLog(p);
  ExpectSame(log, s);
  EXPECT_NE(log.info.layout.find("tab-separated"), std::string::npos) << log.info.layout;
  EXPECT_NE(log.info.layout.find("header at line 3 (comment)"), std::string::npos) << log.info.layout;
}

TEST_F(LogFormats, WhitespaceNoHeaderByPositionMilliseconds) {
  const Signals s = MakeSignals();
  std::string text;
  for (size_t k = 0; k < s.u.size(); ++k) text += "  " + Num(s.t[k] * 1e3) + "   " + Num(s.u[k]) + "\t" + Num(s.y[k]) + "\n";
  const std::string p = Write("d.txt", text);
  LogSelect sel;
  sel.time_column = "1";
  sel.input_column = "2";
  sel.output_column = "3";
  // Time in ms read as s implies 1 Hz: refused with the suggestion.
  EXPECT_NE(Refusal(p, sel).find("LogSelect::time_unit ms"), std::string::npos);
  sel.time_unit = "ms";
  const Log log = ReadLog(p, sel);
  ExpectSame(log, s);
  EXPECT_NE(log.info.layout.find("whitespace-separated"), std::string::npos) << log.info.layout;
  EXPECT_NE(log.info.layout.find("no header"), std::string::npos) << log.info.layout;
  sel.input_column = "torque";  // no header: said so, with the positions
  EXPECT_NE(Refusal(p, sel).find("position 1..3"), std::string::npos);
}

TEST_F(LogFormats, BomQuotedNamesAnyCaseAndScales) {
  const Signals s = MakeSignals();
  const std::string p = Write("e.csv", "\xEF\xBB\xBF\"Time\",\"U [V]\",\"Counts\"\n" + Rows(s, ",", "\n"));
  LogSelect sel;
  sel.time_column = "time";  // case-insensitive match
  sel.input_column = "U [V]";
  sel.output_column = "3";  // by position beside names
  sel.input_scale = 0.25;
  sel.output_scale = -2.0;
  ExpectSame(ReadLog(p, sel), s, 0.25, -2.0);
}

TEST_F(LogFormats, MissingColumnSaysDelimiterAndHeader) {
  const Signals s = MakeSignals();
  const std::string p = Write("f.csv", "t;current;position\n" + Rows(s, ";", "\n"));
  const std::string m = Refusal(p, {});
  EXPECT_NE(m.find("no column 'torque'"), std::string::npos) << m;
  EXPECT_NE(m.find("';'-separated"), std::string::npos) << m;
  EXPECT_NE(m.find("header at line 1: t, current, position"), std::string::npos) << m;
  EXPECT_NE(m.find("LogSelect::input_column"), std::string::npos) << m;
}

// The 610 kB CR-only file: no message may echo more than one line.
TEST_F(LogFormats, LongCrOnlyFileIsNotEchoed) {
  const Signals s = MakeSignals(20000);
  const std::string p = Write("g.csv", "t,current,position\r" + Rows(s, ",", "\r"));
  ASSERT_GT(fs::file_size(p), 600000u);
  Refusal(p, {});
  // A binary-looking single line: refused, shown truncated.
  const std::string q = Write("h.csv", std::string(200, 'x') + "," + std::string(5000, 'y') + "\n1,2,3\n");
  const std::string m = Refusal(q, {});
  EXPECT_LT(m.size(), 400u) << m;
}

TEST_F(LogFormats, RateOverridesJitterWithAWarning) {
  Signals s = MakeSignals();
  for (size_t k = 1; k < s.t.size(); k += 2) s.t[k] += 30e-6;  // 30 us jitter (3 % of 1 ms)
  const std::string p = Write("j.csv", "t,torque,position\n" + Rows(s, ",", "\n"));
  EXPECT_NE(Refusal(p, {}).find("not uniformly sampled"), std::string::npos);
  LogSelect sel;
  sel.sample_rate_hz = 1000.0;
  const Log log = ReadLog(p, sel);
  ExpectSame(log, s);
  ASSERT_EQ(log.info.warnings.size(), 1u);
  EXPECT_NE(log.info.warnings[0].find("deviate from 1/rate by up to 3e-05 s (3 %"), std::string::npos)
      << log.info.warnings[0];
}

TEST_F(LogFormats, RefusalsSayWhatWasFound) {
  // Header and data disagree in field count.
  EXPECT_NE(Refusal(Write("k.csv", "t,torque\n0,1,2\n0.001,2,3\n"), {}).find("has 2 fields"), std::string::npos);
  // Decimal commas mixed with points (decimal commas alone are read: log_units_test.cc).
  EXPECT_NE(Refusal(Write("l.csv", "t;torque;position\n0;1,5;2.5\n"), {}).find("looks like data"), std::string::npos);
  // A short row.
  EXPECT_NE(Refusal(Write("m.csv", "t,torque,position\n0,1,2\n0.001,2\n"), {}).find("line 3 has 2 fields"),
            std::string::npos);
  // Bad flags.
  LogSelect sel;
  sel.time_unit = "min";
  EXPECT_NE(Refusal(Write("n.csv", "t,torque,position\n0,1,2\n"), sel).find("LogSelect::time_unit 'min'"), std::string::npos);
  sel = {};
  sel.input_scale = 0.0;
  EXPECT_NE(Refusal(Write("o.csv", "t,torque,position\n0,1,2\n"), sel).find("LogSelect::input_scale"), std::string::npos);
}

// A 10 kHz loop logged with its time in ms reads as exactly 10 Hz in s.
// The header's unit (t_ms, "t [ms]", ...) is a hint: without LogSelect::time_unit
// the log is refused, naming the column; a time column in s implying exactly
// 10 Hz is refused (the range is [10 Hz, 1 MHz] exclusive at 10), 10-100 Hz warned.
TEST_F(LogFormats, TimeUnitFromTheHeaderAndLowRates) {
  const Signals s = MakeSignals(3000, 10000.0);  // t in s at 10 kHz
  for (const std::string name : {"t_ms", "time_ms", "t [ms]", "Time (ms)", "t_us", "t [us]", "time_usec",
                                 "t [\xc2\xb5s]"}) {
    const std::string unit = name.find("ms") != std::string::npos ? "ms" : "us";
    const std::string p = Write("u.csv", name + ",torque,position\n" + Rows(s, ",", "\n", unit == "ms" ? 1e3 : 1e6));
    LogSelect sel;
    sel.time_column = name;
    const std::string m = Refusal(p, sel);
    EXPECT_NE(m.find("the time column '" + name + "' looks like " + (unit == "ms" ? "milli" : "micro")),
              std::string::npos) << m;
    EXPECT_NE(m.find("pass LogSelect::time_unit " + unit), std::string::npos) << m;
    sel.time_unit = unit;
    const Log log = ReadLog(p, sel);
    EXPECT_NEAR(log.info.sample_rate_hz, 10000.0, 1e-6) << name;
    EXPECT_TRUE(log.info.warnings.empty()) << name;
  }
  // Names that carry no unit word: read in s.
  for (const std::string name : {"t", "time_s", "terms", "t [s]"}) {
    LogSelect sel;
    sel.time_column = name;
    const Log log = ReadLog(Write("v.csv", name + ",torque,position\n" + Rows(s, ",", "\n")), sel);
    EXPECT_NEAR(log.info.sample_rate_hz, 10000.0, 1e-6) << name;
  }
  // Exactly 10 Hz (10 kHz in ms under a plain "t"): refused with the suggestion.
  const std::string p10 = Write("w.csv", "t,torque,position\n" + Rows(s, ",", "\n", 1e3));
  EXPECT_NE(Refusal(p10, {}).find("pass LogSelect::time_unit ms (1e+04 Hz)"), std::string::npos) << Refusal(p10, {});
  // 50 Hz: read, with a warning naming the flag; LogSelect::time_unit s silences it.
  const std::string p50 = Write("x.csv", "t,torque,position\n" + Rows(s, ",", "\n", 200.0));
  Log log = ReadLog(p50, {});
  EXPECT_NEAR(log.info.sample_rate_hz, 50.0, 1e-9);
  ASSERT_EQ(log.info.warnings.size(), 1u);
  EXPECT_NE(log.info.warnings[0].find("implies 50 Hz"), std::string::npos) << log.info.warnings[0];
  EXPECT_NE(log.info.warnings[0].find("LogSelect::time_unit ms (5e+04 Hz)"), std::string::npos) << log.info.warnings[0];
  LogSelect sel;
  sel.time_unit = "s";
  EXPECT_TRUE(ReadLog(p50, sel).info.warnings.empty());
  // 100 Hz and above: no warning.
  log = ReadLog(Write("y.csv", "t,torque,position\n" + Rows(s, ",", "\n", 100.0)), {});
  EXPECT_NEAR(log.info.sample_rate_hz, 100.0, 1e-9);
  EXPECT_TRUE(log.info.warnings.empty());
}

}  // namespace
}  // namespace zwidth::io
