// A parallel-for for tests: std::threads that take uneven chunks of the range in any order, so
// that a result which depends on the split or the thread count shows up.
#pragma once

#include "svdag/Parallel.h"

#include <algorithm>
#include <atomic>
#include <cstdint>
#include <thread>
#include <vector>

inline svdag::ParallelFor threadedFor(unsigned threads)
{
  return [threads](uint64_t begin, uint64_t end, uint64_t, const svdag::RangeFunction& f) {
    std::atomic<uint64_t> next(begin);
    std::vector<std::thread> pool;
    for (unsigned t = 0; t < threads; ++t)
    {
      pool.emplace_back([&, t] {
        for (;;)
        {
          const uint64_t chunk = 1 + (t % 3);
          const uint64_t b = next.fetch_add(chunk);
          if (b >= end)
            return;
          f(b, std::min(end, b + chunk));
        }
      });
    }
    for (auto& th : pool)
      th.join();
  };
}
