// How the VTK-free core runs loops in parallel: the caller injects a parallel-for (the VTK layer
// passes vtkSMPTools::For). Results never depend on how the range is split.
#pragma once

#include <cstdint>
#include <exception>
#include <functional>
#include <vector>

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

// Runs task(0) .. task(count - 1) through `parallel`, a range of one task each, then throws what
// the first of them in order threw, as a loop would (the others still run to their end).
template <typename Task>
void parallelTasks(const ParallelFor& parallel, uint64_t count, const Task& task)
{
  std::vector<std::exception_ptr> errors(static_cast<size_t>(count));
  parallel(0, count, 1, [&](uint64_t begin, uint64_t end) {
    for (uint64_t i = begin; i < end; ++i)
    {
      try
      {
        task(i);
      }
      catch (...)
      {
        errors[static_cast<size_t>(i)] = std::current_exception();
      }
    }
  });
  for (const std::exception_ptr& error : errors)
  {
    if (error)
    {
      std::rethrow_exception(error);
    }
  }
}
} // namespace svdag
