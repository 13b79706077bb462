#include "io/provenance.h"

#include <algorithm>
#include <array>
#include <cstdint>
#include <ctime>
#include <fstream>
#include <map>
#include <mutex>
#include <vector>
#include <utility>
#include <tuple>

#include <sys/stat.h>

#include "build_info.h"
#include "io/atomic_file.h"
#include "io/printable.h"
#include "model/error.h"

namespace zwidth::io {
namespace {

std::mutex g_mutex;
std::string g_invocation;

// FIPS 180-4, section 6.2: the SHA-256 compression of 64-byte blocks.
class Sha256 {
 public:
  void Update(const unsigned char* p, size_t n) {
    total_ += n;
    while (n > 0) {
      const size_t take = std::min(n, size_t{64} - fill_);
      std::copy(p, p + take, block_.begin() + fill_);
      fill_ += take; p += take; n -= take;
      if (fill_ == 64) { Compress(); fill_ = 0; }
    }
  }
  std::string Hex() {
    const uint64_t bits = total_ * 8;
    const unsigned char one = 0x80, zero = 0;
    Update(&one, 1);
    while (fill_ != 56) Update(&zero, 1);
    unsigned char len[8];
    for (int i = 0; i < 8; ++i) len[i] = static_cast<unsigned char>(bits >> (56 - 8 * i));
    Update(len, 8);
    static const char* digits = "0123456789abcdef";
    std::string out;
    for (uint32_t h : h_) for (int s = 28; s >= 0; s -= 4) out += digits[(h >> s) & 15];
    return out;
  }

