// Per-label statistics computed from the compressed form, block by block, without a dense decode
// of the volume: voxel count, centroid and surface voxel count of every label of the table.
#pragma once

#include "svdag/Parallel.h"
#include "svdag/Volume.h"

#include <array>
#include <cstdint>
#include <vector>

namespace svdag
{

struct LabelStatistics
{
  uint64_t voxels = 0;
  // Sum of the voxel indices (i, j, k) of the label's voxels; exact integers, so the result does
  // not depend on how the work was split between threads.
  std::array<uint64_t, 3> indexSum{ { 0, 0, 0 } };
  // Voxels of the label with at least one of their 6 face neighbours outside the volume or of
  // another label (the background included).
  uint64_t surfaceVoxels = 0;
  // Mean voxel index (i, j, k) of the label's voxels (voxel centers; 0 for an empty label).
  std::array<double, 3> centroid() const;
};

// Bytes of working memory labelStatistics needs: 33 z-slices of 32-bit label indices (the cell
// layer being counted, the next one and the last slice of the previous one).
uint64_t labelStatisticsBytes(const Volume& volume);

// Statistics of every label, in the order of volume.labels. Works one 16-voxel layer of cells at
// a time (cells of a layer in parallel), so memory stays at labelStatisticsBytes, whatever the
// depth of the volume. Throws std::length_error when even that does not fit.
std::vector<LabelStatistics> labelStatistics(
  const Volume& volume, const ParallelFor& parallel = sequentialFor);

} // namespace svdag
