// The compressed segmentation volume: blocks, the shared occupancy DAG and the label table.
// VTK-free core; vtkSegmentationSVDAG wraps it. The bit layout is defined in Layout.h.
#pragma once

#include "svdag/Layout.h"
#include "svdag/Parallel.h"

#include <array>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

namespace svdag
{
struct PooledGraph;

// Integer label types. Values are kept as 64-bit patterns (sign-extended for signed types).
enum class ScalarType : uint8_t
{
  Int8 = 0,
  UInt8,
  Int16,
  UInt16,
  Int32,
  UInt32,
  Int64,
  UInt64
};
constexpr int ScalarTypeCount = 8;
int scalarSize(ScalarType t);
bool scalarSigned(ScalarType t);
const char* scalarName(ScalarType t); // numpy-style: "int8", "uint64", ...
// Smallest and largest value of the type, as 64-bit patterns.
uint64_t scalarMin(ScalarType t);
uint64_t scalarMax(ScalarType t);
// Orders two 64-bit label patterns by the value they hold in type t.
bool scalarLess(ScalarType t, uint64_t a, uint64_t b);
// Reads element i of a buffer of type t as a 64-bit pattern.
uint64_t scalarLoad(ScalarType t, const void* data, size_t i);
void scalarStore(ScalarType t, void* data, size_t i, uint64_t value);

struct Geometry
{
  std::array<int32_t, 3> dims{ { 0, 0, 0 } };
  std::array<double, 3> spacing{ { 1, 1, 1 } };
  std::array<double, 3> origin{ { 0, 0, 0 } };
  std::array<double, 9> direction{ { 1, 0, 0, 0, 1, 0, 0, 0, 1 } }; // row-major, like vtkImageData
  uint64_t voxelCount() const { return uint64_t(dims[0]) * uint64_t(dims[1]) * uint64_t(dims[2]); }
  std::array<int32_t, 3> cellCounts() const;
  // Number of 16^3 cells, saturated at UINT64_MAX (absurd dimensions cannot overflow).
  uint64_t cellCount() const;
  // The geometry of z-slices [z0, z1) of this one (0 <= z0 <= z1 <= dims[2]): the same x and y,
  // the origin moved by z0 steps along the third axis, direction included. Throws
  // std::out_of_range for a range outside the volume.
  Geometry zRange(int32_t z0, int32_t z1) const;
  bool operator==(const Geometry& o) const;
};

// Empty if the geometry can be compressed, else why not (absurd dimensions, spacing, ...).
std::string checkGeometry(const Geometry& geometry);

struct LabelInfo
{
  uint64_t value = 0;                  // original label value (pattern, see ScalarType)
  uint64_t voxels = 0;                 // number of voxels with this label
  std::array<int32_t, 6> bounds{ {} }; // inclusive voxel bounds: xmin, xmax, ymin, ymax, zmin, zmax
  bool operator==(const LabelInfo& o) const;
};

// One decoded block record.
struct Block
{
  uint32_t cell = 0;                // linear cell index: cx + ncx * (cy + ncy * cz)
  std::array<uint8_t, 3> lo{ {} };  // inclusive cell-local voxel bounds of the label's voxels
  std::array<uint8_t, 3> hi{ {} };
  uint32_t label = 0;               // index into the label table
  uint32_t root = 0;                // reference (offset << 1 | complement) into the root stream
};

// Per-volume widths of the bit-packed fields (Layout.h).
struct FieldWidths
{
  uint32_t cellBits = 0;
  uint32_t labelBits = 0;
  uint32_t rootRefBits = 0; // block -> root node
  uint32_t midRefBits = 0;  // root -> mid node
  uint32_t leafRefBits = 0; // mid -> leaf
  uint32_t blockBits() const
  {
    return layout::blockRecordBits(cellBits, labelBits, rootRefBits);
  }
  bool operator==(const FieldWidths& o) const;
};

// Bytes held by each part.
struct MemoryUsage
{
  uint64_t blocks = 0;
  uint64_t roots = 0;
  uint64_t mids = 0;
  uint64_t leaves = 0;
  uint64_t labels = 0;
  uint64_t dag() const { return roots + mids + leaves; }
  // What a renderer holds besides its BVH: blocks + DAG (+ the label table).
  uint64_t total() const { return blocks + dag() + labels; }
};

// Which form of the DAG a volume's streams hold (Layout.h, Compact.h).
enum class DagForm : uint8_t
{
  Pooled, // builders and files; what validate() checks
  Compact // in memory: the data object, the traversal, the renderers
};

class Volume
{
public:
  Geometry geometry;
  ScalarType scalarType = ScalarType::UInt32;
  uint64_t background = 0;
  std::vector<LabelInfo> labels; // sorted by value
  FieldWidths widths;
  DagForm form = DagForm::Pooled;

