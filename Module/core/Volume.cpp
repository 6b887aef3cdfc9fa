#include "svdag/Volume.h"

#include <algorithm>
#include <cstring>
#include <limits>
#include <stdexcept>

namespace svdag
{
namespace
{
#define SVDAG_WORD(stream, i) (stream)[(i)]

uint32_t readBits(const std::vector<uint32_t>& stream, uint64_t offset, uint32_t width)
{
  uint32_t result;
  SVDAG_READ_BITS(result, stream, offset, width);
  return result;
}

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

bool Volume::occupied(uint64_t blockIndex, uint32_t x, uint32_t y, uint32_t z) const
{
  uint32_t ref = block(blockIndex).root;
  bool inverted = false;
  // Root (16^3) and mid (8^3) levels share the node encoding.
  const std::vector<uint32_t>* streams[2] = { &roots, &mids };
  const uint32_t refBits[2] = { widths.midRefBits, widths.leafRefBits };
  uint32_t half = layout::CELL_SIZE / 2;
  for (int level = 0; level < 2; ++level, half /= 2)
  {
    inverted ^= layout::refComplement(ref);
    const uint64_t offset = layout::refTarget(ref);
    const uint32_t header = nodeHeader(*streams[level], offset);
    const uint32_t o = layout::octant(x, y, z, half);
    x %= half;
    y %= half;
    z %= half;
    const uint32_t mixed = layout::nodeMixedMask(header);
    if (!(mixed & (1u << o)))
    {
      return ((layout::nodeFullMask(header) >> o) & 1u) != inverted;
    }
    ref = nodeChildRef(*streams[level], offset, layout::childRank(mixed, o), refBits[level]);
  }
  inverted ^= layout::refComplement(ref);
  const uint64_t mask = leaves[layout::refTarget(ref)];
  return ((mask >> layout::leafBit(x, y, z)) & 1u) != inverted;
}

void Volume::occupancy(uint64_t blockIndex, uint8_t* out) const
{
  // Expands level by level; a solid or empty child fills its whole octant at once.
  std::memset(out, 0, layout::CELL_SIZE * layout::CELL_SIZE * layout::CELL_SIZE);
  auto fill = [out](uint32_t x0, uint32_t y0, uint32_t z0, uint32_t size) {
    for (uint32_t z = z0; z < z0 + size; ++z)
      for (uint32_t y = y0; y < y0 + size; ++y)
        std::memset(out + x0 + 16 * (y + 16 * z), 1, size);
  };
  const uint32_t rootRef = block(blockIndex).root;
  const bool rootInv = layout::refComplement(rootRef);
  const uint64_t rootOff = layout::refTarget(rootRef);
  const uint32_t rootHeader = nodeHeader(roots, rootOff);
  for (uint32_t o = 0; o < 8; ++o)
  {
    const uint32_t x0 = (o & 1) * 8, y0 = ((o >> 1) & 1) * 8, z0 = ((o >> 2) & 1) * 8;
    const uint32_t mixed = layout::nodeMixedMask(rootHeader);
    if (!(mixed & (1u << o)))
    {
      if (((layout::nodeFullMask(rootHeader) >> o) & 1u) != rootInv)
        fill(x0, y0, z0, 8);
      continue;
    }
    const uint32_t midRef =
      nodeChildRef(roots, rootOff, layout::childRank(mixed, o), widths.midRefBits);
    const bool midInv = rootInv != layout::refComplement(midRef);
    const uint64_t midOff = layout::refTarget(midRef);
    const uint32_t midHeader = nodeHeader(mids, midOff);
    const uint32_t midMixed = layout::nodeMixedMask(midHeader);
    for (uint32_t c = 0; c < 8; ++c)
    {
      const uint32_t x1 = x0 + (c & 1) * 4, y1 = y0 + ((c >> 1) & 1) * 4,
                     z1 = z0 + ((c >> 2) & 1) * 4;
      if (!(midMixed & (1u << c)))
      {
        if (((layout::nodeFullMask(midHeader) >> c) & 1u) != midInv)
          fill(x1, y1, z1, 4);
        continue;
      }
      const uint32_t leafRef =
        nodeChildRef(mids, midOff, layout::childRank(midMixed, c), widths.leafRefBits);
      uint64_t mask = leaves[layout::refTarget(leafRef)];
      if (midInv != layout::refComplement(leafRef))
        mask = ~mask;
      for (uint32_t b = 0; b < 64; ++b)
      {
        out[(x1 + (b & 3)) + 16 * ((y1 + ((b >> 2) & 3)) + 16 * (z1 + (b >> 4)))] =
          uint8_t((mask >> b) & 1u);
      }
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

void Volume::validate() const
{
  auto fail = [](const std::string& what) { throw std::runtime_error("invalid SVDAG: " + what); };
  for (int a = 0; a < 3; ++a)
  {
    if (geometry.dims[a] < 0)
      fail("negative dimension");
  }
  const uint64_t cells = geometry.cellCount();
  if (cells > (uint64_t(1) << 32))
    fail("more than 2^32 cells");
  const FieldWidths& w = widths;
  if (w.cellBits > 32 || w.labelBits > 32 || w.rootRefBits > 32 || w.midRefBits > 32 ||
    w.leafRefBits > 32)
    fail("field width above 32 bits");
  if (cells > 0 && (cells - 1) >> w.cellBits)
    fail("cell field too narrow for the grid");
  if (!labels.empty() && (uint64_t(labels.size() - 1) >> w.labelBits))
    fail("label field too narrow for the label table");
  if (blocks.size() != (blockCount * w.blockBits() + 31) / 32 + 1)
    fail("block stream size does not match the block count");
  if (roots.empty() || mids.empty())
    fail("missing stream padding");
  for (size_t l = 1; l < labels.size(); ++l)
  {
    if (!scalarLess(scalarType, labels[l - 1].value, labels[l].value))
      fail("label table not sorted");
  }
  const uint64_t rootBitsTotal = uint64_t(roots.size() - 1) * 32;
  const uint64_t midBitsTotal = uint64_t(mids.size() - 1) * 32;
  // A reference must point at the start of a node, not just inside the stream: a reference into
  // the middle of a node would read its references as a header and run past the checked nodes.
  // The node start offsets come from a sequential walk (nodes are contiguous and in offset order).
  auto isStart = [](const std::vector<uint64_t>& starts, uint64_t offset) {
    return std::binary_search(starts.begin(), starts.end(), offset);
  };
  auto walk = [&](const std::vector<uint32_t>& stream, uint64_t count, uint64_t total,
                uint32_t refBits, const char* what, const auto& childValid) {
    std::vector<uint64_t> starts;
    starts.reserve(size_t(std::min<uint64_t>(count, total / layout::NODE_HEADER_BITS + 1)));
    uint64_t offset = 0;
    for (uint64_t n = 0; n < count; ++n)
    {
      if (offset + layout::NODE_HEADER_BITS > total)
        fail(std::string(what) + " stream shorter than its node count");
      const uint32_t header = nodeHeader(stream, offset);
      const uint32_t mixed = layout::nodeMixedMask(header);
      if (mixed & layout::nodeFullMask(header))
        fail(std::string(what) + " child both mixed and full");
      const uint64_t end = offset + nodeBits(stream, offset, refBits);
      if (end > total)
        fail(std::string(what) + " node runs past the end of its stream");
      for (uint32_t r = 0; r < layout::bitCount(mixed); ++r)
      {
        if (!childValid(layout::refTarget(nodeChildRef(stream, offset, r, refBits))))
          fail(std::string(what) + " child reference does not point at a node");
      }
      starts.push_back(offset);
      offset = end;
    }
    if (total - offset >= 32)
      fail(std::string(what) + " stream longer than its nodes");
    return starts;
  };
  const std::vector<uint64_t> midStarts = walk(mids, midCount, midBitsTotal, w.leafRefBits, "mid",
    [this](uint64_t leaf) { return leaf < leaves.size(); });
  const std::vector<uint64_t> rootStarts = walk(roots, rootCount, rootBitsTotal, w.midRefBits,
    "root", [&](uint64_t mid) { return isStart(midStarts, mid); });

  const auto n = geometry.cellCounts();
  uint32_t previousCell = 0;
  for (uint64_t i = 0; i < blockCount; ++i)
  {
    const Block b = block(i);
    if (b.cell >= cells)
      fail("block cell outside the grid");
    if (i > 0 && b.cell < previousCell)
      fail("blocks not sorted by cell");
    previousCell = b.cell;
    if (b.label >= labels.size())
      fail("block label index out of range");
    // Cell origin in voxels; the bounds must stay inside the volume (cells on the far edges are
    // partial), since decoders write voxels inside the bounds without further checks.
    const uint64_t cellOrigin[3] = { uint64_t(b.cell % uint32_t(n[0])) * layout::CELL_SIZE,
      uint64_t(b.cell / uint32_t(n[0]) % uint32_t(n[1])) * layout::CELL_SIZE,
      uint64_t(b.cell / (uint64_t(n[0]) * uint64_t(n[1]))) * layout::CELL_SIZE };
    for (int a = 0; a < 3; ++a)
    {
      if (b.lo[a] > b.hi[a])
        fail("block bounds inverted");
      if (cellOrigin[a] + b.hi[a] >= uint64_t(geometry.dims[a]))
        fail("block bounds outside the volume");
    }
    if (!isStart(rootStarts, layout::refTarget(b.root)))
      fail("block root reference does not point at a root node");
  }
}

bool Volume::operator==(const Volume& o) const
{
  return geometry == o.geometry && scalarType == o.scalarType && background == o.background &&
    labels == o.labels && widths == o.widths && blockCount == o.blockCount && blocks == o.blocks &&
    rootCount == o.rootCount && roots == o.roots && midCount == o.midCount && mids == o.mids &&
    leaves == o.leaves;
}

} // namespace svdag
