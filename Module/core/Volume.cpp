#include "svdag/Volume.h"
#include "svdag/Compact.h"
#include "svdag/LeafSymmetry.h"
#include "svdag/Traversal.h"

#include "Bits.h"
#include "PooledGraph.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstring>
#include <limits>
#include <memory>
#include <stdexcept>
#include <string>

namespace svdag
{
namespace
{
using bits::readBits;

uint64_t signExtend(uint64_t v, int bytes)
{
  const int shift = 64 - 8 * bytes;
  return uint64_t(int64_t(v << shift) >> shift);
}
} // namespace

int scalarSize(ScalarType t)
{
  return 1 << (int(t) / 2);
}

bool scalarSigned(ScalarType t)
{
  return int(t) % 2 == 0;
}

const char* scalarName(ScalarType t)
{
  static const char* names[ScalarTypeCount] = { "int8", "uint8", "int16", "uint16", "int32",
    "uint32", "int64", "uint64" };
  return names[int(t)];
}

uint64_t scalarMin(ScalarType t)
{
  return scalarSigned(t) ? signExtend(uint64_t(1) << (8 * scalarSize(t) - 1), scalarSize(t)) : 0;
}

uint64_t scalarMax(ScalarType t)
{
  const int bits = 8 * scalarSize(t) - (scalarSigned(t) ? 1 : 0);
  return bits == 64 ? ~uint64_t(0) : (uint64_t(1) << bits) - 1;
}

bool scalarLess(ScalarType t, uint64_t a, uint64_t b)
{
  return scalarSigned(t) ? int64_t(a) < int64_t(b) : a < b;
}

uint64_t scalarLoad(ScalarType t, const void* data, size_t i)
{
  switch (t)
  {
    case ScalarType::Int8: return uint64_t(int64_t(static_cast<const int8_t*>(data)[i]));
    case ScalarType::UInt8: return static_cast<const uint8_t*>(data)[i];
    case ScalarType::Int16: return uint64_t(int64_t(static_cast<const int16_t*>(data)[i]));
    case ScalarType::UInt16: return static_cast<const uint16_t*>(data)[i];
    case ScalarType::Int32: return uint64_t(int64_t(static_cast<const int32_t*>(data)[i]));
    case ScalarType::UInt32: return static_cast<const uint32_t*>(data)[i];
    case ScalarType::Int64: return uint64_t(static_cast<const int64_t*>(data)[i]);
    case ScalarType::UInt64: return static_cast<const uint64_t*>(data)[i];
  }
  return 0;
}

void scalarStore(ScalarType t, void* data, size_t i, uint64_t v)
{
  switch (t)
  {
    case ScalarType::Int8: static_cast<int8_t*>(data)[i] = int8_t(v); break;
    case ScalarType::UInt8: static_cast<uint8_t*>(data)[i] = uint8_t(v); break;
    case ScalarType::Int16: static_cast<int16_t*>(data)[i] = int16_t(v); break;
    case ScalarType::UInt16: static_cast<uint16_t*>(data)[i] = uint16_t(v); break;
    case ScalarType::Int32: static_cast<int32_t*>(data)[i] = int32_t(v); break;
    case ScalarType::UInt32: static_cast<uint32_t*>(data)[i] = uint32_t(v); break;
    case ScalarType::Int64: static_cast<int64_t*>(data)[i] = int64_t(v); break;
    case ScalarType::UInt64: static_cast<uint64_t*>(data)[i] = v; break;
  }
}

std::array<int32_t, 3> Geometry::cellCounts() const
{
  std::array<int32_t, 3> n;
  for (int a = 0; a < 3; ++a)
  {
    n[a] = int32_t((int64_t(dims[a]) + layout::CELL_SIZE - 1) / layout::CELL_SIZE);
  }
  return n;
}

Geometry Geometry::zRange(int32_t z0, int32_t z1) const
{
  if (z0 < 0 || z1 < z0 || z1 > dims[2])
    throw std::out_of_range("z-range [" + std::to_string(z0) + ", " + std::to_string(z1) +
      ") is outside the volume's " + std::to_string(dims[2]) + " slices");
  Geometry part = *this;
  part.dims[2] = z1 - z0;
  for (int a = 0; a < 3; ++a)
    part.origin[a] += direction[3 * a + 2] * spacing[2] * double(z0);
  return part;
}

uint64_t Geometry::cellCount() const
{
  const auto n = cellCounts();
  uint64_t cells = 0;
  if (__builtin_mul_overflow(uint64_t(n[0]), uint64_t(n[1]), &cells) ||
    __builtin_mul_overflow(cells, uint64_t(n[2]), &cells))
  {
    return UINT64_MAX;
  }
  return cells;
}

std::string checkGeometry(const Geometry& g)
{
  for (int a = 0; a < 3; ++a)
  {
    if (g.dims[a] < 1)
      return "dimensions must be at least 1 voxel along each axis (got " +
        std::to_string(g.dims[0]) + " x " + std::to_string(g.dims[1]) + " x " +
        std::to_string(g.dims[2]) + ")";
    if (!std::isfinite(g.spacing[a]) || g.spacing[a] <= 0)
      return "spacing must be finite and positive";
    if (!std::isfinite(g.origin[a]))
      return "origin must be finite";
  }
  for (double d : g.direction)
  {
    if (!std::isfinite(d))
      return "direction matrix must be finite";
  }
  if (g.cellCount() > (uint64_t(1) << 32))
    return "volume too large: more than 2^32 cells of 16^3 voxels";
  return "";
}

bool Geometry::operator==(const Geometry& o) const
{
  return dims == o.dims && spacing == o.spacing && origin == o.origin && direction == o.direction;
}

bool LabelInfo::operator==(const LabelInfo& o) const
{
  return value == o.value && voxels == o.voxels && bounds == o.bounds;
}

bool FieldWidths::operator==(const FieldWidths& o) const
{
  return cellBits == o.cellBits && labelBits == o.labelBits && rootRefBits == o.rootRefBits &&
    midRefBits == o.midRefBits && leafRefBits == o.leafRefBits;
}

Block Volume::block(uint64_t i) const
{
  const uint64_t base = i * widths.blockBits();
  Block b;
  b.cell = readBits(blocks, base, widths.cellBits);
  const uint32_t box = readBits(blocks, base + layout::blockBoundsOffset(widths.cellBits), 24);
  for (int a = 0; a < 3; ++a)
  {
    b.lo[a] = uint8_t((box >> (4 * a)) & 15u);
    b.hi[a] = uint8_t((box >> (12 + 4 * a)) & 15u);
  }
  b.label = readBits(blocks, base + layout::blockLabelOffset(widths.cellBits), widths.labelBits);
  b.root = readBits(
    blocks, base + layout::blockRootOffset(widths.cellBits, widths.labelBits), widths.rootRefBits);
  return b;
}

uint32_t Volume::nodeHeader(const std::vector<uint32_t>& stream, uint64_t offset)
{
  return readBits(stream, offset, layout::NODE_HEADER_BITS);
}

uint32_t Volume::nodeChildRef(
  const std::vector<uint32_t>& stream, uint64_t offset, uint32_t rank, uint32_t refBits)
{
  return readBits(stream, offset + layout::NODE_HEADER_BITS + uint64_t(rank) * refBits, refBits);
}

uint64_t Volume::nodeBits(const std::vector<uint32_t>& stream, uint64_t offset, uint32_t refBits)
{
  const uint32_t mixed = layout::nodeMixedMask(nodeHeader(stream, offset));
  return layout::NODE_HEADER_BITS + uint64_t(layout::bitCount(mixed)) * refBits;
}

uint32_t Volume::nodeHeaderAndFlags(const std::vector<uint32_t>& stream, uint64_t offset)
{
  return readBits(stream, offset, layout::COMPACT_HEADER_BITS);
}

uint64_t Volume::midOfRoot(uint64_t rootOffset, uint32_t header, uint32_t rank, bool& inverted) const
{
  if (form == DagForm::Compact)
  {
    const traversal::Streams streams{ roots.data(), mids.data(), leaves.data() };
    return traversal::svdagRootChildMid(
      streams, rootOffset, header, rank, widths.midRefBits, widths.leafRefBits, inverted);
  }
  const uint32_t ref = nodeChildRef(roots, rootOffset, rank, widths.midRefBits);
  inverted = inverted != layout::refComplement(ref);
  return layout::refTarget(ref);
}

uint64_t Volume::leafOfMid(uint64_t midOffset, uint32_t header, uint32_t rank) const
{
  if (form == DagForm::Compact)
  {
    const traversal::Streams streams{ roots.data(), mids.data(), leaves.data() };
    uint32_t symmetry = 0;
    const glm::uvec2 m =
      traversal::svdagMidChildLeaf(streams, midOffset, header, rank, widths.leafRefBits, symmetry);
    return leafUnderSymmetry(symmetry, uint64_t(m.x) | (uint64_t(m.y) << 32));
  }
  const uint32_t ref = nodeChildRef(mids, midOffset, rank, widths.leafRefBits);
  const uint64_t mask = leafMask(ref);
  return layout::refComplement(ref) ? ~mask : mask;
}

bool Volume::occupied(uint64_t blockIndex, uint32_t x, uint32_t y, uint32_t z) const
{
  const uint32_t rootRef = block(blockIndex).root;
  bool inverted = layout::refComplement(rootRef);
  const uint64_t rootOffset = layout::refTarget(rootRef);
  const uint32_t rootHeader = nodeHeaderAndFlags(roots, rootOffset);
  const uint32_t o8 = layout::octant(x, y, z, layout::MID_SIZE);
  const uint32_t rootMixed = layout::nodeMixedMask(rootHeader);
  if (!(rootMixed & (1u << o8)))
    return ((layout::nodeFullMask(rootHeader) >> o8) & 1u) != inverted;
  const uint64_t midOffset = midOfRoot(rootOffset, rootHeader, layout::childRank(rootMixed, o8), inverted);
  const uint32_t midHeader = nodeHeaderAndFlags(mids, midOffset);
  x %= layout::MID_SIZE;
  y %= layout::MID_SIZE;
  z %= layout::MID_SIZE;
  const uint32_t o4 = layout::octant(x, y, z, layout::LEAF_SIZE);
  const uint32_t midMixed = layout::nodeMixedMask(midHeader);
  if (!(midMixed & (1u << o4)))
    return ((layout::nodeFullMask(midHeader) >> o4) & 1u) != inverted;
  const uint64_t mask = leafOfMid(midOffset, midHeader, layout::childRank(midMixed, o4));
  const uint32_t bit = layout::leafBit(x % layout::LEAF_SIZE, y % layout::LEAF_SIZE, z % layout::LEAF_SIZE);
  return ((mask >> bit) & 1u) != inverted;
}

uint64_t Volume::leafMask(uint32_t leafRef) const
{
  return leafUnderSymmetry(layout::leafRefSymmetry(leafRef), leaves[layout::leafRefIndex(leafRef)]);
}

void Volume::leafMasks(uint64_t blockIndex, uint64_t* out) const
{
  // Level by level; a solid or empty child sets its whole octant at once.
  const uint32_t rootRef = block(blockIndex).root;
  const bool rootInv = layout::refComplement(rootRef);
  const uint64_t rootOff = layout::refTarget(rootRef);
  const uint32_t rootHeader = nodeHeaderAndFlags(roots, rootOff);
  const uint32_t rootMixed = layout::nodeMixedMask(rootHeader);
  for (uint32_t o = 0; o < 8; ++o)
  {
    const uint32_t lx0 = (o & 1) * 2, ly0 = ((o >> 1) & 1) * 2, lz0 = ((o >> 2) & 1) * 2;
    uint32_t midHeader = 0, midMixed = 0;
    uint64_t midOff = 0;
    bool midInv = rootInv;
    if (rootMixed & (1u << o))
    {
      midOff = midOfRoot(rootOff, rootHeader, layout::childRank(rootMixed, o), midInv);
      midHeader = nodeHeaderAndFlags(mids, midOff);
      midMixed = layout::nodeMixedMask(midHeader);
    }
    else // the octant is one solid or empty child: every leaf of it alike
      midHeader = ((layout::nodeFullMask(rootHeader) >> o) & 1u) ? 0xFF00u : 0u;
    for (uint32_t c = 0; c < 8; ++c)
    {
      const uint32_t leaf =
        (lx0 + (c & 1)) + 4 * (ly0 + ((c >> 1) & 1)) + 16 * (lz0 + ((c >> 2) & 1));
      uint64_t mask;
      if (midMixed & (1u << c))
        mask = leafOfMid(midOff, midHeader, layout::childRank(midMixed, c));
      else
        mask = ((layout::nodeFullMask(midHeader) >> c) & 1u) ? ~uint64_t(0) : 0;
      out[leaf] = midInv ? ~mask : mask;
    }
  }
}

void Volume::occupancy(uint64_t blockIndex, uint8_t* out) const
{
  uint64_t masks[64];
  leafMasks(blockIndex, masks);
  std::memset(out, 0, layout::CELL_SIZE * layout::CELL_SIZE * layout::CELL_SIZE);
  for (uint32_t l = 0; l < 64; ++l)
  {
    const uint64_t mask = masks[l];
    if (!mask)
      continue;
    uint8_t* corner = out + 4 * (l & 3) + 16 * (4 * ((l >> 2) & 3) + 16 * 4 * (l >> 4));
    for (uint32_t row = 0; row < 16; ++row) // 4 voxels in x for each (y, z) of the leaf
    {
      const uint32_t bits = uint32_t(mask >> (4 * row)) & 0xFu;
      uint8_t* at = corner + 16 * ((row & 3) + 16 * (row >> 2));
      if (bits == 0xFu)
        std::memset(at, 1, 4);
      else
        for (uint32_t x = 0; x < 4; ++x)
          at[x] = uint8_t((bits >> x) & 1u);
    }
  }
}

std::pair<uint64_t, uint64_t> Volume::cellBlocks(uint32_t cell) const
{
  auto cellOf = [this](uint64_t i) {
    return readBits(blocks, i * widths.blockBits(), widths.cellBits);
  };
  uint64_t lo = 0, hi = blockCount;
  while (lo < hi) // first block with cellOf >= cell
  {
    const uint64_t mid = lo + (hi - lo) / 2;
    if (cellOf(mid) < cell)
      lo = mid + 1;
    else
      hi = mid;
  }
  uint64_t end = lo;
  while (end < blockCount && cellOf(end) == cell)
    ++end;
  return { lo, end };
}

uint64_t Volume::labelAt(int32_t i, int32_t j, int32_t k) const
{
  const auto& d = geometry.dims;
  if (i < 0 || j < 0 || k < 0 || i >= d[0] || j >= d[1] || k >= d[2])
  {
    throw std::out_of_range("voxel index outside the volume");
  }
  const auto n = geometry.cellCounts();
  const uint32_t s = layout::CELL_SIZE;
  const uint32_t cell = uint32_t(i / s + uint64_t(n[0]) * (j / s + uint64_t(n[1]) * (k / s)));
  const auto range = cellBlocks(cell);
  for (uint64_t b = range.first; b < range.second; ++b)
  {
    if (occupied(b, uint32_t(i) % s, uint32_t(j) % s, uint32_t(k) % s))
    {
      return labels[block(b).label].value;
    }
  }
  return background;
}

int64_t Volume::findLabel(uint64_t value) const
{
  auto it = std::lower_bound(labels.begin(), labels.end(), value,
    [this](const LabelInfo& l, uint64_t v) { return scalarLess(scalarType, l.value, v); });
  return (it != labels.end() && it->value == value) ? int64_t(it - labels.begin()) : -1;
}

MemoryUsage Volume::memory() const
{
  // Bytes of the packed bits; the padding word is an implementation detail of the reader.
  auto bytes = [](uint64_t bits) { return (bits + 7) / 8; };
  MemoryUsage m;
  m.blocks = bytes(blockCount * widths.blockBits());
  m.roots = roots.empty() ? 0 : (roots.size() - 1) * 4;
  m.mids = mids.empty() ? 0 : (mids.size() - 1) * 4;
  m.leaves = leaves.size() * 8;
  m.labels = labels.size() * uint64_t(scalarSize(scalarType));
  return m;
}

namespace
{
using bits::popcount64;
using bits::popcount8;

// A field of `width` bits at `offset` of a padded word stream, for offsets already known to lie
// inside the stream's data (the padding word makes the second word readable).
inline uint32_t fieldAt(const uint32_t* words, uint64_t offset, uint32_t width)
{
  if (width == 0)
    return 0;
  const uint64_t i = offset >> 5;
  const uint64_t pair = uint64_t(words[i]) | (uint64_t(words[i + 1]) << 32);
  return uint32_t(pair >> (offset & 31)) & layout::lowMask(width);
}

// Start offsets of the nodes of one stream, for O(1) "is this a node start" lookups. Every node
// takes at least 16 bits, so no two starts share a 16-bit slot: one bit per slot plus a rank per
// 64 slots (about 1/14 of the stream's size) find a node's ordinal from its offset.
class NodeIndex
{
public:
  void reset(uint64_t totalBits, uint64_t expected)
  {
    slots.assign(size_t(totalBits / (16 * 64) + 1), 0);
    starts.reset(new uint64_t[size_t(expected)]); // written before it is read: no zeroing
    count = 0;
  }
  // Offsets come in increasing order, at most `expected` of them.
  void add(uint64_t offset)
  {
    slots[size_t(offset >> 10)] |= uint64_t(1) << ((offset >> 4) & 63);
    starts[size_t(count++)] = offset;
  }
  void finish()
  {
    rank.resize(slots.size());
    uint64_t r = 0;
    for (size_t i = 0; i < slots.size(); ++i)
    {
      rank[i] = r;
      r += popcount64(slots[i]);
    }
  }
  // Ordinal of the node starting at `offset`, or -1 when no node starts there.
  int64_t find(uint64_t offset) const
  {
    const uint64_t word = offset >> 10;
    if (word >= slots.size())
      return -1;
    const uint64_t bit = uint64_t(1) << ((offset >> 4) & 63);
    if (!(slots[size_t(word)] & bit))
      return -1;
    const uint64_t i = rank[size_t(word)] + popcount64(slots[size_t(word)] & (bit - 1));
    return starts[size_t(i)] == offset ? int64_t(i) : -1;
  }
  uint64_t start(uint64_t ordinal) const { return starts[size_t(ordinal)]; }
  uint64_t size() const { return count; }

private:
  std::vector<uint64_t> slots;
  std::vector<uint64_t> rank;
  std::unique_ptr<uint64_t[]> starts;
  uint64_t count = 0;
};

// Projections of a 4^3 leaf mask (bit x + 4 y + 16 z) onto x, y and z, as 8-bit lanes
// x | y << 8 | z << 16 (bit c of a lane: some voxel has that coordinate).
inline uint32_t leafLanes(uint64_t m)
{
  uint64_t t = m | (m >> 32);
  t |= t >> 16;
  t &= 0xFFFFu; // bit x + 4 y: some voxel of that column
  const uint32_t px = uint32_t(t | (t >> 4) | (t >> 8) | (t >> 12)) & 0xFu;
  uint64_t v = t | (t >> 1);
  v |= v >> 2;
  v &= 0x1111u;                                             // bit 4 y: row y not empty
  const uint32_t py = uint32_t((v * 0x1248u) >> 12) & 0xFu; // gathers bits 0, 4, 8, 12
  uint64_t u = m | (m >> 8);
  u |= u >> 4;
  u |= u >> 2;
  u |= u >> 1;
  u &= 0x0001000100010001ull; // bit 16 z: slice z not empty
  const uint64_t gather = (uint64_t(1) << 48) | (uint64_t(1) << 33) | (uint64_t(1) << 18) | 8u;
  const uint32_t pz = uint32_t((u * gather) >> 48) & 0xFu;
  return px | (py << 8) | (pz << 16);
}

// leafLanes of a child read under leaf symmetry s, from the stored leaf's lanes: stored axis j
// lands on child axis p_j (the permutation of s), reversed when s mirrors it (Layout.h). A few
// shifts per reference instead of expanding the child's mask.
class LaneSymmetries
{
public:
  LaneSymmetries()
  {
    for (uint32_t s = 0; s < layout::LEAF_SYMMETRY_COUNT; ++s)
      for (uint32_t j = 0; j < 3; ++j)
        this->Shift[s][j] = uint8_t(8 * layout::leafSymmetryCoordinate(s & ~7u, j, 0, 1, 2));
    auto reversed = [](uint32_t v) {
      return ((v & 1u) << 3) | ((v & 2u) << 1) | ((v & 4u) >> 1) | (v >> 3);
    };
    for (uint32_t v = 0; v < 256; ++v)
    {
      this->Lanes[0][v] = uint8_t(v);
      this->Lanes[1][v] = uint8_t(reversed(v & 0xFu) | (reversed(v >> 4) << 4));
    }
  }
  // Both polarities of a child at once: `lanes` and `complementLanes` moved to `out` and
  // `complementOut` (lanes in bits 0-3, 8-11, 16-19 of each).
  void apply(uint32_t s, uint32_t lanes, uint32_t complementLanes, uint32_t& out,
    uint32_t& complementOut) const
  {
    const uint32_t both = (lanes & 0x0F0F0Fu) | ((complementLanes & 0x0F0F0Fu) << 4);
    uint32_t moved = 0;
    for (uint32_t j = 0; j < 3; ++j) // a lookup, not a branch: s varies from leaf to leaf
      moved |= uint32_t(this->Lanes[(s >> j) & 1u][(both >> (8 * j)) & 0xFFu]) << this->Shift[s][j];
    out = moved & 0x0F0F0Fu;
    complementOut = (moved >> 4) & 0x0F0F0Fu;
  }

private:
  uint8_t Shift[layout::LEAF_SYMMETRY_COUNT][3];
  uint8_t Lanes[2][256]; // two lanes a byte: as they are, each reversed
};

// The full mask of a node read with polarity p (complemented: empty and full children swap).
inline uint32_t fullAs(uint32_t header, bool p)
{
  const uint32_t mixed = layout::nodeMixedMask(header), full = layout::nodeFullMask(header);
  return p ? (~(mixed | full) & 0xFFu) : full;
}

// Volume::validate, check by check. Each check throws std::runtime_error("invalid SVDAG: ...")
// naming the first inconsistency it finds; later checks rely on what earlier ones established
// (widths before any field is read, node starts before any reference is followed).
[[noreturn]] void fail(const std::string& what)
{
  throw std::runtime_error("invalid SVDAG: " + what);
}

std::string str(uint64_t v)
{
  return std::to_string(v);
}

// Dimensions, field widths, stream sizes and the scalar type: what every later check indexes with.
void checkHeader(const Volume& v)
{
  for (int a = 0; a < 3; ++a)
  {
    if (v.geometry.dims[a] < 0)
      fail("negative dimension");
  }
  const uint64_t cells = v.geometry.cellCount();
  if (cells > (uint64_t(1) << 32))
    fail("more than 2^32 cells");
  const FieldWidths& w = v.widths;
  if (w.cellBits > 32 || w.labelBits > 32 || w.rootRefBits > 32 || w.midRefBits > 32 ||
    w.leafRefBits > 32)
    fail("field width above 32 bits");
  if (cells > 0 && (cells - 1) >> w.cellBits)
    fail("cell field too narrow for the grid");
  if (!v.labels.empty() && (uint64_t(v.labels.size() - 1) >> w.labelBits))
    fail("label field too narrow for the label table");
  uint64_t blockBitsTotal = 0; // a huge count must not wrap around to a small stream
  if (__builtin_mul_overflow(v.blockCount, uint64_t(w.blockBits()), &blockBitsTotal) ||
    v.blocks.size() != blockBitsTotal / 32 + (blockBitsTotal % 32 ? 1 : 0) + 1)
    fail("block stream size does not match the block count");
  if (v.roots.empty() || v.mids.empty())
    fail("missing stream padding");
  if (int(v.scalarType) >= ScalarTypeCount)
    fail("unknown scalar type");
}

// The label table: values of the type, sorted, unique, not the background, bounds in the volume.
void checkLabelTable(const Volume& v)
{
  const auto& d = v.geometry.dims;
  auto validValue = [&v](uint64_t value) {
    uint64_t tmp = 0;
    scalarStore(v.scalarType, &tmp, 0, value);
    return scalarLoad(v.scalarType, &tmp, 0) == value;
  };
  for (size_t l = 0; l < v.labels.size(); ++l)
  {
    const LabelInfo& info = v.labels[l];
    if (!validValue(info.value))
      fail("label " + str(l) + ": value outside the range of " + scalarName(v.scalarType));
    if (info.value == v.background)
      fail("the label table holds the background value");
    if (l > 0 && !scalarLess(v.scalarType, v.labels[l - 1].value, info.value))
      fail("label table not sorted by value or not unique (label " + str(l) + ")");
    for (int a = 0; a < 3; ++a)
    {
      const int32_t lo = info.bounds[2 * a], hi = info.bounds[2 * a + 1];
      if (lo < 0 || lo > hi || hi >= d[a])
        fail("label " + str(l) + ": bounds outside the volume");
    }
  }
}

// A node pool's occupancy summaries in both polarities (entries 2 n and 2 n + 1 for node n, the
// second as read complemented), and which nodes a reference reached: every stored node must be
// used, so that no node can hide in a stream's padding bits (a zero header is a well-formed
// empty node).
struct NodePool
{
  std::unique_ptr<uint64_t[]> summaries;
  std::vector<uint8_t> used;
  void checkAllUsed(const char* what) const
  {
    for (size_t n = 0; n < used.size(); ++n)
      if (!used[n])
        fail(std::string(what) + " node " + str(n) + " is not referenced");
  }
};

// A leaf child's summary in one polarity: projection lanes (x bits 0-3, y 8-11, z 16-19) and
// voxel count (24-30).
uint32_t leafSummary(uint64_t mask)
{
  return leafLanes(mask) | (popcount64(mask) << 24);
}

// Records node n as the first, in order, to fail a check run through `parallel`.
void keepFirst(std::atomic<uint64_t>& firstBad, uint64_t n)
{
  uint64_t seen = firstBad.load();
  while (n < seen && !firstBad.compare_exchange_weak(seen, n))
  {
  }
}

// Walks one node stream into `nodes` and `refs` (PooledGraph): every node well formed and every
// child reference at a node start (a reference into the middle of a node would read its
// references as a header and run past the checked nodes) or an existing leaf. resolve(ref,
// target) checks the reference of a mixed child and sets what the graph keeps of it. Where nodes
// start is found in order; the references are then resolved node by node through `parallel`, so
// `resolve` may run on several threads at once. Returns where the nodes start.
template <typename Resolve>
NodeIndex walkNodeStream(const std::vector<uint32_t>& stream, uint64_t count, uint32_t refBits,
  const char* what, const Resolve& resolve, const ParallelFor& parallel,
  std::vector<PooledGraph::Node>& nodes, std::vector<uint32_t>& refs)
{
  const uint32_t* words = stream.data();
  const uint64_t total = uint64_t(stream.size() - 1) * 32;
  const uint64_t expected = std::min<uint64_t>(count, total / layout::NODE_HEADER_BITS + 1);
  NodeIndex index;
  index.reset(total, expected);
  uint64_t offset = 0, children = 0;
  nodes.resize(size_t(expected));
  for (uint64_t n = 0; n < count; ++n)
  {
    if (offset + layout::NODE_HEADER_BITS > total)
      fail(std::string(what) + " stream shorter than its node count");
    const uint32_t header = fieldAt(words, offset, layout::NODE_HEADER_BITS);
    const uint32_t mixed = layout::nodeMixedMask(header), full = layout::nodeFullMask(header);
    if (mixed & full)
      fail(std::string(what) + " node at bit " + str(offset) + ": child both mixed and full");
    const uint64_t end = offset + layout::NODE_HEADER_BITS + uint64_t(popcount8(mixed)) * refBits;
    if (end > total)
      fail(std::string(what) + " node runs past the end of its stream");
    nodes[size_t(n)] = { header, popcount8(mixed), uint32_t(children) };
    children += popcount8(mixed);
    if (children > 0xFFFFFFFFull)
      fail(std::string(what) + " stream: more than 2^32 references");
    index.add(offset);
    offset = end;
  }
  if (total - offset >= 32)
    fail(std::string(what) + " stream longer than its nodes");
  index.finish();
  refs.resize(size_t(children));
  std::atomic<uint64_t> firstBad{ count };
  parallel(0, count, 256, [&](uint64_t begin, uint64_t end) {
    for (uint64_t n = begin; n < end; ++n)
    {
      const PooledGraph::Node& node = nodes[size_t(n)];
      uint64_t refAt = index.start(n) + layout::NODE_HEADER_BITS;
      for (uint32_t k = 0; k < node.count; ++k, refAt += refBits)
        if (!resolve(fieldAt(words, refAt, refBits), refs[node.first + k]))
        {
          keepFirst(firstBad, n);
          return;
        }
    }
  });
  if (firstBad.load() < count)
    fail(std::string(what) + " node at bit " + str(index.start(firstBad.load())) +
      ": child reference does not point at a node");
  return index;
}

// The graph of a pooled volume's node streams and blocks, every reference checked.
PooledGraph graphOfStreams(const Volume& v, const ParallelFor& parallel)
{
  PooledGraph g;
  const NodeIndex mids = walkNodeStream(v.mids, v.midCount, v.widths.leafRefBits, "mid",
    [&](uint32_t ref, uint32_t& target) {
      target = ref;
      return layout::leafRefIndex(ref) < v.leaves.size() &&
        layout::leafRefSymmetry(ref) < layout::LEAF_SYMMETRY_COUNT;
    },
    parallel, g.mids, g.leafRefs);
  const NodeIndex roots = walkNodeStream(v.roots, v.rootCount, v.widths.midRefBits, "root",
    [&](uint32_t ref, uint32_t& target) {
      const int64_t mid = mids.find(layout::refTarget(ref));
      if (mid < 0)
        return false;
      target = uint32_t(mid << 1) | (ref & 1u);
      return true;
    },
    parallel, g.roots, g.midRefs);
  const uint64_t recordBits = v.widths.blockBits();
  const uint32_t rootAt = layout::blockRootOffset(v.widths.cellBits, v.widths.labelBits);
  g.blockRoots.resize(size_t(v.blockCount)); // checkHeader matched the count to the blocks
  for (uint64_t i = 0; i < v.blockCount; ++i)
  {
    const uint32_t rootRef = fieldAt(v.blocks.data(), i * recordBits + rootAt, v.widths.rootRefBits);
    const int64_t root = roots.find(layout::refTarget(rootRef));
    if (root < 0)
      fail("block " + str(i) + ": root reference does not point at a root node");
    g.blockRoots[size_t(i)] = uint32_t(root << 1) | (rootRef & 1u);
  }
  return g;
}

// A graph as the checks below read it: one node per node of the volume, each with its references
// where the one before left off, one root per block and inside the root pool. A decoder's graph is
// checked here too.
void checkGraphShape(const Volume& v, const PooledGraph& g)
{
  auto checkLevel = [](const std::vector<PooledGraph::Node>& nodes, uint64_t count,
                      const std::vector<uint32_t>& refs, const char* what) {
    if (nodes.size() != count)
      fail(std::string(what) + " graph does not hold the node count");
    uint64_t first = 0;
    for (const PooledGraph::Node& n : nodes)
    {
      const uint32_t mixed = layout::nodeMixedMask(n.header);
      if (n.first != first || n.count != popcount8(mixed) || (mixed & layout::nodeFullMask(n.header)))
        fail(std::string(what) + " graph: a node's children do not match its masks");
      first += n.count;
    }
    if (first != refs.size())
      fail(std::string(what) + " graph: references beyond its nodes'");
  };
  checkLevel(g.mids, v.midCount, g.leafRefs, "mid");
  checkLevel(g.roots, v.rootCount, g.midRefs, "root");
  if (g.blockRoots.size() != v.blockCount)
    fail("the graph does not hold a root per block");
  for (size_t i = 0; i < g.blockRoots.size(); ++i)
    if ((g.blockRoots[i] >> 1) >= v.rootCount)
      fail("block " + str(i) + ": root outside its pool");
}

// Summarises one level's nodes from the graph, node by node through `parallel`:
// child(ref, acc0, acc1) stores the summary of a mixed child in both polarities (a solid child
// is `solid`), or returns false for a reference outside its pool (neither the walk nor a
// decoder lets one through); combine(acc) summarises a node from its 8 children. Summarising
// once per distinct node lets the block checks bound and count voxels without expanding any.
template <typename Child, typename Combine>
NodePool summarise(const std::vector<PooledGraph::Node>& nodes, const std::vector<uint32_t>& refs,
  const char* what, uint64_t solid, const Child& child, const Combine& combine,
  const ParallelFor& parallel)
{
  const uint64_t count = nodes.size();
  NodePool pool;
  pool.summaries.reset(new uint64_t[size_t(2 * count)]);
  uint64_t* summary = pool.summaries.get();
  std::atomic<uint64_t> firstBad{ count };
  parallel(0, count, 256, [&](uint64_t begin, uint64_t end) {
    for (uint64_t n = begin; n < end; ++n)
    {
      const PooledGraph::Node& node = nodes[size_t(n)];
      const uint32_t mixed = layout::nodeMixedMask(node.header);
      const uint32_t full = layout::nodeFullMask(node.header);
      // Solid children first, then the mixed ones bit by bit: no branch per child, whose
      // pattern changes from node to node.
      uint64_t acc0[8], acc1[8];
      for (uint32_t c = 0; c < 8; ++c)
      {
        const uint64_t isFull = uint64_t(0) - ((full >> c) & 1u);
        acc0[c] = solid & isFull;
        acc1[c] = solid & ~isFull;
      }
      const uint32_t* ref = refs.data() + node.first;
      for (uint32_t left = mixed; left; left &= left - 1)
      {
        const uint32_t c = uint32_t(__builtin_ctz(left));
        if (!child(*ref++, acc0[c], acc1[c]))
        {
          keepFirst(firstBad, n);
          return;
        }
      }
      summary[2 * n] = combine(acc0);
      summary[2 * n + 1] = combine(acc1);
    }
  });
  if (firstBad.load() < count)
    fail(std::string(what) + " node " + str(firstBad.load()) + ": child reference outside its pool");
  pool.used.assign(size_t(count), 0);
  return pool;
}

// The mid pool, from references to existing leaves. Summary: lanes x bits 0-7, y 8-15, z 16-23;
// voxels from bit 32.
NodePool summariseMids(const Volume& v, const PooledGraph& g, const ParallelFor& parallel)
{
  // Each stored leaf's summary in both polarities, once; a reference moves its lanes.
  static const LaneSymmetries symmetries;
  std::vector<uint32_t> stored(2 * v.leaves.size());
  parallel(0, v.leaves.size(), 4096, [&](uint64_t begin, uint64_t end) {
    for (uint64_t l = begin; l < end; ++l)
    {
      stored[2 * l] = leafSummary(v.leaves[l]);
      stored[2 * l + 1] = leafSummary(~v.leaves[l]);
    }
  });
  return summarise(g.mids, g.leafRefs, "mid", uint64_t(0x0F0F0Fu | (64u << 24)),
    [&](uint32_t ref, uint64_t& a0, uint64_t& a1) {
      const uint32_t leaf = layout::leafRefIndex(ref), s = layout::leafRefSymmetry(ref);
      if (leaf >= v.leaves.size() || s >= layout::LEAF_SYMMETRY_COUNT)
        return false;
      const uint32_t m = stored[2 * size_t(leaf) + (ref & 1u)];
      const uint32_t c = stored[(2 * size_t(leaf) + (ref & 1u)) ^ 1u];
      uint32_t moved, complementMoved;
      symmetries.apply(s, m, c, moved, complementMoved);
      a0 = moved | (m & 0xFF000000u);
      a1 = complementMoved | (c & 0xFF000000u);
      return true;
    },
    [](const uint64_t* a) {
      const uint64_t voxels = (a[0] >> 24) + (a[1] >> 24) + (a[2] >> 24) + (a[3] >> 24) +
        (a[4] >> 24) + (a[5] >> 24) + (a[6] >> 24) + (a[7] >> 24);
      const uint64_t xlo = a[0] | a[2] | a[4] | a[6], xhi = a[1] | a[3] | a[5] | a[7];
      const uint64_t ylo = a[0] | a[1] | a[4] | a[5], yhi = a[2] | a[3] | a[6] | a[7];
      const uint64_t zlo = a[0] | a[1] | a[2] | a[3], zhi = a[4] | a[5] | a[6] | a[7];
      return (xlo & 0xFu) | ((xhi & 0xFu) << 4) | (ylo & 0xF00u) | ((yhi & 0xF00u) << 4) |
        (zlo & 0xF0000u) | ((zhi & 0xF0000u) << 4) | (voxels << 32);
    },
    parallel);
}

// The root pool, from references to mids. Summary: lanes x bits 0-15, y 16-31, z 32-47; voxels
// from bit 48.
NodePool summariseRoots(const PooledGraph& g, NodePool& mids, const ParallelFor& parallel)
{
  return summarise(g.roots, g.midRefs, "root", uint64_t(0xFFFFFFu) | (uint64_t(512) << 32),
    [&](uint32_t ref, uint64_t& a0, uint64_t& a1) {
      const uint32_t mid = ref >> 1;
      if (mid >= g.mids.size())
        return false;
      // Roots are summarised in parallel and share mids: the one write is an atomic store.
      __atomic_store_n(&mids.used[mid], uint8_t(1), __ATOMIC_RELAXED);
      const size_t at = 2 * size_t(mid) + (ref & 1u);
      a0 = mids.summaries[at];
      a1 = mids.summaries[at ^ 1u];
      return true;
    },
    [](const uint64_t* a) {
      const uint64_t voxels = (a[0] >> 32) + (a[1] >> 32) + (a[2] >> 32) + (a[3] >> 32) +
        (a[4] >> 32) + (a[5] >> 32) + (a[6] >> 32) + (a[7] >> 32);
      const uint64_t xlo = a[0] | a[2] | a[4] | a[6], xhi = a[1] | a[3] | a[5] | a[7];
      const uint64_t ylo = a[0] | a[1] | a[4] | a[5], yhi = a[2] | a[3] | a[6] | a[7];
      const uint64_t zlo = a[0] | a[1] | a[2] | a[3], zhi = a[4] | a[5] | a[6] | a[7];
      return (xlo & 0xFFu) | ((xhi & 0xFFu) << 8) | ((ylo & 0xFF00u) << 8) |
        ((yhi & 0xFF00u) << 16) | ((zlo & 0xFF0000u) << 16) | ((zhi & 0xFF0000u) << 24) |
        (voxels << 48);
    },
    parallel);
}

// The blocks of one cell, gathered while the blocks are checked in order: no label twice, and
// no voxel in two blocks (a voxel has one label).
class CellBlocks
{
public:
  CellBlocks(const Volume& v, const PooledGraph& g)
    : V(v)
    , G(g)
  {
    for (std::vector<MidEntry>& list : this->Octants)
      list.reserve(64); // one entry a block of the cell: most cells need no more
  }