  uint64_t blockCount = 0;
  std::vector<uint32_t> blocks; // bit-packed records, padded by one word
  uint64_t rootCount = 0;
  std::vector<uint32_t> roots;  // node stream, padded by one word
  uint64_t midCount = 0;
  std::vector<uint32_t> mids;   // node stream, padded by one word
  std::vector<uint64_t> leaves; // canonical 4^3 masks (bit 0 clear), one per symmetry class

  Block block(uint64_t i) const;
  // Pooled form: header (mixed | full << 8) and child reference of the node at a bit offset in
  // a stream.
  static uint32_t nodeHeader(const std::vector<uint32_t>& stream, uint64_t offset);
  static uint32_t nodeChildRef(const std::vector<uint32_t>& stream, uint64_t offset,
    uint32_t childRank, uint32_t refBits);
  // The occupancy a leaf reference names (Layout.h): its stored leaf under its symmetry, the
  // complement bit not applied. The reference must name an existing leaf.
  uint64_t leafMask(uint32_t leafRef) const;
  // Pooled form: bit length of the node at `offset` in a stream whose child references are
  // refBits wide.
  static uint64_t nodeBits(const std::vector<uint32_t>& stream, uint64_t offset, uint32_t refBits);
  // Either form: the first COMPACT_HEADER_BITS of the node at a bit offset (masks, and the
  // compact form's flags); the mid node of a root's mixed child of rank `rank` (its offset;
  // `inverted`, the root's polarity, becomes the mid's); the occupancy of a mid's mixed child as
  // the mid sees it (symmetry and the child's complement applied, the mid's polarity not).
  static uint32_t nodeHeaderAndFlags(const std::vector<uint32_t>& stream, uint64_t offset);
  uint64_t midOfRoot(uint64_t rootOffset, uint32_t header, uint32_t rank, bool& inverted) const;
  uint64_t leafOfMid(uint64_t midOffset, uint32_t header, uint32_t rank) const;

  // Occupancy of cell-local voxel (x, y, z) in 0..15 of block i.
  bool occupied(uint64_t blockIndex, uint32_t x, uint32_t y, uint32_t z) const;
  // Occupancy of the 16^3 cell of block i, x fastest (4096 entries).
  void occupancy(uint64_t blockIndex, uint8_t* out4096) const;
  // The same as the masks of the cell's 64 leaves: leaf lx + 4 ly + 16 lz, bit x + 4 y + 16 z.
  void leafMasks(uint64_t blockIndex, uint64_t* out64) const;
  // Label pattern at voxel (i, j, k); background where no block holds it.
  uint64_t labelAt(int32_t i, int32_t j, int32_t k) const;
  // Range [first, last) of the blocks in a cell (blocks are sorted by cell).
  std::pair<uint64_t, uint64_t> cellBlocks(uint32_t cell) const;
  // Index of a label value in the table, or -1.
  int64_t findLabel(uint64_t value) const;

  MemoryUsage memory() const;
  // A compact volume is checked in its pooled form (Compact.h).
  // Throws std::runtime_error naming the first inconsistency, so that no accessor, decoder or
  // traversal can read out of bounds or disagree with another: widths wide enough; the label
  // table valid for the type, sorted, unique, without the background, bounds inside the volume;
  // every node well formed and every reference (block -> root, root -> mid, mid -> leaf) at a
  // node start of its pool; blocks sorted by (cell, label), bounds ordered and inside the volume,
  // each occupancy non-empty and inside its bounds, the blocks of a cell disjoint; each label's
  // voxel count and bounds exactly what its blocks hold. Linear in the size of the volume:
  // occupancy is summarised once per distinct node, never expanded per block. `parallel` runs
  // the per-node checks; the outcome does not depend on it.
  void validate(const ParallelFor& parallel = sequentialFor) const;
  // Sets each block's bounds to the tight box of its occupancy and each label's voxel count and
  // bounds to what its blocks hold, then checks the rest as validate() does (a .svdag 4.0 file
  // stores neither: they are derived from the same once-per-node summaries that validate() uses).
  // Throws std::runtime_error as validate() does, and for a label no block holds; pooled form
  // only (std::logic_error otherwise). `graph` (PooledGraph.h, private to the core), where
  // given: where it holds nodes, they are the volume's as its decoder read them
  // (dagstreams::decode), and the checks read them instead of walking the node streams again;
  // otherwise it receives the nodes the walk read, for compaction. `alongside`, where given,
  // runs through `parallel` beside the last checks (the blocks and cells), once `graph` is
  // complete and the blocks hold their bounds; it may read the volume and the graph but change
  // neither. The checks' error comes first, then its own.
  void deriveBoundsAndValidate(const ParallelFor& parallel = sequentialFor,
    PooledGraph* graph = nullptr, const std::function<void()>& alongside = {});
  bool operator==(const Volume& o) const;
};

} // namespace svdag
