// The core's parallel-for, run by vtkSMPTools (so VTK's SMP backend and thread settings apply).
#ifndef vtkSVDAGParallel_h
#define vtkSVDAGParallel_h

#ifndef __VTK_WRAP__
#include "svdag/Parallel.h"
#include "vtkSVDAGCoreModule.h"

VTKSVDAGCORE_EXPORT svdag::ParallelFor vtkSVDAGParallelFor();
#endif

#endif
