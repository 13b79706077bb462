// io/provenance: SHA-256 against the FIPS 180-4 examples (and a file against
// the same digest), the provenance object's fields.
#include "io/provenance.h"

#include <filesystem>
#include <fstream>
#include <regex>
#include <string>

#include <gtest/gtest.h>

#include "io/atomic_file.h"

namespace zwidth::io {
namespace {

TEST(Sha256, MatchesTheFipsExamples) {
  // FIPS 180-4 / NIST CSRC example values (one block, two blocks, the empty message).
  EXPECT_EQ(Sha256Hex("abc"), "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad");
  EXPECT_EQ(Sha256Hex("abcdbcdecdefdefgefghfghighijhijkijkljklmklmnlmnomnopnopq"),
            "248d6a61d20638b8e5c026930c3e6039a33ce45964ff2167f6ecedd419db06c1");
  EXPECT_EQ(Sha256Hex(""), "e3b0c44298fc1c149afbf4c8996fb92427ae41e4649b934ca495991b7852b855");
}

TEST(Sha256, MillionAsSpanningManyReadBlocks) {
  EXPECT_EQ(Sha256Hex(std::string(1000000, 'a')), "cdc76e5c9914fb9281a1c7e284d73e67f1809a48a497200e046d39ccc7112cd0");
  const std::filesystem::path p = std::filesystem::temp_directory_path() / "zwidth_sha256_test.bin";
  { std::ofstream(p, std::ios::binary) << std::string(1000000, 'a'); }
  EXPECT_EQ(Sha256OfFile(p.string()), "cdc76e5c9914fb9281a1c7e284d73e67f1809a48a497200e046d39ccc7112cd0");
  { std::ofstream(p, std::ios::binary) << "abc"; }  // changed: hashed again, not the cached digest
  EXPECT_EQ(Sha256OfFile(p.string()), Sha256Hex("abc"));
  std::filesystem::remove(p);
}

TEST(Provenance, NamesTheVersionDateCommandAndEachInputOnce) {
  const std::filesystem::path p = std::filesystem::temp_directory_path() / "zwidth_provenance_input.txt";
  { std::ofstream(p, std::ios::binary) << "abc"; }
  ForgetNotedInputs();
  CheckInputFile(p.string(), "log");
  CheckInputFile(p.string(), "log");  // read twice: listed once
  SetInvocation("zwidth fit x -o y");
  const nlohmann::json j = ProvenanceJson();
  EXPECT_FALSE(j["zwidth_version"].get<std::string>().empty());
  EXPECT_TRUE(std::regex_match(j["utc_date"].get<std::string>(), std::regex(R"(\d{4}-\d\d-\d\dT\d\d:\d\d:\d\dZ)")));
  EXPECT_EQ(j["command"], "zwidth fit x -o y");
  ASSERT_EQ(j["inputs"].size(), 1u);
  EXPECT_EQ(j["inputs"][0]["path"], p.string());
  EXPECT_EQ(j["inputs"][0]["sha256"], Sha256Hex("abc"));
  std::filesystem::remove(p);  // an input removed since (a long-lived process): left out, the write goes on
  EXPECT_TRUE(ProvenanceJson()["inputs"].empty());
  ForgetNotedInputs();
}

}  // namespace
}  // namespace zwidth::io
