// Random-access decoding of sub-boxes, slices, planes and label masks (svdag/RandomAccess.h).
#include "svdag/RandomAccess.h"

#include "svdag/Decoder.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <new>
#include <stdexcept>
#include <string>

namespace svdag
{
namespace
{
constexpr uint32_t S = layout::CELL_SIZE; // 16
constexpr uint32_t NoLabel = UINT32_MAX;

std::string boxText(const Box& b)
{
  std::string s = "(";
  for (int i = 0; i < 6; ++i)
    s += std::to_string(b[i]) + (i < 5 ? ", " : ")");
  return s;
}

// Intersection of two inclusive boxes; empty when some min exceeds its max.
Box intersect(const Box& a, const Box& b)
{
  Box r;
  for (int i = 0; i < 3; ++i)
  {
    r[2 * i] = std::max(a[2 * i], b[2 * i]);
    r[2 * i + 1] = std::min(a[2 * i + 1], b[2 * i + 1]);
  }
  return r;
}

bool empty(const Box& b)
{
  return b[0] > b[1] || b[2] > b[3] || b[4] > b[5];
}

// The linear indices of the cells a non-empty box inside the volume touches.
std::vector<uint32_t> cellsOf(const Volume& v, const Box& box)
{
  const auto n = v.geometry.cellCounts();
  std::vector<uint32_t> cells;
  const uint64_t count = uint64_t(box[1] / S - box[0] / S + 1) * uint64_t(box[3] / S - box[2] / S + 1) *
    uint64_t(box[5] / S - box[4] / S + 1);
  cells.reserve(size_t(count));
  for (int32_t cz = box[4] / int32_t(S); cz <= box[5] / int32_t(S); ++cz)
    for (int32_t cy = box[2] / int32_t(S); cy <= box[3] / int32_t(S); ++cy)
      for (int32_t cx = box[0] / int32_t(S); cx <= box[1] / int32_t(S); ++cx)
        cells.push_back(uint32_t(cx) + uint32_t(n[0]) * (uint32_t(cy) + uint32_t(n[1]) * uint32_t(cz)));
  return cells;
}

// The cell's voxel box (inclusive, volume coordinates), clipped to the volume.
Box cellBox(const Volume& v, uint32_t cell)
{
  const auto n = v.geometry.cellCounts();
  const auto& d = v.geometry.dims;
  const int32_t x = int32_t(cell % uint32_t(n[0]) * S);
  const int32_t y = int32_t(cell / uint32_t(n[0]) % uint32_t(n[1]) * S);
  const int32_t z = int32_t(cell / (uint32_t(n[0]) * uint32_t(n[1])) * S);
  return { { x, std::min<int32_t>(x + int32_t(S) - 1, d[0] - 1), y,
    std::min<int32_t>(y + int32_t(S) - 1, d[1] - 1), z,
    std::min<int32_t>(z + int32_t(S) - 1, d[2] - 1) } };
}

// Box of a block in volume coordinates (its tight bounds).
Box blockBox(const Block& blk, const Box& cell)
{
  return { { cell[0] + blk.lo[0], cell[0] + blk.hi[0], cell[2] + blk.lo[1], cell[2] + blk.hi[1],
    cell[4] + blk.lo[2], cell[4] + blk.hi[2] } };
}

// Visits, for every cell the box touches, each block whose bounds meet the box (and, with
// labelIndex != NoLabel, only that label's block): f(block index, block, part of the box it
// covers, cell-local occupancy valid inside that part). Cells run in parallel; different cells
// cover different voxels, so the callbacks of two threads never write the same output.
template <typename F>
void forEachBlockIn(const Volume& v, const Box& box, uint32_t labelIndex, const ParallelFor& parallel, F&& f)
{
  if (v.blockCount == 0 || empty(box))
    return;
  const std::vector<uint32_t> cells = cellsOf(v, box);
  parallel(0, cells.size(), 1, [&](uint64_t begin, uint64_t end) {
    std::vector<uint8_t> occ(S * S * S);
    for (uint64_t c = begin; c < end; ++c)
    {
      const Box cb = cellBox(v, cells[c]);
      const auto range = v.cellBlocks(cells[c]);
      for (uint64_t b = range.first; b < range.second; ++b)
      {
        const Block blk = v.block(b);
        if (labelIndex != NoLabel && blk.label != labelIndex)
          continue;
        const Box part = intersect(blockBox(blk, cb), box);
        if (empty(part))
          continue;
        const std::array<uint32_t, 3> lo{ { uint32_t(part[0] - cb[0]), uint32_t(part[2] - cb[2]),
          uint32_t(part[4] - cb[4]) } };
        const std::array<uint32_t, 3> hi{ { uint32_t(part[1] - cb[0]), uint32_t(part[3] - cb[2]),
          uint32_t(part[5] - cb[4]) } };
        occupancyInBox(v, b, lo, hi, occ.data());
        f(blk, cb, part, occ.data());
      }
    }
  });
}

// Fills the cell-local box lo..hi clipped to the cube (x0, y0, z0) + size with `value`.
inline void fillClipped(uint8_t* out, uint32_t x0, uint32_t y0, uint32_t z0, uint32_t size,
  const std::array<uint32_t, 3>& lo, const std::array<uint32_t, 3>& hi, uint8_t value)
{
  const uint32_t xa = std::max(x0, lo[0]), xb = std::min(x0 + size - 1, hi[0]);
  const uint32_t ya = std::max(y0, lo[1]), yb = std::min(y0 + size - 1, hi[1]);
  const uint32_t za = std::max(z0, lo[2]), zb = std::min(z0 + size - 1, hi[2]);
  for (uint32_t z = za; z <= zb; ++z)
    for (uint32_t y = ya; y <= yb; ++y)
      std::memset(out + xa + S * (y + S * z), value, xb - xa + 1);
}

inline bool meets(uint32_t x0, uint32_t y0, uint32_t z0, uint32_t size,
  const std::array<uint32_t, 3>& lo, const std::array<uint32_t, 3>& hi)
{
  return x0 <= hi[0] && x0 + size > lo[0] && y0 <= hi[1] && y0 + size > lo[1] && z0 <= hi[2] &&
    z0 + size > lo[2];
}

// Fills the whole output of `count` values with the background, in the output's own type (one
// switch for the whole buffer rather than one per value).
void fillBackground(const Volume& v, void* out, uint64_t count)
{
  if (count == 0)
    return;
  scalarStore(v.scalarType, out, 0, v.background);
  const size_t size = size_t(scalarSize(v.scalarType));
  uint8_t* bytes = static_cast<uint8_t*>(out);
  // Doubling copies: the pattern of one value repeated.
  uint64_t done = 1;
  while (done < count)
  {
    const uint64_t n = std::min(done, count - done);
    std::memcpy(bytes + done * size, bytes, size_t(n) * size);
    done += n;
  }
}
} // namespace

Box volumeBox(const Volume& v)
{
  const auto& d = v.geometry.dims;
  return { { 0, d[0] - 1, 0, d[1] - 1, 0, d[2] - 1 } };
}

void checkBox(const Volume& v, const Box& box, const char* what)
{
  if (empty(box))
    throw std::invalid_argument(std::string(what) + ": the box " + boxText(box) +
      " is empty (a minimum above its maximum)");
  const Box whole = volumeBox(v);
  for (int i = 0; i < 3; ++i)
  {
    if (box[2 * i] < 0 || box[2 * i + 1] > whole[2 * i + 1])
      throw std::out_of_range(std::string(what) + ": the box " + boxText(box) +
        " is not inside the volume " + boxText(whole));
  }
}

uint64_t boxVoxels(const Box& box)
{
  if (empty(box))
    return 0;
  uint64_t n = 1;
  for (int i = 0; i < 3; ++i)
  {
    if (__builtin_mul_overflow(n, uint64_t(int64_t(box[2 * i + 1]) - box[2 * i] + 1), &n))
      return UINT64_MAX;
  }
  return n;
}

uint64_t boxBytes(const Box& box, uint64_t valueBytes)
{
  uint64_t bytes = 0;
  return __builtin_mul_overflow(boxVoxels(box), valueBytes, &bytes) ? UINT64_MAX : bytes;
}

uint64_t layerSlicesBytes(const Volume& v, uint64_t slices)
{
  const auto& d = v.geometry.dims;
  uint64_t bytes = 0;
  if (__builtin_mul_overflow(uint64_t(std::max(d[0], 0)), uint64_t(std::max(d[1], 0)), &bytes) ||
    __builtin_mul_overflow(bytes, slices * sizeof(uint32_t), &bytes))
    return UINT64_MAX;
  return bytes;
}

void checkOutputMemory(uint64_t bytes, const std::string& what)
{
  // Half the address space at most: vtkIdType, ptrdiff_t and numpy's sizes are signed.
  const uint64_t addressable = uint64_t(std::numeric_limits<std::ptrdiff_t>::max());
  const std::string needs =
    what + " needs " + std::to_string(bytes) + " bytes (" + formatBytes(bytes) + ")";
  if (bytes > addressable)
    throw std::length_error(needs + ", more than the address space");
  const uint64_t memory = physicalMemoryBytes();
  if (memory > 0 && bytes > memory)
    throw std::length_error(
      needs + ", more than this machine's " + formatBytes(memory) + " of memory");
}

Box sliceBox(const Volume& v, int axis, int32_t index)
{
  if (axis < 0 || axis > 2)
    throw std::invalid_argument(
      "slice: axis must be 0 (x), 1 (y) or 2 (z), not " + std::to_string(axis));
  const int32_t n = v.geometry.dims[axis];
  if (index < 0 || index >= n)
    throw std::out_of_range("slice: index " + std::to_string(index) + " along " +
      std::string(1, "xyz"[axis]) + " is outside the volume (0 .. " + std::to_string(n - 1) + ")");
  Box box = volumeBox(v);
  box[2 * axis] = box[2 * axis + 1] = index;
  return box;
}

void occupancyInBox(const Volume& v, uint64_t blockIndex, const std::array<uint32_t, 3>& lo,
  const std::array<uint32_t, 3>& hi, uint8_t* out)
{
  // Volume::occupancy restricted to a box: octants that miss it are skipped before their
  // references are even read, which is what makes a thin slice cheap.
  const uint32_t rootRef = v.block(blockIndex).root;
  const bool rootInv = layout::refComplement(rootRef);
  const uint64_t rootOff = layout::refTarget(rootRef);
  const uint32_t rootHeader = Volume::nodeHeaderAndFlags(v.roots, rootOff);
  const uint32_t rootMixed = layout::nodeMixedMask(rootHeader);
  for (uint32_t o = 0; o < 8; ++o)
  {
    const uint32_t x0 = (o & 1) * 8, y0 = ((o >> 1) & 1) * 8, z0 = ((o >> 2) & 1) * 8;
    if (!meets(x0, y0, z0, 8, lo, hi))
      continue;
    if (!(rootMixed & (1u << o)))
    {
      const bool full = ((layout::nodeFullMask(rootHeader) >> o) & 1u) != rootInv;
      fillClipped(out, x0, y0, z0, 8, lo, hi, full ? 1 : 0);
      continue;
    }
    bool midInv = rootInv;
    const uint64_t midOff = v.midOfRoot(rootOff, rootHeader, layout::childRank(rootMixed, o), midInv);
    const uint32_t midHeader = Volume::nodeHeaderAndFlags(v.mids, midOff);
    const uint32_t midMixed = layout::nodeMixedMask(midHeader);
    for (uint32_t c = 0; c < 8; ++c)
    {
      const uint32_t x1 = x0 + (c & 1) * 4, y1 = y0 + ((c >> 1) & 1) * 4,
                     z1 = z0 + ((c >> 2) & 1) * 4;
      if (!meets(x1, y1, z1, 4, lo, hi))
        continue;
      if (!(midMixed & (1u << c)))
      {
        const bool full = ((layout::nodeFullMask(midHeader) >> c) & 1u) != midInv;
        fillClipped(out, x1, y1, z1, 4, lo, hi, full ? 1 : 0);
        continue;
      }
      uint64_t mask = v.leafOfMid(midOff, midHeader, layout::childRank(midMixed, c));
      if (midInv)
        mask = ~mask;
      const uint32_t xa = std::max(x1, lo[0]), xb = std::min(x1 + 3, hi[0]);
      const uint32_t ya = std::max(y1, lo[1]), yb = std::min(y1 + 3, hi[1]);
      const uint32_t za = std::max(z1, lo[2]), zb = std::min(z1 + 3, hi[2]);
      for (uint32_t z = za; z <= zb; ++z)
        for (uint32_t y = ya; y <= yb; ++y)
          for (uint32_t x = xa; x <= xb; ++x)
            out[x + S * (y + S * z)] =
              uint8_t((mask >> layout::leafBit(x - x1, y - y1, z - z1)) & 1u);
    }
  }
}

void decodeCellLabels(
  const Volume& v, uint64_t cell, uint32_t empty, uint32_t* out4096, uint8_t* scratch4096)
{
  std::fill(out4096, out4096 + S * S * S, empty);
  const auto range = v.cellBlocks(cell);
  for (uint64_t b = range.first; b < range.second; ++b)
  {
    const Block blk = v.block(b);
    occupancyInBox(v, b, { { blk.lo[0], blk.lo[1], blk.lo[2] } },
      { { blk.hi[0], blk.hi[1], blk.hi[2] } }, scratch4096);
    // The blocks of a cell are disjoint: each solid voxel is written once.
    for (uint32_t z = blk.lo[2]; z <= blk.hi[2]; ++z)
      for (uint32_t y = blk.lo[1]; y <= blk.hi[1]; ++y)
        for (uint32_t x = blk.lo[0]; x <= blk.hi[0]; ++x)
        {
          const size_t i = x + S * (y + S * z);
          if (scratch4096[i])
            out4096[i] = blk.label;
        }
  }
}

void decodeLayerLabels(const Volume& v, int32_t cz, uint32_t empty, std::vector<uint32_t>& out,
  const ParallelFor& parallel)
{
  const auto& d = v.geometry.dims;
  const auto n = v.geometry.cellCounts();
  const size_t nx = size_t(d[0]), ny = size_t(d[1]);
  const int32_t z0 = cz * int32_t(S);
  const size_t lz = size_t(std::min<int32_t>(int32_t(S), d[2] - z0));
  out.assign(nx * ny * lz, empty);
  const uint32_t perLayer = uint32_t(n[0]) * uint32_t(n[1]);
  parallel(0, perLayer, 1, [&](uint64_t begin, uint64_t end) {
    std::vector<uint8_t> occ(S * S * S);
    std::vector<uint32_t> labels(S * S * S);
    for (uint64_t c = begin; c < end; ++c)
    {
      const uint32_t cell = uint32_t(cz) * perLayer + uint32_t(c);
      const size_t cx = size_t(c % uint32_t(n[0])) * S, cy = size_t(c / uint32_t(n[0])) * S;
      decodeCellLabels(v, cell, empty, labels.data(), occ.data());
      // The cell's part inside the volume (edge cells are partial).
      const size_t ex = std::min<size_t>(S, nx - cx), ey = std::min<size_t>(S, ny - cy);
      for (size_t z = 0; z < lz; ++z)
        for (size_t y = 0; y < ey; ++y)
          for (size_t x = 0; x < ex; ++x)
            out[cx + x + nx * (cy + y + ny * z)] = labels[x + S * (y + S * z)];
    }
  });
}

void decodeBox(const Volume& v, const Box& box, void* out, const ParallelFor& parallel)
{
  checkBox(v, box, "decodeBox");
  fillBackground(v, out, boxVoxels(box));
  const ScalarType type = v.scalarType;
  const size_t nx = size_t(box[1] - box[0] + 1), ny = size_t(box[3] - box[2] + 1);
  forEachBlockIn(v, box, NoLabel, parallel,
    [&](const Block& blk, const Box& cb, const Box& part, const uint8_t* occ) {
      const uint64_t value = v.labels[blk.label].value;
      for (int32_t z = part[4]; z <= part[5]; ++z)
        for (int32_t y = part[2]; y <= part[3]; ++y)
        {
          // Row starts in the cell and in the output; x is relative to the part's first voxel.
          const uint8_t* row = occ + S * (size_t(y - cb[2]) + S * size_t(z - cb[4])) + size_t(part[0] - cb[0]);
          const size_t base = nx * (size_t(y - box[2]) + ny * size_t(z - box[4])) + size_t(part[0] - box[0]);
          for (size_t x = 0; x <= size_t(part[1] - part[0]); ++x)
            if (row[x])
              scalarStore(type, out, base + x, value);
        }
    });
}

std::vector<uint8_t> decodeBox(const Volume& v, const Box& box, const ParallelFor& parallel)
{
  checkBox(v, box, "decodeBox");
  const uint64_t bytes = boxBytes(box, uint64_t(scalarSize(v.scalarType)));
  const std::string what = "decoding " + std::to_string(boxVoxels(box)) + " " +
    scalarName(v.scalarType) + " voxels";
  checkOutputMemory(bytes, what);
  std::vector<uint8_t> out;
  try
  {
    out.resize(size_t(bytes));
  }
  catch (const std::bad_alloc&)
  {
    throw std::length_error(what + " needs " + formatBytes(bytes) + ", not available");
  }
  decodeBox(v, box, out.data(), parallel);
  return out;
}

void decodeMask(
  const Volume& v, uint32_t labelIndex, const Box& box, uint8_t* out, const ParallelFor& parallel)
{
  checkBox(v, box, "decodeMask");
  if (labelIndex >= v.labels.size())
    throw std::out_of_range("decodeMask: label index " + std::to_string(labelIndex) +
      " is not in the label table of " + std::to_string(v.labels.size()) + " labels");
  std::memset(out, 0, size_t(boxVoxels(box)));
  // Only the cells of the label's own bounds can hold it.
  const Box part = intersect(box, Box(v.labels[labelIndex].bounds));
  const size_t nx = size_t(box[1] - box[0] + 1), ny = size_t(box[3] - box[2] + 1);
  forEachBlockIn(v, part, labelIndex, parallel,
    [&](const Block&, const Box& cb, const Box& p, const uint8_t* occ) {
      for (int32_t z = p[4]; z <= p[5]; ++z)
        for (int32_t y = p[2]; y <= p[3]; ++y)
        {
          const uint8_t* row = occ + S * (size_t(y - cb[2]) + S * size_t(z - cb[4])) + size_t(p[0] - cb[0]);
          uint8_t* dst = out + nx * (size_t(y - box[2]) + ny * size_t(z - box[4])) + size_t(p[0] - box[0]);
          std::memcpy(dst, row, size_t(p[1] - p[0] + 1));
        }
    });
}

void checkPlaneSampling(const Volume& v, const PlaneSampling& p)
{
  for (int i = 0; i < 3; ++i)
  {
    if (!std::isfinite(p.origin[i]) || !std::isfinite(p.uStep[i]) || !std::isfinite(p.vStep[i]))
      throw std::invalid_argument("resamplePlane: the origin and steps must be finite");
  }
  if (p.nu < 0 || p.nv < 0)
    throw std::invalid_argument("resamplePlane: the output size " + std::to_string(p.nu) + " x " +
      std::to_string(p.nv) + " is negative");
  uint64_t bytes = 0;
  if (__builtin_mul_overflow(uint64_t(p.nu) * uint64_t(p.nv), uint64_t(scalarSize(v.scalarType)), &bytes))
    bytes = UINT64_MAX;
  checkOutputMemory(bytes, "resampling a " + std::to_string(p.nu) + " x " + std::to_string(p.nv) +
      " plane of " + scalarName(v.scalarType) + " labels");
}

void resamplePlane(const Volume& v, const PlaneSampling& p, void* out, const ParallelFor& parallel)
{
  checkPlaneSampling(v, p);
  const uint64_t count = uint64_t(p.nu) * uint64_t(p.nv);
  if (count == 0)
    return;
  const auto& d = v.geometry.dims;
  const auto n = v.geometry.cellCounts();
  const ScalarType type = v.scalarType;
  // Tiles of T x T samples: neighbouring samples fall in the same few cells, so each tile
  // expands a cell once (into label indices) and then reads it per sample.
  constexpr int32_t T = 32;
  constexpr size_t CacheSize = 16;
  const int32_t tilesU = (p.nu + T - 1) / T, tilesV = (p.nv + T - 1) / T;
  parallel(0, uint64_t(tilesU) * uint64_t(tilesV), 1, [&](uint64_t begin, uint64_t end) {
    std::vector<uint32_t> cacheCell(CacheSize, NoLabel);
    std::vector<uint32_t> cacheLabels(CacheSize * S * S * S);
    std::vector<uint8_t> occ(S * S * S);
    size_t nextSlot = 0;
    auto cellLabels = [&](uint32_t cell) -> const uint32_t* {
      for (size_t s = 0; s < CacheSize; ++s)
        if (cacheCell[s] == cell)
          return cacheLabels.data() + s * S * S * S;
      const size_t s = nextSlot;
      nextSlot = (nextSlot + 1) % CacheSize;
      cacheCell[s] = cell;
      uint32_t* labels = cacheLabels.data() + s * S * S * S;
      decodeCellLabels(v, cell, NoLabel, labels, occ.data());
      return labels;
    };
    for (uint64_t t = begin; t < end; ++t)
    {
      const int32_t ta = int32_t(t % uint64_t(tilesU)) * T, tb = int32_t(t / uint64_t(tilesU)) * T;
      for (int32_t b = tb; b < std::min(tb + T, p.nv); ++b)
        for (int32_t a = ta; a < std::min(ta + T, p.nu); ++a)
        {
          const size_t index = size_t(a) + size_t(p.nu) * size_t(b);
          uint64_t value = v.background;
          int32_t voxel[3];
          bool inside = true;
          for (int i = 0; i < 3 && inside; ++i)
          {
            // The documented nearest voxel: floor(p + 0.5), compared as doubles so that far
            // away samples cannot overflow an integer.
            const double c = std::floor(p.origin[i] + a * p.uStep[i] + b * p.vStep[i] + 0.5);
            inside = c >= 0 && c < double(d[i]);
            voxel[i] = inside ? int32_t(c) : 0;
          }
          if (inside && v.blockCount > 0)
          {
            const uint32_t cell = uint32_t(voxel[0]) / S +
              uint32_t(n[0]) * (uint32_t(voxel[1]) / S + uint32_t(n[1]) * (uint32_t(voxel[2]) / S));
            const uint32_t label = cellLabels(cell)[uint32_t(voxel[0]) % S +
              S * (uint32_t(voxel[1]) % S + S * (uint32_t(voxel[2]) % S))];
            if (label != NoLabel)
              value = v.labels[label].value;
          }
          scalarStore(type, out, index, value);
        }
    }
  });
}

} // namespace svdag