 private:
  static uint32_t Rot(uint32_t x, int n) { return (x >> n) | (x << (32 - n)); }
  void Compress() {
    static constexpr uint32_t k[64] = {
        0x428a2f98, 0x71374491, 0xb5c0fbcf, 0xe9b5dba5, 0x3956c25b, 0x59f111f1, 0x923f82a4, 0xab1c5ed5, 0xd807aa98,
        0x12835b01, 0x243185be, 0x550c7dc3, 0x72be5d74, 0x80deb1fe, 0x9bdc06a7, 0xc19bf174, 0xe49b69c1, 0xefbe4786,
        0x0fc19dc6, 0x240ca1cc, 0x2de92c6f, 0x4a7484aa, 0x5cb0a9dc, 0x76f988da, 0x983e5152, 0xa831c66d, 0xb00327c8,
        0xbf597fc7, 0xc6e00bf3, 0xd5a79147, 0x06ca6351, 0x14292967, 0x27b70a85, 0x2e1b2138, 0x4d2c6dfc, 0x53380d13,
        0x650a7354, 0x766a0abb, 0x81c2c92e, 0x92722c85, 0xa2bfe8a1, 0xa81a664b, 0xc24b8b70, 0xc76c51a3, 0xd192e819,
        0xd6990624, 0xf40e3585, 0x106aa070, 0x19a4c116, 0x1e376c08, 0x2748774c, 0x34b0bcb5, 0x391c0cb3, 0x4ed8aa4a,
        0x5b9cca4f, 0x682e6ff3, 0x748f82ee, 0x78a5636f, 0x84c87814, 0x8cc70208, 0x90befffa, 0xa4506ceb, 0xbef9a3f7,
        0xc67178f2};
    uint32_t w[64];
    for (int i = 0; i < 16; ++i) {
      w[i] = uint32_t{block_[4 * i]} << 24 | uint32_t{block_[4 * i + 1]} << 16 | uint32_t{block_[4 * i + 2]} << 8 |
             uint32_t{block_[4 * i + 3]};
    }
    for (int i = 16; i < 64; ++i) {
      const uint32_t s0 = Rot(w[i - 15], 7) ^ Rot(w[i - 15], 18) ^ (w[i - 15] >> 3);
      const uint32_t s1 = Rot(w[i - 2], 17) ^ Rot(w[i - 2], 19) ^ (w[i - 2] >> 10);
      w[i] = w[i - 16] + s0 + w[i - 7] + s1;
    }
    uint32_t a = h_[0], b = h_[1], c = h_[2], d = h_[3], e = h_[4], f = h_[5], g = h_[6], h = h_[7];
    for (int i = 0; i < 64; ++i) {
      const uint32_t t1 = h + (Rot(e, 6) ^ Rot(e, 11) ^ Rot(e, 25)) + ((e & f) ^ (~e & g)) + k[i] + w[i];
      const uint32_t t2 = (Rot(a, 2) ^ Rot(a, 13) ^ Rot(a, 22)) + ((a & b) ^ (a & c) ^ (b & c));
      h = g; g = f; f = e; e = d + t1; d = c; c = b; b = a; a = t1 + t2;
    }
    const uint32_t add[8] = {a, b, c, d, e, f, g, h};
    for (int i = 0; i < 8; ++i) h_[i] += add[i];
  }
  std::array<uint32_t, 8> h_ = {0x6a09e667, 0xbb67ae85, 0x3c6ef372, 0xa54ff53a,
                                0x510e527f, 0x9b05688c, 0x1f83d9ab, 0x5be0cd19};
  std::array<unsigned char, 64> block_{};
  size_t fill_ = 0;
  uint64_t total_ = 0;
};

}  // namespace

void SetInvocation(const std::string& command) {
  std::lock_guard<std::mutex> lock(g_mutex);
  g_invocation = command;
}

std::string Invocation() {
  std::lock_guard<std::mutex> lock(g_mutex);
  return g_invocation;
}

std::string UtcNow() {
  const std::time_t t = std::time(nullptr);
  std::tm tm{};
  gmtime_r(&t, &tm);
  char b[32];
  std::strftime(b, sizeof b, "%Y-%m-%dT%H:%M:%SZ", &tm);
  return b;
}

std::string Sha256Hex(std::string_view data) {
  Sha256 s;
  s.Update(reinterpret_cast<const unsigned char*>(data.data()), data.size());
  return s.Hex();
}

std::string Sha256OfFile(const std::string& path) {
  // A command writes several files from the same inputs (run: model.json,
  // summary.json): each file is hashed once while it is unchanged.
  static std::mutex cache_mutex;
  static std::map<std::string, std::pair<std::tuple<long, long, long long>, std::string>> cache;
  struct stat st;
  if (::stat(path.c_str(), &st) != 0) throw InputError(path + ": cannot read the input to hash it (removed?)");
  const std::tuple<long, long, long long> key{st.st_mtim.tv_sec, st.st_mtim.tv_nsec, static_cast<long long>(st.st_size)};
  {
    std::lock_guard<std::mutex> lock(cache_mutex);
    auto it = cache.find(path);
    if (it != cache.end() && it->second.first == key) return it->second.second;
  }
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path + ": cannot read the input to hash it");
  Sha256 s;
  std::array<char, 1 << 16> buf;
  while (in.read(buf.data(), buf.size()) || in.gcount() > 0) {
    s.Update(reinterpret_cast<const unsigned char*>(buf.data()), static_cast<size_t>(in.gcount()));
  }
  if (in.bad()) throw InputError(path + ": read error while hashing the input");
  const std::string hex = s.Hex();
  std::lock_guard<std::mutex> lock(cache_mutex);
  cache[path] = {key, hex};
  return hex;
}

namespace {
thread_local const std::vector<std::string>* t_scope_inputs = nullptr;
}  // namespace

ProvenanceInputsScope::ProvenanceInputsScope(std::vector<std::string> inputs)
    : inputs_(std::move(inputs)), outer_(t_scope_inputs) {
  t_scope_inputs = &inputs_;
}
ProvenanceInputsScope::~ProvenanceInputsScope() { t_scope_inputs = outer_; }

nlohmann::json ProvenanceJson() {
  nlohmann::json inputs = nlohmann::json::array();
  for (const std::string& path : t_scope_inputs ? *t_scope_inputs : NotedInputs()) {
    // An input of an earlier command of a long-lived process (a library
    // user's), removed since, is no input of this file: skipped, never a
    // reason to fail the write.
    try {
      inputs.push_back({{"path", Utf8ForJson(path)}, {"sha256", Sha256OfFile(path)}});
    } catch (const InputError&) {
    }
  }
  return {{"zwidth_version", build_info::kVersion}, {"utc_date", UtcNow()},
          {"command", Utf8ForJson(Invocation())}, {"inputs", inputs}};
}

}  // namespace zwidth::io