  // `root`: the block's root in the graph, index << 1 | complement.
  void add(uint64_t index, uint32_t label, uint32_t root)
  {
    this->Labels.push_back(label);
    this->Entries.push_back({ index, root, this->G.roots[root >> 1].header });
  }

  // Checks the cell's blocks added since the last call, then forgets them.
  void check(uint32_t cell)
  {
    this->checkDisjoint(cell);
    this->checkLabelsUnique(cell);
    this->Entries.clear();
  }

private:
  struct Entry
  {
    uint64_t index;  // block
    uint32_t root;   // its root, index << 1 | complement
    uint32_t header; // the root node's header
  };
  struct MidEntry
  {
    size_t entry; // in Entries
    uint32_t mid; // index in the mid pool
    bool inverted;
    uint32_t mixed, full; // full as read with `inverted`
  };

  void checkLabelsUnique(uint32_t cell)
  {
    if (this->Labels.size() > 1) // a cell of one block has nothing to sort
    {
      std::sort(this->Labels.begin(), this->Labels.end());
      if (std::adjacent_find(this->Labels.begin(), this->Labels.end()) != this->Labels.end())
        fail("cell " + str(cell) + " holds two blocks of one label");
    }
    this->Labels.clear();
  }

  [[noreturn]] void overlap(size_t a, size_t b, uint32_t cell) const
  {
    fail("blocks " + str(this->Entries[a].index) + " and " + str(this->Entries[b].index) +
      " of cell " + str(cell) + " overlap (a voxel has one label)");
  }

