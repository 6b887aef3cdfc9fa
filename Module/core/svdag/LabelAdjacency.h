// Which labels touch: the pairs of labels with at least one pair of face-adjacent voxels
// (6-neighbourhood), computed from the compressed form one 16-voxel layer of cells at a time, so
// memory stays at a few z-slices whatever the depth of the volume (no dense decode).
#pragma once

#include "svdag/Parallel.h"
#include "svdag/Volume.h"

#include <array>
#include <cstdint>
#include <vector>

namespace svdag
{

using LabelPair = std::array<uint32_t, 2>;

// Bytes of working memory labelAdjacency needs besides its result: 17 z-slices of 32-bit label
// indices (the cell layer being scanned and the last slice of the previous one).
uint64_t labelAdjacencyBytes(const Volume& volume);

// Every pair {a, b} of label indices (into volume.labels) with a < b whose labels hold two voxels
// that share a face, sorted; the background is not a label and never appears. Throws
// std::length_error when the working memory does not fit. The result does not depend on how
// `parallel` splits the work.
std::vector<LabelPair> labelAdjacency(const Volume& volume, const ParallelFor& parallel = sequentialFor);

} // namespace svdag
