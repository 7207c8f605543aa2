// KeyMap, the flat map the regularizer looks points and segments up in: the
// same contents as std::unordered_map through many growths, whatever the keys
// (edge keys share their high or low halves; 0 is a key like any other). And
// ConcurrentUnionFind, the disjoint sets its growth joins on all threads.
#include <catch2/catch.hpp>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <random>
#include <unordered_map>

#include "polyheal/mesh/hash.h"
#include "polyheal/mesh/union_find.h"

using namespace polyheal;

TEST_CASE("KeyMap: finds what was put, nothing else, through its growths", "[mesh]") {
  std::mt19937_64 random(11);
  KeyMap<std::uint32_t> map;
  std::unordered_map<std::uint64_t, std::uint32_t> reference;
  CHECK(map.find(0) == nullptr);  // empty: no slots yet
  auto key = [&](int kind) -> std::uint64_t {
    const std::uint64_t a = random() % 5000, b = random() % 5000;
    switch (kind) {
      case 0: return (a << 32) | b;  // an edge key: both halves small
      case 1: return a;              // high half zero
      case 2: return a << 32;        // low half zero
      default: return random() % (KeyMap<std::uint32_t>::kFree - 1);
    }
  };
  for (int round = 0; round < 6; ++round) {
    for (int i = 0; i < 20000; ++i) {
      const std::uint64_t k = round == 0 && i == 0 ? 0 : key(i % 4);
      const std::uint32_t v = static_cast<std::uint32_t>(random());
      map[k] += v;  // value-initialised when new
      reference[k] += v;
    }
    REQUIRE(map.size() == reference.size());
    for (const auto& [k, v] : reference) {
      const std::uint32_t* found = map.find(k);
      REQUIRE(found != nullptr);
      REQUIRE(*found == v);
    }
    for (int i = 0; i < 20000; ++i) {
      const std::uint64_t k = key(i % 4);
      const std::uint32_t* found = map.find(k);
      REQUIRE((found != nullptr) == (reference.count(k) == 1));
    }
  }
  CHECK(map.contains(0));
  CHECK(reference.size() > 50000);  // grown many times
}

TEST_CASE("ConcurrentUnionFind: unions from all threads give UnionFind's sets and least representatives",
          "[mesh]") {
  // Long chains and many merges of large sets at once: the cases where two
  // threads race to link the same roots.
  constexpr std::size_t n = 200000;
  std::mt19937 random(7);
  std::vector<std::pair<std::uint32_t, std::uint32_t>> pairs;
  for (std::size_t k = 0; k < 3 * n / 4; ++k)
    pairs.push_back({std::uint32_t(random() % n), std::uint32_t(random() % n)});
  for (std::uint32_t k = 1; k < n / 10; ++k) pairs.push_back({k - 1, k});  // a chain
  std::shuffle(pairs.begin(), pairs.end(), random);
  UnionFind serial(n);
  for (const auto& [a, b] : pairs) serial.unite(a, b);
  ConcurrentUnionFind joined(n);
  tbb::parallel_for(std::size_t(0), pairs.size(), [&](std::size_t k) { joined.unite(pairs[k].first, pairs[k].second); },
                    tbb::simple_partitioner());
  std::size_t differ = 0;
  for (std::uint32_t x = 0; x < n; ++x) differ += joined.find(x) != serial.find(x);
  CHECK(differ == 0);
}