  // Level by level: a solid child may meet no other non-empty one; children mixed in two or
  // more blocks are compared one level down, and leaves voxel by voxel.
  void checkDisjoint(uint32_t cell)
  {
    if (this->Entries.size() < 2)
      return;
    // Two blocks whose roots are each other's complement split the cell between them.
    if (this->Entries.size() == 2 && (this->Entries[0].root ^ this->Entries[1].root) == 1u)
      return;
    const uint32_t shared = this->checkRootLevel(cell);
    this->gatherSharedOctants(shared);
    for (std::vector<MidEntry>& list : this->Octants)
      this->checkOctant(list, cell);
  }

  // The root nodes' children; returns the octants mixed in two or more blocks.
  uint32_t checkRootLevel(uint32_t cell) const
  {
    uint32_t accNonEmpty = 0, accFull = 0, accMixed = 0, shared = 0;
    for (size_t e = 0; e < this->Entries.size(); ++e)
    {
      const Entry& ce = this->Entries[e];
      const uint32_t mixed = layout::nodeMixedMask(ce.header);
      const uint32_t full = fullAs(ce.header, layout::refComplement(ce.root));
      if ((accNonEmpty & full) | (accFull & (mixed | full)))
        this->overlap(e - 1, e, cell);
      shared |= accMixed & mixed;
      accNonEmpty |= mixed | full;
      accFull |= full;
      accMixed |= mixed;
    }
    return shared;
  }

