// polyheal — the one "over all indices, in parallel or not" loop (internal to inspect/).
#pragma once

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <cstddef>

namespace polyheal::detail {

/// Calls f(i) for every i in [0, n): across TBB's threads when `parallel`
/// (so f must be safe to call concurrently), otherwise in order.
template <class F>
void for_each_index(std::size_t n, bool parallel, F f) {
  if (!parallel) {
    for (std::size_t i = 0; i < n; ++i) f(i);
    return;
  }
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 4096), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t i = r.begin(); i != r.end(); ++i) f(i);
  });
}

}  // namespace polyheal::detail
