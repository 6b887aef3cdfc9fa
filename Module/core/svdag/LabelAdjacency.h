// Which labels touch: the pairs of labels with at least one pair of face-adjacent voxels
// (6-neighbourhood), computed from the compressed form one layer of cells at a time without a
// dense decode: each block's occupancy as 256 rows of 16 bits (from its leaves), the blocks of a
// cell tested pairwise and against those across the cell's -x, -y and -z faces, where their
// bounds allow a contact. The work grows with the blocks, not the voxels (fib_ts2's 15.6 million
// voxels: 13,330 blocks), and memory with two layers' blocks.
#pragma once

#include "svdag/Parallel.h"
#include "svdag/Volume.h"

#include <array>
#include <cstdint>
#include <vector>

namespace svdag
{

using LabelPair = std::array<uint32_t, 2>;

// Bytes of working memory labelAdjacency needs besides its result: the block records and rows
// (512 bytes a block) of the two adjacent cell layers with the most blocks.
uint64_t labelAdjacencyBytes(const Volume& volume);

// Every pair {a, b} of label indices (into volume.labels) with a < b whose labels hold two voxels
// that share a face, sorted; the background is not a label and never appears. Throws
// std::length_error when the working memory does not fit. The result does not depend on how
// `parallel` splits the work.
std::vector<LabelPair> labelAdjacency(const Volume& volume, const ParallelFor& parallel = sequentialFor);

} // namespace svdag
