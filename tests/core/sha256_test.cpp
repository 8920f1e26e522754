#include <cstdio>
#include <random>

#include "core/sha256_blocks.h"
#include "support/test_util.h"

namespace splintcore {
namespace {

// Test vectors from FIPS 180-4 examples (NIST CSRC).
TEST(Sha256, KnownVectors) {
  EXPECT_EQ(test::sha256_hex("", 0),
            "e3b0c44298fc1c149afbf4c8996fb92427ae41e4649b934ca495991b7852b855");
  EXPECT_EQ(test::sha256_hex("abc", 3),
            "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad");
  const char* two_blocks = "abcdbcdecdefdefgefghfghighijhijkijkljklmklmnlmnomnopnopq";
  EXPECT_EQ(test::sha256_hex(two_blocks, std::strlen(two_blocks)),
            "248d6a61d20638b8e5c026930c3e6039a33ce45964ff2167f6ecedd419db06c1");
  std::string million(1000000, 'a');
  EXPECT_EQ(test::sha256_hex(million.data(), million.size()),
            "cdc76e5c9914fb9281a1c7e284d73e67f1809a48a497200e046d39ccc7112cd0");
}

TEST(Sha256, ChunkingDoesNotMatter) {
  std::string data(1000, '\0');
  for (size_t i = 0; i < data.size(); ++i) data[i] = static_cast<char>(i * 7);
  std::string whole = test::sha256_hex(data.data(), data.size());
  for (size_t chunk : {1u, 3u, 63u, 64u, 65u, 999u}) {
    Sha256 sha;
    for (size_t i = 0; i < data.size(); i += chunk) {
      sha.update(data.data() + i, std::min(chunk, data.size() - i));
    }
    uint8_t d[32];
    sha.finish(d);
    char hex[65];
    Sha256::to_hex(d, hex);
    EXPECT_EQ(whole, hex) << "chunk " << chunk;
  }
}

// The SHA extensions' compression (where this CPU has them) against the portable one: the same
// state after 1..40 random blocks from random states. Skipped where there are none.
TEST(Sha256, AcceleratedBlocksMatchThePortableOnes) {
  std::mt19937_64 rng(180);
  std::vector<uint8_t> data(64 * 40);
  int compared = 0;
  for (int draw = 0; draw < 200; ++draw) {
    for (uint8_t& b : data) b = static_cast<uint8_t>(rng());
    uint32_t a[8], b[8];
    for (int i = 0; i < 8; ++i) a[i] = b[i] = static_cast<uint32_t>(rng());
    const size_t blocks = 1 + static_cast<size_t>(rng() % 40);
    sha256_blocks_portable(a, data.data(), blocks);
    if (!sha256_blocks_accelerated(b, data.data(), blocks)) break;
    ++compared;
    for (int i = 0; i < 8; ++i) ASSERT_EQ(a[i], b[i]) << "draw " << draw << " word " << i;
  }
  std::printf("accelerated SHA-256 compared on %d draws\n", compared);
  if (compared == 0) GTEST_SKIP() << "no SHA extensions on this CPU or build";
}

}  // namespace
}  // namespace splintcore
