// SHA-256 as specified in FIPS 180-4 (Secure Hash Standard), section 6.2.
#include "splintcore/core.h"

#include "core/sha256_blocks.h"

// The SHA extensions' path: x86-64 with GCC or Clang (target attributes, <cpuid.h>).
#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
#define SPLINTCORE_SHA_NI 1
#include <cpuid.h>
#include <immintrin.h>

#include <atomic>
#else
#define SPLINTCORE_SHA_NI 0
#endif

namespace splintcore {

namespace {
constexpr uint32_t kRound[64] = {
    0x428a2f98, 0x71374491, 0xb5c0fbcf, 0xe9b5dba5, 0x3956c25b, 0x59f111f1, 0x923f82a4, 0xab1c5ed5,
    0xd807aa98, 0x12835b01, 0x243185be, 0x550c7dc3, 0x72be5d74, 0x80deb1fe, 0x9bdc06a7, 0xc19bf174,
    0xe49b69c1, 0xefbe4786, 0x0fc19dc6, 0x240ca1cc, 0x2de92c6f, 0x4a7484aa, 0x5cb0a9dc, 0x76f988da,
    0x983e5152, 0xa831c66d, 0xb00327c8, 0xbf597fc7, 0xc6e00bf3, 0xd5a79147, 0x06ca6351, 0x14292967,
    0x27b70a85, 0x2e1b2138, 0x4d2c6dfc, 0x53380d13, 0x650a7354, 0x766a0abb, 0x81c2c92e, 0x92722c85,
    0xa2bfe8a1, 0xa81a664b, 0xc24b8b70, 0xc76c51a3, 0xd192e819, 0xd6990624, 0xf40e3585, 0x106aa070,
    0x19a4c116, 0x1e376c08, 0x2748774c, 0x34b0bcb5, 0x391c0cb3, 0x4ed8aa4a, 0x5b9cca4f, 0x682e6ff3,
    0x748f82ee, 0x78a5636f, 0x84c87814, 0x8cc70208, 0x90befffa, 0xa4506ceb, 0xbef9a3f7, 0xc67178f2};

inline uint32_t rotr(uint32_t x, int n) { return (x >> n) | (x << (32 - n)); }
}  // namespace

Sha256::Sha256()
    : state_{0x6a09e667, 0xbb67ae85, 0x3c6ef372, 0xa54ff53a,
             0x510e527f, 0x9b05688c, 0x1f83d9ab, 0x5be0cd19},
      buffer_{} {}

void sha256_blocks_portable(uint32_t state[8], const uint8_t* p, size_t blocks) {
  for (; blocks > 0; --blocks, p += 64) {
    uint32_t w[64];
    for (int i = 0; i < 16; ++i) {
      w[i] = (uint32_t{p[4 * i]} << 24) | (uint32_t{p[4 * i + 1]} << 16) |
             (uint32_t{p[4 * i + 2]} << 8) | uint32_t{p[4 * i + 3]};
    }
    for (int i = 16; i < 64; ++i) {
      uint32_t s0 = rotr(w[i - 15], 7) ^ rotr(w[i - 15], 18) ^ (w[i - 15] >> 3);
      uint32_t s1 = rotr(w[i - 2], 17) ^ rotr(w[i - 2], 19) ^ (w[i - 2] >> 10);
      w[i] = w[i - 16] + s0 + w[i - 7] + s1;
    }
    uint32_t a = state[0], b = state[1], c = state[2], d = state[3];
    uint32_t e = state[4], f = state[5], g = state[6], h = state[7];
    for (int i = 0; i < 64; ++i) {
      uint32_t s1 = rotr(e, 6) ^ rotr(e, 11) ^ rotr(e, 25);
      uint32_t ch = (e & f) ^ (~e & g);
      uint32_t t1 = h + s1 + ch + kRound[i] + w[i];
      uint32_t s0 = rotr(a, 2) ^ rotr(a, 13) ^ rotr(a, 22);
      uint32_t maj = (a & b) ^ (a & c) ^ (b & c);
      uint32_t t2 = s0 + maj;
      h = g;
      g = f;
      f = e;
      e = d + t1;
      d = c;
      c = b;
      b = a;
      a = t1 + t2;
    }
    state[0] += a;
    state[1] += b;
    state[2] += c;
    state[3] += d;
    state[4] += e;
    state[5] += f;
    state[6] += g;
    state[7] += h;
  }
}

#if SPLINTCORE_SHA_NI
namespace {

// Whether the CPU has SHA, SSSE3 and SSE4.1 (CPUID leaf 7 EBX bit 29; leaf 1 ECX bits 9, 19),
// asked once: 0 not yet, 1 no, 2 yes.
std::atomic<int> g_sha_ni{0};

bool cpu_has_sha_ni() {
  int known = g_sha_ni.load(std::memory_order_relaxed);
  if (known == 0) {
    unsigned a = 0, b = 0, c = 0, d = 0;
    bool yes = __get_cpuid(1, &a, &b, &c, &d) != 0 && (c & (1u << 9)) != 0 && (c & (1u << 19)) != 0;
    yes = yes && __get_cpuid_count(7, 0, &a, &b, &c, &d) != 0 && (b & (1u << 29)) != 0;
    known = yes ? 2 : 1;
    g_sha_ni.store(known, std::memory_order_relaxed);
  }
  return known == 2;
}

// Four rounds' message words from the block (big-endian words in lanes 0..3).
__attribute__((target("sha,ssse3,sse4.1"))) inline __m128i load_words(const uint8_t* p,
                                                                      __m128i swap) {
  return _mm_shuffle_epi8(_mm_loadu_si128(reinterpret_cast<const __m128i*>(p)), swap);
}

// The state as SHA-NI holds it: ABEF and CDGH (Intel, "New Instructions Supporting the Secure
// Hash Algorithm on Intel Architecture Processors", 2013). Each step of 4 rounds adds the
// round constants, runs two double rounds and extends the schedule 16 words ahead
// (W[t] = s1(W[t-2]) + W[t-7] + s0(W[t-15]) + W[t-16]: msg1 gives W[t-16] + s0(W[t-15]),
// W[t-7] is the middle of the next two groups, msg2 adds the s1 terms).
__attribute__((target("sha,ssse3,sse4.1"))) void sha_ni_blocks(uint32_t state[8], const uint8_t* p,
                                                               size_t blocks) {
  alignas(16) static const uint8_t kSwap[16] = {3,  2,  1, 0, 7,  6,  5,  4,
                                                11, 10, 9, 8, 15, 14, 13, 12};
  const __m128i swap = _mm_load_si128(reinterpret_cast<const __m128i*>(kSwap));
  __m128i tmp = _mm_loadu_si128(reinterpret_cast<const __m128i*>(state));     // DCBA
  __m128i s1 = _mm_loadu_si128(reinterpret_cast<const __m128i*>(state + 4));  // HGFE
  tmp = _mm_shuffle_epi32(tmp, 0xB1);                                         // CDAB
  s1 = _mm_shuffle_epi32(s1, 0x1B);                                           // EFGH
  __m128i s0 = _mm_alignr_epi8(tmp, s1, 8);                                   // ABEF
  s1 = _mm_blend_epi16(s1, tmp, 0xF0);                                        // CDGH
  for (; blocks > 0; --blocks, p += 64) {
    const __m128i abef = s0, cdgh = s1;
    __m128i w[4] = {load_words(p, swap), load_words(p + 16, swap), load_words(p + 32, swap),
                    load_words(p + 48, swap)};
    for (int g = 0; g < 16; ++g) {
      __m128i k = _mm_add_epi32(w[g & 3],
                                _mm_loadu_si128(reinterpret_cast<const __m128i*>(kRound + 4 * g)));
      s1 = _mm_sha256rnds2_epu32(s1, s0, k);
      k = _mm_shuffle_epi32(k, 0x0E);
      s0 = _mm_sha256rnds2_epu32(s0, s1, k);
      if (g < 12) {
        __m128i next = _mm_sha256msg1_epu32(w[g & 3], w[(g + 1) & 3]);
        next = _mm_add_epi32(next, _mm_alignr_epi8(w[(g + 3) & 3], w[(g + 2) & 3], 4));
        w[g & 3] = _mm_sha256msg2_epu32(next, w[(g + 3) & 3]);
      }
    }
    s0 = _mm_add_epi32(s0, abef);
    s1 = _mm_add_epi32(s1, cdgh);
  }
  tmp = _mm_shuffle_epi32(s0, 0x1B);    // FEBA
  s1 = _mm_shuffle_epi32(s1, 0xB1);     // DCHG
  s0 = _mm_blend_epi16(tmp, s1, 0xF0);  // DCBA
  s1 = _mm_alignr_epi8(s1, tmp, 8);     // HGFE
  _mm_storeu_si128(reinterpret_cast<__m128i*>(state), s0);
  _mm_storeu_si128(reinterpret_cast<__m128i*>(state + 4), s1);
}

}  // namespace

bool sha256_blocks_accelerated(uint32_t state[8], const uint8_t* p, size_t blocks) {
  if (!cpu_has_sha_ni()) return false;
  sha_ni_blocks(state, p, blocks);
  return true;
}
#else
bool sha256_blocks_accelerated(uint32_t*, const uint8_t*, size_t) { return false; }
#endif

void Sha256::blocks(const uint8_t* p, size_t n) {
  if (!sha256_blocks_accelerated(state_, p, n)) sha256_blocks_portable(state_, p, n);
}

void Sha256::update(const void* data, size_t bytes) {
  if (bytes == 0) return;  // (data may be null then: an empty array's; memcpy must not see it)
  const uint8_t* p = static_cast<const uint8_t*>(data);
  length_ += bytes;
  if (buffered_ > 0) {
    size_t take = 64 - buffered_ < bytes ? 64 - buffered_ : bytes;
    std::memcpy(buffer_ + buffered_, p, take);
    buffered_ += take;
    p += take;
    bytes -= take;
    if (buffered_ < 64) return;
    blocks(buffer_, 1);
    buffered_ = 0;
  }
  if (bytes >= 64) {
    blocks(p, bytes / 64);
    p += bytes / 64 * 64;
    bytes %= 64;
  }
  std::memcpy(buffer_, p, bytes);
  buffered_ = bytes;
}

void Sha256::finish(uint8_t digest[32]) {
  uint64_t bits = length_ * 8;
  uint8_t pad[72] = {0x80};
  size_t pad_bytes = buffered_ < 56 ? 56 - buffered_ : 120 - buffered_;
  for (int i = 0; i < 8; ++i)
    pad[pad_bytes + static_cast<size_t>(i)] = static_cast<uint8_t>(bits >> (56 - 8 * i));
  update(pad, pad_bytes + 8);
  for (int i = 0; i < 8; ++i) {
    digest[4 * i] = static_cast<uint8_t>(state_[i] >> 24);
    digest[4 * i + 1] = static_cast<uint8_t>(state_[i] >> 16);
    digest[4 * i + 2] = static_cast<uint8_t>(state_[i] >> 8);
    digest[4 * i + 3] = static_cast<uint8_t>(state_[i]);
  }
}

void Sha256::to_hex(const uint8_t digest[32], char out[65]) {
  static const char kHex[] = "0123456789abcdef";
  for (int i = 0; i < 32; ++i) {
    out[2 * i] = kHex[digest[i] >> 4];
    out[2 * i + 1] = kHex[digest[i] & 15];
  }
  out[64] = '\0';
}

}  // namespace splintcore