  // The mid references of the shared octants, read in one sequential pass per block.
  void gatherSharedOctants(uint32_t shared)
  {
    for (std::vector<MidEntry>& list : this->Octants)
      list.clear();
    for (size_t e = 0; e < this->Entries.size(); ++e)
    {
      const Entry& ce = this->Entries[e];
      const uint32_t mixed = layout::nodeMixedMask(ce.header);
      const uint32_t* refs = this->G.midRefs.data() + this->G.roots[ce.root >> 1].first;
      for (uint32_t both = mixed & shared; both; both &= both - 1) // set bits: few branches
      {
        const uint32_t o = uint32_t(__builtin_ctz(both));
        const uint32_t midRef = refs[layout::childRank(mixed, o)];
        MidEntry me;
        me.entry = e;
        me.mid = midRef >> 1;
        me.inverted = layout::refComplement(ce.root) != layout::refComplement(midRef);
        this->Octants[o].push_back(me);
      }
    }
  }

  // One octant's mid nodes, then the leaves mixed in two or more of them voxel by voxel.
  void checkOctant(std::vector<MidEntry>& list, uint32_t cell) const
  {
    // Two blocks splitting the octant between them refer to one node with opposite polarity
    // (the common case: the two sides of a boundary share their node, complemented).
    if (list.size() < 2 ||
      (list.size() == 2 && list[0].mid == list[1].mid && list[0].inverted != list[1].inverted))
      return;
    uint32_t midNonEmpty = 0, midFullAcc = 0, midMixedAcc = 0, midShared = 0;
    for (size_t k = 0; k < list.size(); ++k)
    {
      MidEntry& me = list[k];
      const uint32_t header = this->G.mids[me.mid].header;
      me.mixed = layout::nodeMixedMask(header);
      me.full = fullAs(header, me.inverted);
      if ((midNonEmpty & me.full) | (midFullAcc & (me.mixed | me.full)))
        this->overlap(k > 0 ? list[k - 1].entry : me.entry, me.entry, cell);
      midShared |= midMixedAcc & me.mixed;
      midNonEmpty |= me.mixed | me.full;
      midFullAcc |= me.full;
      midMixedAcc |= me.mixed;
    }
    if (!midShared)
      return;
    uint64_t acc[8] = {};
    size_t owner[8] = {};
    // The first leaf of each child as a reference (read as complemented or not) until a second
    // one needs its voxels: two blocks splitting a leaf refer to it with opposite polarity, and
    // together fill it without expanding either. Then a child's leaves are compared as the first
    // one is stored (a symmetry moves voxels one to one, so two leaves overlap there where they
    // overlap in the child): the first one as it is, each next one under the symmetry that does
    // its own and then undoes the first's.
    uint32_t firstRef[8] = {}, undoFirst[8] = {};
    bool firstInverted[8] = {}, pending[8] = {};
    for (const MidEntry& me : list)
    {
      const uint32_t* refs = this->G.leafRefs.data() + this->G.mids[me.mid].first;
      for (uint32_t both = me.mixed & midShared; both; both &= both - 1)
      {
        const uint32_t c = uint32_t(__builtin_ctz(both));
        const uint32_t leafRef = refs[layout::childRank(me.mixed, c)];
        const bool inverted = me.inverted != layout::refComplement(leafRef);
        const uint32_t stored = leafRef & ~1u;
        if (!acc[c] && !pending[c])
        {
          pending[c] = true;
          firstRef[c] = stored;
          firstInverted[c] = inverted;
          owner[c] = me.entry;
          continue;
        }
        if (pending[c])
        {
          pending[c] = false;
          if (firstRef[c] == stored && firstInverted[c] != inverted)
          {
            acc[c] = ~uint64_t(0);
            owner[c] = me.entry;
            continue;
          }
          undoFirst[c] = inverseLeafSymmetry(layout::leafRefSymmetry(firstRef[c]));
          const uint64_t first = this->V.leaves[layout::leafRefIndex(firstRef[c])];
          acc[c] = firstInverted[c] ? ~first : first;
        }
        const uint64_t m = leafUnderSymmetry(
                             composeLeafSymmetries(undoFirst[c], layout::leafRefSymmetry(leafRef)),
                             this->V.leaves[layout::leafRefIndex(leafRef)]) ^
          (uint64_t(0) - uint64_t(inverted));
        if (acc[c] & m)
          this->overlap(owner[c], me.entry, cell);
        acc[c] |= m;
        owner[c] = me.entry;
      }
    }
  }

