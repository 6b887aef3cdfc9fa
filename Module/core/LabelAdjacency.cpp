// Label adjacency from the compressed form (svdag/LabelAdjacency.h).
#include "svdag/LabelAdjacency.h"

#include "svdag/RandomAccess.h"

#include <algorithm>
#include <mutex>
#include <string>

namespace svdag
{
namespace
{
constexpr uint32_t S = layout::CELL_SIZE; // 16
constexpr uint32_t RowCount = S * S;      // rows of a block: y + 16 z, bit x

// A pair packed as one integer (smaller index high), so that sort + unique orders it as LabelPair.
inline uint64_t packPair(uint32_t a, uint32_t b)
{
  return a < b ? (uint64_t(a) << 32 | b) : (uint64_t(b) << 32 | a);
}

void sortUnique(std::vector<uint64_t>& pairs)
{
  std::sort(pairs.begin(), pairs.end());
  pairs.erase(std::unique(pairs.begin(), pairs.end()), pairs.end());
}

// Block b's occupancy as 256 rows of 16 voxels (row y + 16 z, bit x), from its 64 leaf masks.
void blockRows(const Volume& v, uint64_t b, uint16_t* rows)
{
  uint64_t leaves[64];
  v.leafMasks(b, leaves);
  std::fill(rows, rows + RowCount, uint16_t(0));
  for (uint32_t l = 0; l < 64; ++l)
  {
    const uint64_t mask = leaves[l];
    if (mask == 0)
      continue;
    const uint32_t x0 = 4 * (l & 3), y0 = 4 * ((l >> 2) & 3), z0 = 4 * (l >> 4);
    for (uint32_t z = 0; z < 4; ++z)
      for (uint32_t y = 0; y < 4; ++y)
        rows[(y0 + y) + S * (z0 + z)] |= uint16_t(((mask >> (4 * y + 16 * z)) & 0xFu) << x0);
  }
}

// Whether two blocks of one cell hold face-adjacent voxels (+x, +y or +z of one in the other).
bool touchWithin(const uint16_t* a, const uint16_t* b)
{
  uint32_t any = 0;
  for (uint32_t r = 0; r < RowCount; ++r)
    any |= uint32_t(a[r] & (b[r] >> 1)) | uint32_t(b[r] & (a[r] >> 1));
  for (uint32_t r = 0; r + 1 < RowCount; ++r)
  {
    if ((r & (S - 1)) != S - 1)
      any |= uint32_t(a[r] & b[r + 1]) | uint32_t(b[r] & a[r + 1]);
  }
  for (uint32_t r = 0; r + S < RowCount; ++r)
    any |= uint32_t(a[r] & b[r + S]) | uint32_t(b[r] & a[r + S]);
  return any != 0;
}

// Whether block a's last voxel plane along `axis` touches block b's first one, b in a's +axis
// neighbour cell.
bool touchAcross(const uint16_t* a, const uint16_t* b, int axis)
{
  uint32_t any = 0;
  if (axis == 0)
  {
    for (uint32_t r = 0; r < RowCount; ++r)
      any |= uint32_t(a[r] >> (S - 1)) & b[r];
  }
  else if (axis == 1)
  {
    for (uint32_t z = 0; z < S; ++z)
      any |= uint32_t(a[(S - 1) + S * z] & b[S * z]);
  }
  else
  {
    for (uint32_t y = 0; y < S; ++y)
      any |= uint32_t(a[y + S * (S - 1)] & b[y]);
  }
  return (any & 0xFFFFu) != 0;
}

// Whether the bounds of two blocks of one cell, one of them grown by a voxel, overlap: a
// necessary condition for touching.
bool boundsMeet(const Block& a, const Block& b)
{
  for (int axis = 0; axis < 3; ++axis)
  {
    if (int(a.lo[axis]) > int(b.hi[axis]) + 1 || int(b.lo[axis]) > int(a.hi[axis]) + 1)
      return false;
  }
  return true;
}

// Whether two blocks' bounds overlap on the two axes other than `axis` (face neighbours across
// a cell face along `axis` must).
bool faceBoundsMeet(const Block& a, const Block& b, int axis)
{
  for (int other = 0; other < 3; ++other)
  {
    if (other != axis && (a.lo[other] > b.hi[other] || b.lo[other] > a.hi[other]))
      return false;
  }
  return true;
}

// The blocks of cell layer cz: [first, last).
std::pair<uint64_t, uint64_t> layerBlocks(const Volume& v, int32_t cz)
{
  const auto n = v.geometry.cellCounts();
  const uint64_t layerCells = uint64_t(n[0]) * uint64_t(n[1]);
  const uint64_t firstCell = uint64_t(cz) * layerCells;
  return { v.cellBlocks(uint32_t(firstCell)).first,
    v.cellBlocks(uint32_t(firstCell + layerCells - 1)).second };
}

// One decoded layer: its blocks' records and rows.
struct Layer
{
  uint64_t first = 0;
  std::vector<Block> blocks;
  std::vector<uint16_t> rows;
  const uint16_t* rowsOf(uint64_t b) const { return rows.data() + (b - first) * RowCount; }
  const Block& blockOf(uint64_t b) const { return blocks[size_t(b - first)]; }
};

void decodeLayer(const Volume& v, int32_t cz, Layer& layer, const ParallelFor& parallel)
{
  const auto range = layerBlocks(v, cz);
  layer.first = range.first;
  const size_t count = size_t(range.second - range.first);
  layer.blocks.resize(count);
  layer.rows.resize(count * RowCount);
  parallel(0, count, 16, [&](uint64_t begin, uint64_t end) {
    for (uint64_t i = begin; i < end; ++i)
    {
      layer.blocks[size_t(i)] = v.block(range.first + i);
      blockRows(v, range.first + i, layer.rows.data() + i * RowCount);
    }
  });
}
} // namespace

uint64_t labelAdjacencyBytes(const Volume& v)
{
  if (v.blockCount == 0)
    return 0;
  // Two layers' block records and rows at once.
  const auto n = v.geometry.cellCounts();
  uint64_t previous = 0, most = 0;
  for (int32_t cz = 0; cz < n[2]; ++cz)
  {
    const auto range = layerBlocks(v, cz);
    const uint64_t blocks = range.second - range.first;
    most = std::max(most, previous + blocks);
    previous = blocks;
  }
  return most * (RowCount * sizeof(uint16_t) + sizeof(Block));
}

std::vector<LabelPair> labelAdjacency(const Volume& v, const ParallelFor& parallel)
{
  std::vector<LabelPair> result;
  if (v.blockCount == 0 || v.labels.size() < 2)
    return result;
  checkOutputMemory(labelAdjacencyBytes(v), "the label adjacency of a " +
      std::to_string(v.geometry.dims[0]) + " x " + std::to_string(v.geometry.dims[1]) + " x " +
      std::to_string(v.geometry.dims[2]) + " volume");
  const auto n = v.geometry.cellCounts();
  const uint64_t nx = uint64_t(n[0]), ny = uint64_t(n[1]), layerCells = nx * ny;

  std::vector<uint64_t> found; // packed pairs of every layer so far, sorted and unique
  std::mutex merge;
  Layer previous, current;
  for (int32_t cz = 0; cz < n[2]; ++cz)
  {
    decodeLayer(v, cz, current, parallel);
    // Cells of the layer in parallel: the pairs inside each cell, and across its -x, -y and -z
    // faces, so that every face of the volume is seen exactly once.
    parallel(0, layerCells, 64, [&](uint64_t begin, uint64_t end) {
      std::vector<uint64_t> local;
      const auto see = [&](const Block& a, const Block& b, bool touch) {
        if (touch)
          local.push_back(packPair(a.label, b.label));
      };
      // Blocks of `other` (a's -axis neighbour cell, in `layer`) touching this cell's blocks.
      const auto across = [&](const Layer& layer, uint64_t otherCell, uint64_t first,
                            uint64_t last, int axis) {
        const auto o = v.cellBlocks(uint32_t(otherCell));
        for (uint64_t a = o.first; a < o.second; ++a)
        {
          const Block& A = layer.blockOf(a);
          if (A.hi[axis] != S - 1)
            continue;
          for (uint64_t b = first; b < last; ++b)
          {
            const Block& B = current.blockOf(b);
            if (B.lo[axis] == 0 && A.label != B.label && faceBoundsMeet(A, B, axis))
              see(A, B, touchAcross(layer.rowsOf(a), current.rowsOf(b), axis));
          }
        }
      };
      for (uint64_t c = begin; c < end; ++c)
      {
        const uint64_t cell = uint64_t(cz) * layerCells + c;
        const auto range = v.cellBlocks(uint32_t(cell));
        if (range.first == range.second)
          continue;
        for (uint64_t a = range.first; a < range.second; ++a)
        {
          const Block& A = current.blockOf(a);
          for (uint64_t b = a + 1; b < range.second; ++b)
          {
            const Block& B = current.blockOf(b);
            if (A.label != B.label && boundsMeet(A, B))
              see(A, B, touchWithin(current.rowsOf(a), current.rowsOf(b)));
          }
        }
        const uint64_t cx = c % nx, cy = c / nx;
        if (cx > 0)
          across(current, cell - 1, range.first, range.second, 0);
        if (cy > 0)
          across(current, cell - nx, range.first, range.second, 1);
        if (cz > 0)
          across(previous, cell - layerCells, range.first, range.second, 2);
      }
      sortUnique(local);
      std::lock_guard<std::mutex> lock(merge);
      found.insert(found.end(), local.begin(), local.end());
    });
    sortUnique(found);
    std::swap(previous, current);
  }
  result.reserve(found.size());
  for (const uint64_t p : found)
    result.push_back({ { uint32_t(p >> 32), uint32_t(p & 0xFFFFFFFFu) } });
  return result;
}

} // namespace svdag
