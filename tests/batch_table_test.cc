// io/batch_table.h: manifests as a spreadsheet writes them, the table's CSV
// and HDF5 read back cell for cell, globs, and the resume hash's sensitivity.
#include "io/batch_table.h"

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <random>
#include <string>

#include <gtest/gtest.h>

#include "io/log.h"
#include "model/error.h"
#include "tests/test_util.h"

namespace zwidth::io {
namespace {

std::string Write(const std::string& path, const std::string& text) {
  std::ofstream(path, std::ios::binary) << text;
  return path;
}

TEST(BatchTable, CsvOfAnyCellsReadsBackCellForCell) {
  std::mt19937 rng(7);
  const std::string alphabet = "ab,\"\n\r x1.5e-3";
  BatchTable t;
  t.columns = {"serial", "error", "K"};
  for (int r = 0; r < 200; ++r) {
    std::map<std::string, std::string> row;
    for (const std::string& c : t.columns) {
      std::string cell;
      for (int k = std::uniform_int_distribution<int>(0, 8)(rng); k > 0; --k) {
        cell += alphabet[std::uniform_int_distribution<size_t>(0, alphabet.size() - 1)(rng)];
      }
      row[c] = cell;
    }
    row["serial"] = "S" + std::to_string(r);  // never an all-empty line
    t.rows.push_back(row);
  }
  const BatchTable back = ParseBatchCsv(FormatBatchCsv(t), "t.csv");
  EXPECT_EQ(back.columns, t.columns);
  ASSERT_EQ(back.rows.size(), t.rows.size());
  for (size_t r = 0; r < t.rows.size(); ++r) EXPECT_EQ(back.rows[r], t.rows[r]) << "row " << r;
}

// A table as zwidth batch writes it, from a seed: value columns as %.17g of
// random doubles (nan where no std), an error row with the value cells empty,
// text with commas, quotes and line breaks, a number typed otherwise ("1e-3").
BatchTable SeededBatch(unsigned seed, int units) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> normal(0.0, 1.0);
  auto full = [](double v) {
    char b[40];
    std::snprintf(b, sizeof b, "%.17g", v);
    return std::string(b);
  };
  BatchTable t;
  t.columns = {"serial", "logs", "status", "error", "verdict", "verdict_reasons", "input_hash", "fit_quality",
               "warnings", "m", "m_std", "b", "b_std", "delay_samples", "modes", "mode1_omega", "mode1_omega_std",
               "d2_K_cr_at_zero_B", "d2_K_cr_max", "d2_K_cr_max_std", "d2_B_t", "d2_B_max", "d2_B_max_from_zero",
               "note", "empty"};
  for (int u = 0; u < units; ++u) {
    std::map<std::string, std::string> r;
    r["serial"] = "SN-" + std::to_string(u);
    r["logs"] = "/line/unit " + std::to_string(u) + ",a.h5";
    r["input_hash"] = full(static_cast<double>(rng()));  // digits, kept as text elsewhere
    if (u % 5 == 3) {  // a broken log: its error, no values
      r["status"] = "input_error";
      r["error"] = "line 3, column 'torque': \"x\" is not a number\nfix the log";
      r["verdict"] = "error";
    } else {
      r["status"] = "ok";
      r["verdict"] = u % 2 ? "pass" : "marginal";
      r["verdict_reasons"] = u % 2 ? "" : "d2_K_cr_max>=30 met within noise (value 30.1, std 0.2, P = 0.69)";
      r["fit_quality"] = "good";
      r["m"] = full(1.2e-4 * (1 + 0.05 * normal(rng)));
      r["m_std"] = full(u % 4 == 0 ? std::nan("") : 1e-6 * std::abs(normal(rng)));
      r["b"] = full(2.5e-3 * (1 + 0.1 * normal(rng)));
      r["b_std"] = full(3e-4 * std::abs(normal(rng)));
      r["delay_samples"] = "1";
      r["modes"] = "1";
      r["mode1_omega"] = full(1100 + 30 * normal(rng));
      r["mode1_omega_std"] = full(2 * std::abs(normal(rng)));
      r["d2_K_cr_at_zero_B"] = full(20 + normal(rng));
      r["d2_K_cr_max"] = full(30 + normal(rng));
      r["d2_K_cr_max_std"] = full(0.3);
      r["d2_B_t"] = full(u == 1 ? std::numeric_limits<double>::infinity() : 0.01 + 1e-4 * normal(rng));
      r["d2_B_max"] = full(0.05 + 1e-3 * normal(rng));
      r["d2_B_max_from_zero"] = full(-0.0);
    }
    if (u == 2) r["note"] = "1e-3";  // a number as typed: stays text
    if (u == 4) r["warnings"] = "few averages | band, from 2 Hz";
    t.rows.push_back(r);
  }
  return t;
}

TEST(BatchTable, HdfAndCsvTablesReadBackEqualCellForCell) {
  test::TempDir dir;
  const BatchTable t = SeededBatch(11, 12);
  WriteBatchTable(dir / "t.csv", t);
  WriteBatchTable(dir / "t.h5", t);
  WriteBatchTable(dir / "t.HDF5", t);
  const BatchTable csv = ReadBatchTable(dir / "t.csv");
  // What the CSV gives back: every column of every row (a missing cell is empty).
  const BatchTable want = ParseBatchCsv(FormatBatchCsv(t), "t");
  EXPECT_EQ(csv.columns, want.columns);
  EXPECT_EQ(csv.rows, want.rows);
  for (const char* name : {"t.h5", "t.HDF5"}) {
    std::ifstream in(dir / name, std::ios::binary);
    char sig[8] = {};
    in.read(sig, 8);
    EXPECT_EQ(std::string(sig, 8), std::string("\x89HDF\r\n\x1a\n", 8)) << name << " is not HDF5";
    const BatchTable h5 = ReadBatchTable(dir / name);
    EXPECT_EQ(h5.columns, csv.columns) << name;
    ASSERT_EQ(h5.rows.size(), csv.rows.size()) << name;
    for (size_t r = 0; r < csv.rows.size(); ++r) EXPECT_EQ(h5.rows[r], csv.rows[r]) << name << " row " << r;
  }
  // An HDF5 table of no rows keeps its columns.
  WriteBatchTable(dir / "none.h5", BatchTable{{"serial", "m"}, {}});
  EXPECT_EQ(ReadBatchTable(dir / "none.h5").columns, (std::vector<std::string>{"serial", "m"}));
  EXPECT_TRUE(ReadBatchTable(dir / "none.h5").rows.empty());
}

TEST(BatchTable, HdfTableRefusesWhatItCannotHoldAndWritesNothing) {
  test::TempDir dir;
  auto message = [&](const BatchTable& t, const std::string& name) {
    try {
      WriteBatchTable(dir / name, t);
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  EXPECT_NE(message(BatchTable{{"serial", "a/b"}, {{{"serial", "A"}}}}, "slash.h5").find("'a/b'"), std::string::npos);
  EXPECT_NE(message(BatchTable{{"serial"}, {{{"serial", std::string("A\0B", 3)}}}}, "nul.h5").find("row 1, column 'serial'"),
            std::string::npos);
  EXPECT_FALSE(std::filesystem::exists(dir / "slash.h5"));
  EXPECT_FALSE(std::filesystem::exists(dir / "nul.h5"));
  for (const auto& e : std::filesystem::directory_iterator(dir.path())) ADD_FAILURE() << "left behind: " << e.path();
}

TEST(BatchTable, AnHdfFileThatIsNoTableOrIsTruncatedIsAnInputErrorNamingIt) {
  test::TempDir dir;
  WriteLog(dir / "log.h5", 1000.0, {1, 2, 3}, {4, 5, 6});  // HDF5, but a log
  auto message = [&](const std::string& path) {
    try {
      ReadBatchTable(path);
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  const std::string log = message(dir / "log.h5");
  EXPECT_NE(log.find("log.h5"), std::string::npos) << log;
  EXPECT_NE(log.find("not a table zwidth batch wrote"), std::string::npos) << log;
  WriteBatchTable(dir / "t.h5", SeededBatch(3, 4));
  std::ifstream in(dir / "t.h5", std::ios::binary);
  std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const std::string cut = message(dir.Write("cut.h5", bytes.substr(0, bytes.size() / 2)));
  EXPECT_NE(cut.find("cut.h5"), std::string::npos) << cut;
  EXPECT_NE(message(dir / "missing.h5").find("not a regular file"), std::string::npos);
}

TEST(BatchTable, AMissingCellIsWrittenEmpty) {
  BatchTable t{{"serial", "m"}, {{{"serial", "A"}}, {{"serial", "B"}, {"m", "1"}}}};
  EXPECT_EQ(FormatBatchCsv(t), "serial,m\nA,\nB,1\n");
}

TEST(BatchTable, ManifestRowsGetTheirFlagsAndPathsFromTheManifestsFolder) {
  test::TempDir dir;
  const std::string m = Write(dir.path().string() + "/units.csv",
                              "path,serial,rate,output-scale\r\nu1.csv,SN 1,1000,\r\n\r\n/abs/u2.h5,\"SN,2\",,2\r\n");
  const std::vector<BatchEntry> e = ReadManifest(m);
  ASSERT_EQ(e.size(), 2u);
  EXPECT_EQ(e[0].serial, "SN 1");
  EXPECT_EQ(e[0].path, dir.path().string() + "/u1.csv");
  ASSERT_EQ(e[0].flags.size(), 1u);  // the empty output-scale keeps the command's flag
  EXPECT_EQ(e[0].flags[0], (std::pair<std::string, std::string>{"rate", "1000"}));
  EXPECT_EQ(e[1].serial, "SN,2");
  EXPECT_EQ(e[1].path, "/abs/u2.h5");
  EXPECT_EQ(e[1].flags.size(), 1u);
  EXPECT_NE(e[1].origin.find("line 4"), std::string::npos) << e[1].origin;  // the blank line counts
}

TEST(BatchTable, ManifestMistakesNameTheLine) {
  test::TempDir dir;
  auto message = [&](const std::string& text) {
    try {
      ReadManifest(Write(dir.path().string() + "/m.csv", text));
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  EXPECT_NE(message("serial,path\nA,a.csv,3\n").find("line 2: 3 fields"), std::string::npos);
  EXPECT_NE(message("serial\nA\n").find("line 1"), std::string::npos);
  EXPECT_NE(message("serial,path\n,a.csv\n").find("column 'serial'"), std::string::npos);
  EXPECT_NE(message("serial,path\n\"A,a.csv\n").find("never closed"), std::string::npos);
  EXPECT_NE(message("serial,path\n").find("no units"), std::string::npos);
  EXPECT_NE(message("serial,path,serial\nA,b,c\n").find("named twice"), std::string::npos);
}

TEST(BatchTable, GlobsExpandInNameOrderAndAPathTwiceIsRefused) {
  test::TempDir dir;
  for (const char* n : {"b.csv", "a.csv", "c.txt"}) Write(dir.path().string() + "/" + n, "x");
  const std::vector<BatchEntry> e = EntriesFromArguments({dir.path().string() + "/*.csv", dir.path().string() + "/c.txt"});
  ASSERT_EQ(e.size(), 3u);
  EXPECT_EQ(e[0].path, dir.path().string() + "/a.csv");
  EXPECT_EQ(e[1].path, dir.path().string() + "/b.csv");
  EXPECT_EQ(e[2].serial, dir.path().string() + "/c.txt");
  EXPECT_THROW(EntriesFromArguments({dir.path().string() + "/*.csv", dir.path().string() + "/a.csv"}), InputError);
  EXPECT_THROW(EntriesFromArguments({dir.path().string() + "/*.h5"}), InputError);
}

TEST(BatchTable, TheHashFollowsEveryByteAndTheOptionsAndNothingElse) {
  test::TempDir dir;
  const std::string a = Write(dir.path().string() + "/a.csv", "t,u,y\n0,1,2\n");
  const std::string h = HashInputs({a}, "--delays=2,");
  EXPECT_EQ(h.size(), 16u);
  EXPECT_EQ(HashInputs({Write(dir.path().string() + "/copy.csv", "t,u,y\n0,1,2\n")}, "--delays=2,"), h);  // bytes, not names
  EXPECT_NE(HashInputs({a}, "--delays=4,"), h);
  Write(a, "t,u,y\n0,1,3\n");
  EXPECT_NE(HashInputs({a}, "--delays=2,"), h);
  // Size-prefixed: moving bytes between the options and the file changes it.
  EXPECT_NE(HashInputs({Write(dir.path().string() + "/b", "xy")}, "a"), HashInputs({Write(dir.path().string() + "/c", "y")}, "ax"));
  EXPECT_EQ(HashInputs({dir.path().string() + "/missing.csv"}, ""), "");
  // FNV-1a of known bytes: the 8-byte size 0, nothing, and no file.
  std::uint64_t ref = 14695981039346656037ull;
  for (int i = 0; i < 8; ++i) ref = (ref ^ 0u) * 1099511628211ull;
  char hex[17];
  std::snprintf(hex, sizeof hex, "%016llx", static_cast<unsigned long long>(ref));
  EXPECT_EQ(HashInputs({}, ""), hex);
}

}  // namespace
}  // namespace zwidth::io
