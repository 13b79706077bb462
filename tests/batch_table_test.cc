// io/batch_table.h: manifests as a spreadsheet writes them, the table's CSV
// read back cell for cell, globs, and the resume hash's sensitivity.
#include "io/batch_table.h"

#include <fstream>
#include <random>
#include <string>

#include <gtest/gtest.h>

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