  const Volume& V;
  const PooledGraph& G;
  std::vector<Entry> Entries;
  std::vector<MidEntry> Octants[8];
  std::vector<uint32_t> Labels; // the labels of the current cell's blocks
};

// What the blocks hold per label, for the label table to match.
struct LabelTotals
{
  std::vector<uint64_t> voxels;
  std::vector<std::array<int32_t, 6>> bounds;
};

// The blocks of every cell disjoint and of distinct labels (CellBlocks), for blocks whose
// fields checkBlocks has checked; cells side by side through `parallel` (a range of blocks
// takes the cells that start in it). The error is the first failing cell's, as in order.
void checkCells(const Volume& v, const PooledGraph& g, const ParallelFor& parallel)
{
  const FieldWidths& w = v.widths;
  const uint32_t* blockWords = v.blocks.data();
  const uint32_t recordBits = w.blockBits();
  const uint32_t labelFieldAt = layout::blockLabelOffset(w.cellBits);
  auto cellOf = [&](uint64_t i) { return fieldAt(blockWords, i * recordBits, w.cellBits); };
  // The cell starting at block `first` through `cells`; returns the block after it.
  auto checkCell = [&](uint64_t first, CellBlocks& cells) {
    const uint32_t cell = cellOf(first);
    uint64_t i = first;
    for (; i < v.blockCount && cellOf(i) == cell; ++i)
      cells.add(i, fieldAt(blockWords, i * recordBits + labelFieldAt, w.labelBits), g.blockRoots[i]);
    cells.check(cell);
    return i;
  };
  std::atomic<uint64_t> firstBad{ v.blockCount };
  parallel(0, v.blockCount, 4096, [&](uint64_t begin, uint64_t end) {
    uint64_t i = begin;
    while (i > 0 && i < end && cellOf(i) == cellOf(i - 1))
      ++i;
    CellBlocks cells(v, g);
    while (i < end)
    {
      const uint64_t first = i;
      try
      {
        i = checkCell(first, cells);
      }
      catch (const std::runtime_error&)
      {
        keepFirst(firstBad, first);
        return;
      }
    }
  });
  if (firstBad.load() < v.blockCount)
  {
    CellBlocks cells(v, g);
    checkCell(firstBad.load(), cells); // throws its error on this thread
  }
}

// Blocks: sorted by cell, inside the grid and the volume, each occupancy non-empty and inside
// its bounds (decoders write only inside the bounds, the traversal reads the whole cell: both
// must agree), the blocks of a cell disjoint (checkCells); returns each label's voxel count and
// bounds as the blocks hold them.
LabelTotals checkBlocks(
  const Volume& v, const PooledGraph& g, NodePool& roots, const ParallelFor& parallel)
{
  const FieldWidths& w = v.widths;
  const auto& d = v.geometry.dims;
  const uint64_t cells = v.geometry.cellCount();
  const auto n = v.geometry.cellCounts();
  LabelTotals totals;
  totals.voxels.assign(v.labels.size(), 0);
  totals.bounds.assign(v.labels.size(),
    std::array<int32_t, 6>{ { INT32_MAX, INT32_MIN, INT32_MAX, INT32_MIN, INT32_MAX, INT32_MIN } });
  const uint32_t* blockWords = v.blocks.data();
  const uint32_t recordBits = w.blockBits();
  const uint32_t boundsAt = layout::blockBoundsOffset(w.cellBits);
  const uint32_t labelFieldAt = layout::blockLabelOffset(w.cellBits);
  uint32_t previousCell = 0;
  for (uint64_t i = 0; i < v.blockCount; ++i)
  {
    const uint64_t base = i * recordBits;
    const uint32_t cell = fieldAt(blockWords, base, w.cellBits);
    const uint32_t box = fieldAt(blockWords, base + boundsAt, layout::BLOCK_BOUNDS_BITS);
    const uint32_t label = fieldAt(blockWords, base + labelFieldAt, w.labelBits);
    auto name = [&]() { return "block " + str(i); };
    if (cell >= cells)
      fail(name() + ": cell outside the grid");
    if (label >= v.labels.size())
      fail(name() + ": label index out of range");
    // Blocks are sorted by cell; within a cell, files written before version 0.1's builder
    // sorted them by label come in scan order: only a label twice in one cell is refused.
    if (i > 0 && cell < previousCell)
      fail("blocks not sorted by cell (" + name() + ")");
    previousCell = cell;
    const uint32_t root = g.blockRoots[i] >> 1; // inside its pool (checkGraphShape, the walk)
    roots.used[root] = 1;
    const uint64_t summary = roots.summaries[2 * size_t(root) + (g.blockRoots[i] & 1u)];
    const uint32_t voxels = uint32_t(summary >> 48);
    if (voxels == 0)
      fail(name() + ": empty occupancy");
    // Cell origin in voxels; the bounds must stay inside the volume (cells on the far edges are
    // partial), since decoders write voxels inside the bounds without further checks.
    const uint64_t cellOrigin[3] = { uint64_t(cell % uint32_t(n[0])) * layout::CELL_SIZE,
      uint64_t(cell / uint32_t(n[0]) % uint32_t(n[1])) * layout::CELL_SIZE,
      uint64_t(cell / (uint64_t(n[0]) * uint64_t(n[1]))) * layout::CELL_SIZE };
    std::array<int32_t, 6>& lb = totals.bounds[label];
    for (int a = 0; a < 3; ++a)
    {
      const uint32_t blo = (box >> (4 * a)) & 15u, bhi = (box >> (12 + 4 * a)) & 15u;
      if (blo > bhi)
        fail(name() + ": bounds inverted");
      if (cellOrigin[a] + bhi >= uint64_t(d[a]))
        fail(name() + ": bounds outside the volume");
      const uint32_t proj = uint32_t(summary >> (16 * a)) & 0xFFFFu;
      const uint32_t lo = uint32_t(__builtin_ctz(proj)), hi = uint32_t(31 - __builtin_clz(proj));
      if (lo < blo || hi > bhi)
        fail(name() + ": occupancy outside its declared bounds");
      lb[2 * a] = std::min(lb[2 * a], int32_t(cellOrigin[a] + lo));
      lb[2 * a + 1] = std::max(lb[2 * a + 1], int32_t(cellOrigin[a] + hi));
    }
    totals.voxels[label] += voxels;
  }
  checkCells(v, g, parallel);
  return totals;
}

// The label table's voxel counts and bounds are exactly what the blocks hold.
void checkLabelTotals(const Volume& v, const LabelTotals& totals)
{
  for (size_t l = 0; l < v.labels.size(); ++l)
  {
    const std::string what = "label " + str(l) + " (value " +
      (scalarSigned(v.scalarType) ? std::to_string(int64_t(v.labels[l].value))
                                  : std::to_string(v.labels[l].value)) +
      ")";
    if (v.labels[l].voxels != totals.voxels[l])
      fail(what + ": voxel count " + str(v.labels[l].voxels) + " in the label table, " +
        str(totals.voxels[l]) + " in its blocks");
    if (v.labels[l].bounds != totals.bounds[l])
      fail(what + ": bounds in the label table differ from its blocks'");
  }
}

} // namespace

void Volume::validate(const ParallelFor& parallel) const
{
  if (form == DagForm::Compact)
  {
    // Checked in the pooled form, which pooled() reads with every bound checked.
    pooled(*this).validate(parallel);
    return;
  }
  checkHeader(*this);
  checkLabelTable(*this);
  const PooledGraph graph = graphOfStreams(*this, parallel);
  NodePool mids = summariseMids(*this, graph, parallel);
  NodePool roots = summariseRoots(graph, mids, parallel);
  mids.checkAllUsed("mid");
  checkLabelTotals(*this, checkBlocks(*this, graph, roots, parallel));
  roots.checkAllUsed("root");
}

void Volume::deriveBoundsAndValidate(
  const ParallelFor& parallel, PooledGraph* graph, const std::function<void()>& alongside)
{
  if (form != DagForm::Pooled)
    throw std::logic_error("Volume: validation reads the pooled form (svdag::pooled)");
  checkHeader(*this);
  PooledGraph walked;
  const bool decoded =
    graph && !(graph->mids.empty() && graph->roots.empty() && graph->blockRoots.empty());
  if (!decoded)
    (graph ? *graph : walked) = graphOfStreams(*this, parallel);
  const PooledGraph& g = graph ? *graph : walked;
  checkGraphShape(*this, g);
  NodePool mids = summariseMids(*this, g, parallel);
  NodePool roots = summariseRoots(g, mids, parallel);
  mids.checkAllUsed("mid");
  const uint64_t recordBits = this->widths.blockBits();
  const uint32_t boundsAt = layout::blockBoundsOffset(this->widths.cellBits);
  for (uint64_t i = 0; i < this->blockCount; ++i)
  {
    const uint32_t root = g.blockRoots[size_t(i)];
    const uint64_t summary = roots.summaries[2 * size_t(root >> 1) + (root & 1u)];
    uint32_t box = 0; // an empty occupancy keeps 0 (checkBlocks refuses it)
    for (uint32_t a = 0; a < 3 && (summary >> 48) != 0; ++a)
    {
      const uint32_t lane = uint32_t(summary >> (16 * a)) & 0xFFFFu;
      box |= (uint32_t(__builtin_ctz(lane)) << (4 * a)) |
        (uint32_t(31 - __builtin_clz(lane)) << (12 + 4 * a));
    }
    bits::replaceBits(this->blocks, i * recordBits + boundsAt, layout::BLOCK_BOUNDS_BITS, box);
  }
  LabelTotals totals;
  if (alongside) // two tasks: the checks (their loops then run on their task's thread), and it
    parallelTasks(parallel, 2, [&](uint64_t task) {
      if (task == 0)
        totals = checkBlocks(*this, g, roots, parallel);
      else
        alongside();
    });
  else
    totals = checkBlocks(*this, g, roots, parallel);
  for (size_t l = 0; l < this->labels.size(); ++l)
  {
    if (totals.voxels[l] == 0)
      fail("label " + str(l) + " is in no block");
    this->labels[l].voxels = totals.voxels[l];
    this->labels[l].bounds = totals.bounds[l];
  }
  checkLabelTable(*this);
  roots.checkAllUsed("root");
}

bool Volume::operator==(const Volume& o) const
{
  return geometry == o.geometry && scalarType == o.scalarType && background == o.background &&
    labels == o.labels && widths == o.widths && blockCount == o.blockCount && blocks == o.blocks &&
    form == o.form && rootCount == o.rootCount && roots == o.roots && midCount == o.midCount &&
    mids == o.mids && leaves == o.leaves;
}

} // namespace svdag
