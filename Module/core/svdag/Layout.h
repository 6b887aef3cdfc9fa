/* The one definition of the compressed SVDAG layout, shared by C++ (with GLM) and GLSL.
 *
 * Written in the common subset of both languages: constants and pure functions on 32-bit
 * integers. Storage access differs per language, so stream reads take a macro
 * SVDAG_WORD(stream, index) that the including file defines.
 *
 * A volume is cut into an axis-aligned grid of 16^3 cells. Each (cell, label) pair present
 * becomes one block. Occupancy of a block is a 3-level tree, every level deduplicated in a pool
 * shared by all blocks and labels:
 *
 *   root  (16^3)  node in the ROOT stream   -> 8 children, each an 8^3 node or empty/full
 *   mid   (8^3)   node in the MID stream    -> 8 children, each a 4^3 leaf or empty/full
 *   leaf  (4^3)   64-bit occupancy mask in the LEAF array, bit = x + 4*y + 16*z
 *
 * Node encoding (bit stream, LSB first):  [mixed:8][full:8][ref x popcount(mixed)]
 *   child o = ox + 2*oy + 4*oz (x fastest). A child is "mixed" (stored, has a reference),
 *   "full" (solid, no reference) or empty (neither bit). References of mixed children follow in
 *   increasing child order, each CHILD_REF_BITS wide (per level, chosen from the pool size).
 *
 * References carry a complement bit (bit 0): ref = (target << 1) | complement. A complemented
 * reference means the child's occupancy is the inverse of the stored node. Every stored leaf is
 * canonical (its voxel (0,0,0) empty) and so is every stored node (its first child empty, or
 * mixed through a reference without the complement bit), so a shape and its inverse are stored
 * once.
 * For roots and mids, target = bit offset of the node in its stream.
 *
 * Leaf references also name one of the 48 symmetries of the cube (axis permutations with
 * mirrors): ref = (index << 7) | (symmetry << 1) | complement. Leaves equal up to a symmetry and
 * complement are stored once (the builder keeps the smallest mask of the class), and the child's
 * voxel (x, y, z) is the stored leaf's voxel at leafSymmetryBit(symmetry, x, y, z).
 *
 * That is the POOLED form: every node stored once in its level's pool and reached through a
 * reference. Builders and files use it (files store it; readers validate it). A volume in memory
 * (what the data object holds, the traversal reads and the GPU renders) is in the COMPACT form,
 * in which a child referenced once in the whole volume costs no reference (most leaves and nearly
 * all mids are referenced once; svdag::compacted and svdag::pooled convert):
 *
 *   mid   [mixed:8][full:8][inline:k][leaf refs: (k - n) x CHILD_REF_BITS][masks: n x 64]
 *   root  [mixed:8][full:8][chained:k][base: CHILD_REF_BITS - 1, iff n > 0][mid refs: (k - n) x CHILD_REF_BITS]
 *
 * with k = popcount(mixed) flag bits, one per mixed child in child order, n of them set. A mid's
 * inline child is its 64-bit occupancy mask, stored after the references in child order, as the
 * node sees it (no symmetry, no complement: the node's own complement still applies). A root's
 * chained children are mid nodes that lie one after another in the MID stream from bit offset
 * `base`, in child order, each as the root sees it (no complement); a mid node's length follows
 * from its first 16 + k bits (compactMidBits). References to shared leaves and mids are as above.
 * The flags start at bit 16, so one read of COMPACT_HEADER_BITS holds a node's masks and flags.
 *
 * Blocks are fixed-width bit-packed records, sorted by cell index (and, as the builder writes
 * them, by label within a cell; readers accept any order within a cell):
 *   [cell:CELL_BITS][minX:4][minY:4][minZ:4][maxX:4][maxY:4][maxZ:4][label:LABEL_BITS][root:ROOT_REF_BITS]
 * with the tight voxel bounds (inclusive, cell-local) and the dense label index. A block's root
 * covers the whole cell; voxels outside the volume are empty.
 *
 * All field widths are in [0, 32]. Streams are arrays of 32-bit words padded by one zero word.
 */
#ifndef SVDAG_LAYOUT_H
#define SVDAG_LAYOUT_H

