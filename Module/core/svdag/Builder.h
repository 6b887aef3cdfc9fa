// Builds a Volume from a label volume streamed in slabs of 16 z-slices, or from the volumes of
// consecutive z-ranges built separately (addVolume).
//
// Each 16^3 cell of a slab is scanned independently (in parallel); the per-cell results are then
// merged in cell order into the deduplicated pools, so the output does not depend on the thread
// count. The pools are kept bit-packed at the widths their counts need so far (widened in place
// as they grow), so the builder's own memory stays near 1.5 times the output; the caller holds
// one slab at a time. The decoder (Volume -> dense labels) is in svdag/Decoder.h.
#pragma once

#include "svdag/Parallel.h"
#include "svdag/Volume.h"

#include <array>
#include <memory>
#include <string>
#include <vector>

namespace svdag
{

// One label's voxels in one 16^3 cell, as the masks of the cell's 64 leaves (leaf lx + 4 ly + 16 lz,
// bit x + 4 y + 16 z, Layout.h) and, for each mixed one (neither 0 nor all ones), the
// (symmetry << 1 | complement) of canonicalLeaf (LeafSymmetry.h) that its class's stored mask is
// read under.
struct CellOccupancy
{
  uint64_t value = 0; // label pattern
  uint64_t masks[64];
  uint8_t codes[64];
};

struct BuildOptions
{
  uint64_t background = 0;        // label pattern not stored (decodes where no block is)
  std::vector<uint64_t> excluded; // label patterns left out (decode as background)
};

class Builder
{
public:
  static constexpr int32_t SlabDepth = 16;

  // The z-slices [z0, z1) of piece `piece` of `pieces` (a parallel reader's share) of a volume
  // `depth` slices deep: its slabs shared out in order as evenly as possible, the first pieces
  // taking one more, so that every piece starts on a slab (cell) boundary and the pieces' cells
  // are the whole volume's. {0, 0} for a piece beyond the slab count. Throws
  // std::invalid_argument unless 0 <= piece < pieces and depth >= 0.
  static std::array<int32_t, 2> pieceZRange(int32_t depth, int piece, int pieces);

  // Throws std::invalid_argument when checkGeometry (Volume.h) fails.
  Builder(const Geometry& geometry, ScalarType type, const BuildOptions& options = {},
    ParallelFor parallel = sequentialFor);
  ~Builder();
  Builder(const Builder&) = delete;
  Builder& operator=(const Builder&) = delete;

  // Adds z-slices [z0, z0 + nz): slabs must come in order, z0 = 16 * n and
  // nz = min(16, dims[2] - z0). `data` holds dims[0] * dims[1] * nz values of the scalar type,
  // x fastest. Throws std::logic_error on a slab out of order.
  void addSlab(int32_t z0, int32_t nz, const void* data);
  // Appends a volume built elsewhere as the next part.dims[2] z-slices, starting at nextSlab():
  // the result is byte-identical to adding those slices' slabs, given that `part` was built from
  // them with the same background and excluded labels. So partial volumes built in parallel
  // (Dask workers, each over its own z-range) merge in z order, in a chain or a tree, into the
  // single-machine build. Only the part's dims, scalar type and background are used (its spacing,
  // origin and direction are not). Throws std::logic_error if nextSlab() is not a multiple of 16
  // or the part does not fit the slices left, std::invalid_argument if its x and y dims, scalar
  // type or background differ from this builder's, or it holds a label this builder excludes;
  // the builder is unchanged then. A part that is not a valid Volume (Volume::validate) throws
  // std::runtime_error and leaves the builder unusable.
  void addVolume(const Volume& part);
  // Next expected slab start, or dims[2] when every slab was added.
  int32_t nextSlab() const;

  // Adds a block given as its occupancy instead of voxels (how a .svdag 3.0 file is loaded):
  // the result is byte-identical to a build from the voxels those blocks hold, given every block
  // in the order a build writes them: by cell, and within a cell by label value. The occupancy
  // must be non-empty, inside the volume and disjoint from the cell's other blocks, and its codes
  // canonicalLeaf's: not checked here. The value is not checked against the background and
  // excluded labels either. Throws std::logic_error once slabs or volumes were added (and they
  // cannot be added after a block), or for a block out of order.
  void addBlock(uint32_t cell, const CellOccupancy& block);
  // Starts taking blocks (addBlock, which calls it) instead of slabs: finish() then takes the
  // cells no block was added to as empty, all of them for a volume without blocks. Throws
  // std::logic_error once slabs or volumes were added.
  void startBlocks();

  // Packs the pools with their final field widths, in the compact form (Compact.h) that a
  // volume in memory holds. Throws std::logic_error if slabs are missing (not for blocks added
  // by addBlock: cells without a block are empty), std::length_error if a pool outgrows the
  // 32-bit reference widths.
  Volume finish();
  // The same in the pooled form, as files store it.
  Volume finishPooled();

  // Compresses a whole volume held in memory (x fastest).
  static Volume build(const Geometry& geometry, ScalarType type, const void* data,
    const BuildOptions& options = {}, ParallelFor parallel = sequentialFor);

private:
  struct Impl;
  std::unique_ptr<Impl> impl;
};

} // namespace svdag
