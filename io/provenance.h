// Provenance of every JSON file zwidth writes (issue 26): the zwidth
// version, the UTC date, the command line (or the Python call) and the
// SHA-256 of every input file the command read (those CheckInputFile noted),
//   "provenance": {"zwidth_version": "0.9.0", "utc_date": "2026-12-02T01:20:00Z",
//                  "command": "zwidth fit log.csv -o model.json",
//                  "inputs": [{"path": "log.csv", "sha256": "9f86d0..."}]}
// (docs/schema/provenance.schema.json). report.html's provenance section shows
// the same data.
#pragma once

#include <string>
#include <string_view>
#include <vector>

#include <nlohmann/json.hpp>

namespace zwidth::io {

// The command as the user typed it (the zwidth executable sets it from argv;
// the Python module to the call, e.g. "zwidth.fit('log.h5')"); "" until set.
void SetInvocation(const std::string& command);
std::string Invocation();

// Now as ISO 8601 UTC, "2026-12-02T01:20:00Z".
std::string UtcNow();

// SHA-256 (FIPS 180-4) as 64 lower-case hex digits.
std::string Sha256Hex(std::string_view data);
// Of a file's bytes, read in blocks; InputError when it cannot be read.
std::string Sha256OfFile(const std::string& path);

// The provenance object above, for the inputs noted so far that can still be
// read (one removed since it was read is left out).
nlohmann::json ProvenanceJson();

// While one lives, ProvenanceJson on its thread lists exactly `inputs`
// instead of every input the process noted: the files of one unit of a
// batch, whose other units' logs are read on other threads meanwhile.
class ProvenanceInputsScope {
 public:
  explicit ProvenanceInputsScope(std::vector<std::string> inputs);
  ~ProvenanceInputsScope();
  ProvenanceInputsScope(const ProvenanceInputsScope&) = delete;
  ProvenanceInputsScope& operator=(const ProvenanceInputsScope&) = delete;

 private:
  std::vector<std::string> inputs_;
  const std::vector<std::string>* outer_;
};

}  // namespace zwidth::io