#ifdef __cplusplus
#include <cstdint>
namespace svdag
{
namespace layout
{
typedef uint32_t uint;
// Arithmetic, not __builtin_popcount: built for any x86-64 (no POPCNT), that is a libgcc call.
inline uint bitCount(uint v)
{
  v = v - ((v >> 1) & 0x55555555u);
  v = (v & 0x33333333u) + ((v >> 2) & 0x33333333u);
  return (((v + (v >> 4)) & 0x0F0F0F0Fu) * 0x01010101u) >> 24;
}
#define SVDAG_CONST constexpr uint
#define SVDAG_FN inline
#define SVDAG_NS svdag::layout::
#define SVDAG_OFFSET_T uint64_t
#else
#define SVDAG_CONST const uint
#define SVDAG_FN
#define SVDAG_NS
#define SVDAG_OFFSET_T uint
#endif

SVDAG_CONST CELL_SIZE = 16u;       // voxels per block edge (root level)
SVDAG_CONST MID_SIZE = 8u;         // voxels per mid node edge
SVDAG_CONST LEAF_SIZE = 4u;        // voxels per leaf edge
SVDAG_CONST NODE_MASK_BITS = 8u;   // one bit per octant
SVDAG_CONST NODE_HEADER_BITS = 16u; // mixed mask + full mask
SVDAG_CONST BOUND_BITS = 4u;       // one cell-local coordinate 0..15
SVDAG_CONST BLOCK_BOUNDS_BITS = 24u;

/* Bit offsets of the block record fields, given the per-volume widths. */
SVDAG_FN uint blockBoundsOffset(uint cellBits) { return cellBits; }
SVDAG_FN uint blockLabelOffset(uint cellBits) { return cellBits + BLOCK_BOUNDS_BITS; }
SVDAG_FN uint blockRootOffset(uint cellBits, uint labelBits)
{
  return cellBits + BLOCK_BOUNDS_BITS + labelBits;
}
SVDAG_FN uint blockRecordBits(uint cellBits, uint labelBits, uint rootRefBits)
{
  return cellBits + BLOCK_BOUNDS_BITS + labelBits + rootRefBits;
}

/* Octant of a cell-local (root) or node-local coordinate at a level of edge `size`. */
SVDAG_FN uint octant(uint x, uint y, uint z, uint halfSize)
{
  return (x >= halfSize ? 1u : 0u) + (y >= halfSize ? 2u : 0u) + (z >= halfSize ? 4u : 0u);
}
/* Bit of voxel (x, y, z) in a 4^3 leaf mask, 0 <= x, y, z < 4. */
SVDAG_FN uint leafBit(uint x, uint y, uint z) { return x + 4u * y + 16u * z; }

SVDAG_FN uint nodeMixedMask(uint header) { return header & 0xFFu; }
SVDAG_FN uint nodeFullMask(uint header) { return (header >> 8u) & 0xFFu; }
/* Position of child o's reference among the node's references. */
SVDAG_FN uint childRank(uint mixedMask, uint o) { return uint(bitCount(mixedMask & ((1u << o) - 1u))); }

SVDAG_FN uint refTarget(uint ref) { return ref >> 1u; }
SVDAG_FN bool refComplement(uint ref) { return (ref & 1u) != 0u; }

SVDAG_CONST LEAF_SYMMETRY_BITS = 6u;
SVDAG_CONST LEAF_SYMMETRY_COUNT = 48u;
SVDAG_FN uint leafRefIndex(uint ref) { return ref >> (LEAF_SYMMETRY_BITS + 1u); }
SVDAG_FN uint leafRefSymmetry(uint ref) { return (ref >> 1u) & 63u; }
SVDAG_FN uint leafRef(uint index, uint symmetry, uint complement)
{
  return (index << (LEAF_SYMMETRY_BITS + 1u)) | (symmetry << 1u) | complement;
}
/* Coordinate j (0..2) of symmetry s applied to a voxel of a 4^3 leaf: the (s / 8)-th of the
 * permutations 012, 021, 102, 120, 201, 210 picks the axis, bit j of s mirrors it. */
SVDAG_FN uint leafSymmetryCoordinate(uint s, uint j, uint x, uint y, uint z)
{
  uint p = s >> 3u;
  uint first = p >> 1u;
  uint low = first == 0u ? 1u : 0u;
  uint high = first == 2u ? 1u : 2u;
  bool odd = (p & 1u) != 0u;
  uint axis = j == 0u ? first : (j == 1u ? (odd ? high : low) : (odd ? low : high));
  uint v = axis == 0u ? x : (axis == 1u ? y : z);
  return ((s >> j) & 1u) != 0u ? LEAF_SIZE - 1u - v : v;
}
/* Bit of the stored leaf mask that holds voxel (x, y, z) of a child reached under symmetry s. */
SVDAG_FN uint leafSymmetryBit(uint s, uint x, uint y, uint z)
{
  return leafBit(leafSymmetryCoordinate(s, 0u, x, y, z), leafSymmetryCoordinate(s, 1u, x, y, z),
    leafSymmetryCoordinate(s, 2u, x, y, z));
}

SVDAG_FN uint lowMask(uint width) { return width >= 32u ? 0xFFFFFFFFu : ((1u << width) - 1u); }

/* The compact form (above). `header` is a node's first COMPACT_HEADER_BITS bits; `rank` a mixed
 * child's rank (childRank). Offsets are in bits from the node's start. */
SVDAG_CONST COMPACT_HEADER_BITS = 24u; // masks and up to 8 flags
/* The k flag bits: bit r set = the mixed child of rank r is inline (mids) or chained (roots). */
SVDAG_FN uint compactFlags(uint header)
{
  return (header >> NODE_HEADER_BITS) & lowMask(bitCount(nodeMixedMask(header)));
}
SVDAG_FN bool compactChildFlagged(uint header, uint rank) { return ((compactFlags(header) >> rank) & 1u) != 0u; }
/* Flagged children before rank `rank`. */
SVDAG_FN uint compactFlaggedBefore(uint header, uint rank)
{
  return bitCount(compactFlags(header) & lowMask(rank));
}
SVDAG_FN uint compactPrefixBits(uint header) { return NODE_HEADER_BITS + bitCount(nodeMixedMask(header)); }
SVDAG_FN uint compactReferencedCount(uint header)
{
  return bitCount(nodeMixedMask(header)) - bitCount(compactFlags(header));
}
/* Mid node: the reference of an unflagged child, the mask of an inline one, the node's length. */
SVDAG_FN uint compactMidRefOffset(uint header, uint rank, uint leafRefBits)
{
  return compactPrefixBits(header) + (rank - compactFlaggedBefore(header, rank)) * leafRefBits;
}
SVDAG_FN uint compactMidMaskOffset(uint header, uint rank, uint leafRefBits)
{
  return compactPrefixBits(header) + compactReferencedCount(header) * leafRefBits +
    compactFlaggedBefore(header, rank) * 64u;
}
SVDAG_FN uint compactMidBits(uint header, uint leafRefBits)
{
  return compactPrefixBits(header) + compactReferencedCount(header) * leafRefBits +
    bitCount(compactFlags(header)) * 64u;
}
/* Root node: the base of its chained mids (when it has any), the reference of an unflagged
 * child, the node's length. */
SVDAG_FN uint compactRootBaseBits(uint header, uint midRefBits)
{
  return compactFlags(header) != 0u ? midRefBits - 1u : 0u;
}
SVDAG_FN uint compactRootRefOffset(uint header, uint rank, uint midRefBits)
{
  return compactPrefixBits(header) + compactRootBaseBits(header, midRefBits) +
    (rank - compactFlaggedBefore(header, rank)) * midRefBits;
}
SVDAG_FN uint compactRootBits(uint header, uint midRefBits)
{
  return compactPrefixBits(header) + compactRootBaseBits(header, midRefBits) +
    compactReferencedCount(header) * midRefBits;
}

#ifdef __cplusplus
} // namespace layout
} // namespace svdag
#endif

/* Reads `width` (0..32) bits at bit `offset` of a word stream into `result`. The stream must be
 * padded with one zero word, so that a field ending in the last data word needs no bounds check.
 * SVDAG_WORD(stream, i) must be defined by the including file. */
#define SVDAG_READ_BITS(result, stream, offset, width)                                             \
  {                                                                                                \
    SVDAG_OFFSET_T svdagWord_ = (offset) >> 5u;                                                    \
    SVDAG_NS uint svdagShift_ = SVDAG_NS uint((offset) & 31u);                                     \
    SVDAG_NS uint svdagValue_ = SVDAG_WORD(stream, svdagWord_) >> svdagShift_;                     \
    if (svdagShift_ != 0u && svdagShift_ + (width) > 32u)                                          \
      svdagValue_ |= SVDAG_WORD(stream, svdagWord_ + 1u) << (32u - svdagShift_);                   \
    result = svdagValue_ & SVDAG_NS lowMask(width);                                                \
  }

#endif
