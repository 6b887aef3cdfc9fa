#include "vtkSVDAGParallel.h"

#include "vtkSMPTools.h"

svdag::ParallelFor vtkSVDAGParallelFor()
{
  return [](uint64_t begin, uint64_t end, uint64_t grain, const svdag::RangeFunction& f) {
    vtkSMPTools::For(static_cast<vtkIdType>(begin), static_cast<vtkIdType>(end),
      static_cast<vtkIdType>(grain),
      [&f](vtkIdType b, vtkIdType e) { f(static_cast<uint64_t>(b), static_cast<uint64_t>(e)); });
  };
}
