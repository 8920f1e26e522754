#include <atomic>

#include "splintcore/platform.h"
#include "support/test_util.h"

namespace splintcore {
namespace {

TEST(Executor, SerialRunsInOrder) {
  std::vector<uint32_t> order;
  auto f = [&](uint32_t i) { order.push_back(i); };
  parallel_for_each(&serial_executor(), 5, f);
  EXPECT_EQ(order, (std::vector<uint32_t>{0, 1, 2, 3, 4}));
  parallel_for_each(nullptr, 3, f);  // null executor means serial
  EXPECT_EQ(order.size(), 8u);
}

TEST(Executor, ThreadPoolRunsEveryIndexExactlyOnceAndResultsMatchAnyThreadCount) {
  std::vector<uint64_t> reference;
  for (unsigned threads : {1u, 2u, 3u, 8u}) {
    ThreadExecutor pool(threads);
    EXPECT_EQ(pool.executor().concurrency, threads);
    for (int round = 0; round < 20; ++round) {
      const uint32_t n = 1000 + static_cast<uint32_t>(round);
      std::vector<std::atomic<int>> hits(n);
      std::vector<uint64_t> out(n);
      auto f = [&](uint32_t i) {
        hits[i].fetch_add(1);
        out[i] = hash_mix(i);
      };
      parallel_for_each(&pool.executor(), n, f);
      for (uint32_t i = 0; i < n; ++i) ASSERT_EQ(hits[i].load(), 1) << i;
      if (round == 0) {
        if (reference.empty()) reference = out;
        EXPECT_EQ(out, reference);
      }
    }
  }
}

}  // namespace
}  // namespace splintcore
