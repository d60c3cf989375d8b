// lang::NodePool and PoolAllocator (lang/node_pool.h), which the syntax tree and the
// modifier maps allocate from: every live block distinct and aligned, freed blocks reused,
// threads allocating at once never handed the same block, and a map on the pool holding
// what a map on the global heap holds. A failure means two nodes sharing memory.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <map>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include "lang/node_pool.h"

namespace kanesim::lang {
namespace {

// Sizes no node type has, so that these pools are the tests' own.
using Pool48 = NodePool<48, 16>;
using Pool40 = NodePool<40, 8>;

// True when the blocks (each `size` bytes) do not overlap.
bool Disjoint(std::vector<void*> blocks, std::size_t size) {
  std::sort(blocks.begin(), blocks.end());
  for (std::size_t i = 1; i < blocks.size(); ++i)
    if (static_cast<char*>(blocks[i]) - static_cast<char*>(blocks[i - 1]) < static_cast<std::ptrdiff_t>(size))
      return false;
  return true;
}

TEST(NodePool, BlocksAreDistinctAlignedAndKeepTheirContents) {
  std::vector<void*> blocks;
  for (int i = 0; i < 10000; ++i) {  // several chunks
    void* p = Pool48::Allocate();
    ASSERT_EQ(reinterpret_cast<std::uintptr_t>(p) % 16, 0u);
    std::memset(p, i & 0xff, 48);
    blocks.push_back(p);
  }
  EXPECT_TRUE(Disjoint(blocks, 48));
  for (int i = 0; i < 10000; ++i) {
    const auto* b = static_cast<const unsigned char*>(blocks[static_cast<std::size_t>(i)]);
    ASSERT_TRUE(std::all_of(b, b + 48, [&](unsigned char c) { return c == (i & 0xff); })) << "block " << i;
  }
  for (void* p : blocks) Pool48::Free(p);
}

TEST(NodePool, FreedBlocksAreReused) {
  if (!kNodePoolEnabled) GTEST_SKIP() << "under AddressSanitizer nodes come from the global heap";
  void* a = Pool40::Allocate();
  void* b = Pool40::Allocate();
  Pool40::Free(a);
  EXPECT_EQ(Pool40::Allocate(), a);  // the free list first
  Pool40::Free(a);
  Pool40::Free(b);
}

TEST(NodePool, ThreadsAllocatingAtOnceGetDistinctBlocks) {
  constexpr int kThreads = 4, kEach = 20000;
  std::vector<std::vector<void*>> got(kThreads);
  std::vector<std::thread> threads;
  for (int t = 0; t < kThreads; ++t)
    threads.emplace_back([t, &got] {
      std::mt19937 rng(static_cast<unsigned>(t) + 1);  // fixed seeds
      std::vector<void*>& mine = got[static_cast<std::size_t>(t)];
      for (int i = 0; i < kEach; ++i) {
        if (!mine.empty() && rng() % 4 == 0) {  // free some as we go: the free list is shared too
          Pool48::Free(mine.back());
          mine.pop_back();
        }
        void* p = Pool48::Allocate();
        std::memset(p, t + 1, 48);
        mine.push_back(p);
      }
    });
  for (auto& th : threads) th.join();
  std::vector<void*> all;
  for (int t = 0; t < kThreads; ++t)
    for (void* p : got[static_cast<std::size_t>(t)]) {
      const auto* b = static_cast<const unsigned char*>(p);
      ASSERT_TRUE(std::all_of(b, b + 48, [&](unsigned char c) { return c == t + 1; })) << "thread " << t;
      all.push_back(p);
    }
  EXPECT_TRUE(Disjoint(all, 48));
  for (void* p : all) Pool48::Free(p);
}

TEST(PoolAllocator, MapHoldsWhatAMapOnTheHeapHolds) {
  std::map<std::string, int, std::less<>, PoolAllocator<std::pair<const std::string, int>>> pooled;
  std::map<std::string, int> reference;
  std::mt19937 rng(7);
  for (int i = 0; i < 5000; ++i) {
    const std::string key = "k" + std::to_string(rng() % 1000);
    if (rng() % 3 == 0) {
      pooled.erase(key);
      reference.erase(key);
    } else {
      pooled[key] = i;
      reference[key] = i;
    }
  }
  auto moved = std::move(pooled);  // stateless: moving keeps the nodes
  ASSERT_EQ(moved.size(), reference.size());
  EXPECT_TRUE(std::equal(moved.begin(), moved.end(), reference.begin(), reference.end()));
}

}  // namespace
}  // namespace kanesim::lang
