// Random-access decoding straight from the compressed form: a sub-box of the volume, an
// axis-aligned slice, an oblique plane resampled nearest, the mask of one label. Only the 16^3
// cells that intersect what is asked for are visited, and inside a cell only the octants of the
// occupancy tree that intersect it are expanded, so a slice costs about its own size, not the
// volume's (the dense decoder in Decoder.h expands every cell).
//
// Boxes are INCLUSIVE voxel index bounds {xmin, xmax, ymin, ymax, zmin, zmax}, the convention of
// LabelInfo::bounds and of VTK extents. Outputs are dense arrays of the volume's scalar type (the
// mask: uint8 0/1), x fastest, the caller owning the memory; check it with checkBoxMemory first.
#pragma once

#include "svdag/Parallel.h"
#include "svdag/Volume.h"

#include <array>
#include <cstdint>
#include <vector>

namespace svdag
{

using Box = std::array<int32_t, 6>; // inclusive: xmin, xmax, ymin, ymax, zmin, zmax

// The whole volume as a box.
Box volumeBox(const Volume& volume);
// Throws std::invalid_argument for an empty box (a min above its max) and std::out_of_range for
// a box not inside the volume; `what` starts the message ("decodeBox").
void checkBox(const Volume& volume, const Box& box, const char* what = "box");
// Voxels of a box (0 for an empty one) and bytes of a dense array of them, `valueBytes` each
// (saturated at UINT64_MAX).
uint64_t boxVoxels(const Box& box);
uint64_t boxBytes(const Box& box, uint64_t valueBytes);
// Throws std::length_error naming the bytes needed when `bytes` exceed the address space or the
// machine's physical memory (like checkDecodeMemory); `what` names the output.
void checkOutputMemory(uint64_t bytes, const std::string& what);
// The box of one voxel thick slice `index` along `axis` (0 = x, 1 = y, 2 = z). Throws
// std::invalid_argument for a bad axis, std::out_of_range for an index outside the volume.
Box sliceBox(const Volume& volume, int axis, int32_t index);

// Occupancy of block `blockIndex` restricted to the cell-local inclusive box lo..hi (0..15 each):
// writes 0 or 1 to out4096[x + 16 * (y + 16 * z)] for every (x, y, z) in the box and leaves the
// rest of the buffer untouched. Subtrees that miss the box are never read.
void occupancyInBox(const Volume& volume, uint64_t blockIndex, const std::array<uint32_t, 3>& lo,
  const std::array<uint32_t, 3>& hi, uint8_t* out4096);

// The label index of every voxel of cell `cell` (cell-local, out4096[x + 16 * (y + 16 * z)]),
// `empty` where no block is; `scratch4096` is occupancy scratch space of 4096 bytes.
void decodeCellLabels(const Volume& volume, uint64_t cell, uint32_t empty, uint32_t* out4096,
  uint8_t* scratch4096);
// The label indices (`empty` where no block is) of the z-slices of cell layer `cz` (voxel z in
// [16 cz, 16 cz + 16), clipped to the volume): dims[0] * dims[1] * slices values, x fastest, in
// `out` (resized). The cells of the layer decode in parallel. The streaming passes over the
// compressed form (label statistics) walk the volume one layer at a time with it.
void decodeLayerLabels(const Volume& volume, int32_t cz, uint32_t empty, std::vector<uint32_t>& out,
  const ParallelFor& parallel = sequentialFor);
// Bytes of `slices` full z-slices of such 32-bit label indices: what a pass holding that many
// slices at once needs (saturated at UINT64_MAX).
uint64_t layerSlicesBytes(const Volume& volume, uint64_t slices);

// Decodes the labels of `box` into `out` (boxVoxels(box) values of the volume's scalar type,
// x fastest). Voxels of no block hold the background.
void decodeBox(const Volume& volume, const Box& box, void* out,
  const ParallelFor& parallel = sequentialFor);
// Allocating form (bytes of the scalar type); std::length_error when it cannot fit.
std::vector<uint8_t> decodeBox(
  const Volume& volume, const Box& box, const ParallelFor& parallel = sequentialFor);

// 1 where the voxel of `box` holds label `labelIndex` (an index into volume.labels), else 0;
// boxVoxels(box) bytes, x fastest. Only the cells of that label's bounds within the box are
// visited, and of each cell only the label's block. Throws std::out_of_range for a bad index.
void decodeMask(const Volume& volume, uint32_t labelIndex, const Box& box, uint8_t* out,
  const ParallelFor& parallel = sequentialFor);

// An oblique (or any) plane sampled on a regular nu x nv grid, in continuous voxel index
// coordinates (voxel (i, j, k) is centered at (i, j, k)): sample (a, b) lies at
// origin + a * uStep + b * vStep, and takes the label of the nearest voxel, the one at
// floor(p + 0.5) per coordinate; samples outside the volume get the background.
struct PlaneSampling
{
  std::array<double, 3> origin{ { 0, 0, 0 } };
  std::array<double, 3> uStep{ { 1, 0, 0 } };
  std::array<double, 3> vStep{ { 0, 1, 0 } };
  int32_t nu = 0;
  int32_t nv = 0;
};
// Throws std::invalid_argument for non-finite values or a negative size, std::length_error for
// an output too large (checkOutputMemory) or a grid of more than 2^31 samples per row.
void checkPlaneSampling(const Volume& volume, const PlaneSampling& plane);
// Writes nu * nv values of the volume's scalar type into `out`, a fastest.
void resamplePlane(const Volume& volume, const PlaneSampling& plane, void* out,
  const ParallelFor& parallel = sequentialFor);

} // namespace svdag
