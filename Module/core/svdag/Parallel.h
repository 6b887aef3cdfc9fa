// How the VTK-free core runs loops in parallel: the caller injects a parallel-for (the VTK layer
// passes vtkSMPTools::For). Results never depend on how the range is split.
#pragma once

#include <cstdint>
#include <functional>

namespace svdag
{
using RangeFunction = std::function<void(uint64_t begin, uint64_t end)>;
using ParallelFor = std::function<void(uint64_t begin, uint64_t end, uint64_t grain, const RangeFunction&)>;

// Runs the whole range on the calling thread.
inline void sequentialFor(uint64_t begin, uint64_t end, uint64_t, const RangeFunction& f)
{
  if (begin < end)
  {
    f(begin, end);
  }
}
} // namespace svdag
