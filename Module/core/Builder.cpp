#include "svdag/Builder.h"

#include "BuildPools.h"
#include "svdag/Compact.h"
#include "svdag/LeafSymmetry.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <numeric>
#include <stdexcept>
#include <string>

namespace svdag
{
namespace
{
constexpr uint32_t S = layout::CELL_SIZE; // 16
constexpr uint32_t LeavesPerCell = 64;    // 4^3 leaves of 4^3 voxels

using bits::writeBits;
using build::bitWidth;
using build::mix64;
using build::GrowArray;
using build::PackedNodePool;

class LeafPool
{
public:
  uint32_t intern(uint64_t mask)
  {
    return table.intern(
      mix64(mask), [&](uint32_t id) { return masks[id] == mask; },
      [&]() {
        if (masks.size() >= 0x7FFFFFFFu)
          throw std::length_error("SVDAG too large: more than 2^31 leaves");
        masks.push_back(mask);
        return uint32_t(masks.size() - 1);
      },
      [&](const auto& place) {
        for (uint32_t id = 0; id < masks.size(); ++id)
          place(id, mix64(masks[id]));
      });
  }
  // The reference (Layout.h: index, symmetry, complement) to a mixed mask whose class's stored
  // mask is read under code = symmetry << 1 | complement (canonicalLeaf), the class interned.
  uint32_t reference(uint64_t mask, uint32_t code)
  {
    const uint64_t stored =
      leafUnderSymmetry(inverseLeafSymmetry(code >> 1), (code & 1u) ? ~mask : mask);
    return layout::leafRef(intern(stored), code >> 1, code & 1u);
  }
  size_t size() const { return masks.size(); }
  // Width of a reference to any leaf so far.
  uint32_t refBits() const
  {
    return bitWidth(masks.empty() ? 0 : masks.size() - 1) + 1 + layout::LEAF_SYMMETRY_BITS;
  }
  void releaseTable() { table.clear(); }
  std::vector<uint64_t> take() { return masks.takeVector(); }

private:
  GrowArray<uint64_t> masks;
  build::IdTable<0> table;
};

// Child state while assembling a node: empty, full, or mixed with a reference.
enum : uint32_t
{
  ChildEmpty = 0,
  ChildFull = 1,
  ChildMixed = 2
};

// Makes a node canonical (voxel (0,0,0) empty) and returns whether it was complemented.
bool canonicalize(uint32_t& mixed, uint32_t& full, uint32_t* refs)
{
  const bool firstSolid = (full & 1u) || ((mixed & 1u) && (refs[0] & 1u));
  if (!firstSolid)
    return false;
  full = ~(mixed | full) & 0xFFu;
  for (uint32_t r = 0; r < build::popcount8(mixed); ++r)
    refs[r] ^= 1u;
  return true;
}

// One label's voxels inside one cell (Builder.h). Its codes come from canonicalLeaf's search in
// the parallel scan, so that the ordered merge only undoes one symmetry and interns.
using CellLabel = CellOccupancy;

void canonicalizeLeaves(CellLabel& cl)
{
  for (uint32_t i = 0; i < LeavesPerCell; ++i)
  {
    const uint64_t m = cl.masks[i];
    if (m == 0 || m == ~uint64_t(0))
      continue;
    const CanonicalLeaf c = canonicalLeaf(m);
    cl.codes[i] = uint8_t((c.symmetry << 1) | c.complement);
  }
}

struct CellResult
{
  std::vector<CellLabel> labels; // by label value once the scan is done
};

template <class T>
void scanCell(const T* slab, int64_t rowStride, int64_t sliceStride, uint32_t nx, uint32_t ny,
  uint32_t nz, T background, const std::vector<uint64_t>& excluded, CellResult& out)
{
  out.labels.clear();
  // Local label slots; slot -1 marks a value left out (background or excluded).
  T cachedValue = background;
  int cachedSlot = -1;
  std::vector<std::pair<T, int>> seen;
  for (uint32_t z = 0; z < nz; ++z)
  {
    for (uint32_t y = 0; y < ny; ++y)
    {
      const T* row = slab + z * sliceStride + y * rowStride;
      const uint32_t leafYZ = 4 * (y >> 2) + 16 * (z >> 2);
      const uint32_t bitYZ = 4 * (y & 3) + 16 * (z & 3);
      // Runs of one value are set a row of up to 16 bits at a time: labels come in runs, and a
      // per-voxel lookup and bit set were most of the build time.
      for (uint32_t x = 0; x < nx;)
      {
        const T v = row[x];
        uint32_t end = x + 1;
        while (end < nx && row[end] == v)
          ++end;
        if (v != cachedValue)
        {
          cachedValue = v;
          cachedSlot = -2;
          for (const auto& s : seen)
          {
            if (s.first == v)
            {
              cachedSlot = s.second;
              break;
            }
          }
          if (cachedSlot == -2)
          {
            const uint64_t pattern = uint64_t(int64_t(v));
            const bool leftOut =
              std::binary_search(excluded.begin(), excluded.end(), uint64_t(pattern));
            cachedSlot = leftOut ? -1 : int(out.labels.size());
            seen.emplace_back(v, cachedSlot);
            if (!leftOut)
            {
              out.labels.emplace_back();
              CellLabel& l = out.labels.back();
              l.value = pattern;
              std::memset(l.masks, 0, sizeof(l.masks));
            }
          }
        }
        if (cachedSlot >= 0)
        {
          // Bits x .. end-1 of the cell row, four per leaf column.
          const uint32_t run = ((1u << end) - 1u) & ~((1u << x) - 1u);
          uint64_t* masks = out.labels[size_t(cachedSlot)].masks + leafYZ;
          for (uint32_t lx = x >> 2; lx <= (end - 1) >> 2; ++lx)
            masks[lx] |= uint64_t((run >> (4 * lx)) & 0xFu) << bitYZ;
        }
        x = end;
      }
    }
  }
}

// Tight cell-local bounds of a set of leaf masks, from per-axis projections of each leaf.
void leafBounds(const uint64_t* masks, std::array<uint8_t, 3>& lo, std::array<uint8_t, 3>& hi)
{
  uint32_t proj[3] = { 0, 0, 0 }; // bit c set if any voxel with that coordinate (0..15)
  for (uint32_t l = 0; l < LeavesPerCell; ++l)
  {
    const uint64_t m = masks[l];
    if (!m)
      continue;
    const uint32_t lx = l & 3, ly = (l >> 2) & 3, lz = l >> 4;
    uint64_t t = m | (m >> 32);
    t |= t >> 16; // low 16 bits: x + 4 y over all z
    uint32_t px = uint32_t(t | (t >> 4) | (t >> 8) | (t >> 12)) & 0xFu;
    uint32_t py = 0, pz = 0;
    for (uint32_t c = 0; c < 4; ++c)
    {
      py |= ((t >> (4 * c)) & 0xFu) ? (1u << c) : 0u;
      pz |= ((m >> (16 * c)) & 0xFFFFu) ? (1u << c) : 0u;
    }
    proj[0] |= px << (4 * lx);
    proj[1] |= py << (4 * ly);
    proj[2] |= pz << (4 * lz);
  }
  for (int a = 0; a < 3; ++a)
  {
    lo[a] = uint8_t(__builtin_ctz(proj[a]));
    hi[a] = uint8_t(31 - __builtin_clz(proj[a]));
  }
}

// A block until finish() knows the final field widths: bit-packed fields, the label and root
// ones as wide as the ids so far need.
enum PendingField : uint32_t
{
  PendingCell,
  PendingBox,   // lo x, y, z then hi x, y, z, 4 bits each (the record's bounds field)
  PendingLabel, // build-time label id
  PendingRoot,  // root id << 1 | complement
  PendingFieldCount
};
using PendingBlocks = build::PackedRecords<PendingFieldCount>;

} // namespace

struct Builder::Impl
{
  Geometry geometry;
  ScalarType type;
  BuildOptions options;
  ParallelFor parallel;
  std::array<int32_t, 3> cells;
  int32_t nextZ = 0;
  // addBlock's mode: blocks given as occupancy, the last one's cell and label value.
  bool blockMode = false;
  uint32_t lastBlockCell = 0;
  uint64_t lastBlockValue = 0;

  // Scan results of one row of cells: a whole slab's would be a large share of the state.
  std::vector<CellResult> rowResults;
  LeafPool leaves;
  PackedNodePool mids;  // child refs: leaf ids, already the final stream
  PackedNodePool roots; // child refs: mid ids (finish() turns them into mid stream offsets)
  PendingBlocks blocks;
  std::vector<LabelInfo> labels; // build-time ids, first-seen order
  // Label value -> build-time id, through the same exact-compare hash table.
  build::IdTable<0> labelTable;

  uint32_t labelId(uint64_t value)
  {
    return labelTable.intern(
      mix64(value), [&](uint32_t id) { return labels[id].value == value; },
      [&]() {
        LabelInfo info;
        info.value = value;
        info.bounds = { { INT32_MAX, INT32_MIN, INT32_MAX, INT32_MIN, INT32_MAX, INT32_MIN } };
        labels.push_back(info);
        return uint32_t(labels.size() - 1);
      },
      [&](const auto& place) {
        for (uint32_t id = 0; id < labels.size(); ++id)
          place(id, mix64(labels[id].value));
      });
  }

  // Interns the occupancy of one label in one cell and records the block.
  void addBlock(uint32_t cell, const std::array<int32_t, 3>& cellOrigin, const CellLabel& cl)
  {
    PendingBlocks::Record b;
    b[PendingCell] = cell;
    std::array<uint8_t, 3> lo, hi;
    leafBounds(cl.masks, lo, hi);
    b[PendingBox] = 0;
    for (int a = 0; a < 3; ++a)
      b[PendingBox] |= (uint32_t(lo[a]) << (4 * a)) | (uint32_t(hi[a]) << (12 + 4 * a));
    uint64_t voxels = 0;
    uint32_t rootMixed = 0, rootFull = 0, rootRefs[8];
    for (uint32_t o = 0; o < 8; ++o)
    {
      const uint32_t ox = o & 1, oy = (o >> 1) & 1, oz = o >> 2;
      uint32_t mixed = 0, full = 0, refs[8], n = 0;
      for (uint32_t c = 0; c < 8; ++c)
      {
        const uint32_t lx = 2 * ox + (c & 1), ly = 2 * oy + ((c >> 1) & 1), lz = 2 * oz + (c >> 2);
        uint64_t m = cl.masks[lx + 4 * ly + 16 * lz];
        if (m == 0)
          continue;
        if (m == ~uint64_t(0))
        {
          full |= 1u << c;
          voxels += 64;
          continue;
        }
        voxels += uint64_t(__builtin_popcountll(m));
        mixed |= 1u << c;
        const uint32_t leaf = lx + 4 * ly + 16 * lz;
        refs[n++] = leaves.reference(m, cl.codes[leaf]);
      }
      if (!mixed && !full)
        continue;
      if (!mixed && full == 0xFFu)
      {
        rootFull |= 1u << o;
        continue;
      }
      const uint32_t complement = canonicalize(mixed, full, refs) ? 1u : 0u;
      mids.widenTo(leaves.refBits());
      rootRefs[build::popcount8(rootMixed)] = (mids.intern(mixed | (full << 8), refs) << 1) | complement;
      rootMixed |= 1u << o;
    }
    const uint32_t complement = canonicalize(rootMixed, rootFull, rootRefs) ? 1u : 0u;
    roots.widenTo(bitWidth(mids.size() ? mids.size() - 1 : 0) + 1);
    b[PendingRoot] = (roots.intern(rootMixed | (rootFull << 8), rootRefs) << 1) | complement;
    b[PendingLabel] = labelId(cl.value);
    LabelInfo& info = labels[b[PendingLabel]];
    info.voxels += voxels;
    for (int a = 0; a < 3; ++a)
    {
      info.bounds[2 * a] = std::min(info.bounds[2 * a], cellOrigin[a] + int32_t(lo[a]));
      info.bounds[2 * a + 1] = std::max(info.bounds[2 * a + 1], cellOrigin[a] + int32_t(hi[a]));
    }
    blocks.widenTo(PendingLabel, bitWidth(labels.size() - 1));
    blocks.widenTo(PendingRoot, bitWidth(roots.size() - 1) + 1);
    blocks.push_back(b);
  }
};

void Builder::addVolume(const Volume& input)
{
  Volume holder;
  const Volume& part = pooledView(input, holder);
  Impl& m = *impl;
  if (m.blockMode)
    throw std::logic_error("cannot append a volume to a builder given blocks");
  const auto& d = m.geometry.dims;
  const auto& pd = part.geometry.dims;
  if (m.nextZ % int32_t(S) != 0)
    throw std::logic_error("cannot append a volume after a partial slab (next z0 = " +
      std::to_string(m.nextZ) + ")");
  if (pd[0] != d[0] || pd[1] != d[1])
    throw std::invalid_argument("the appended volume is " + std::to_string(pd[0]) + " x " +
      std::to_string(pd[1]) + " voxels in x and y, not " + std::to_string(d[0]) + " x " +
      std::to_string(d[1]));
  if (int64_t(pd[2]) > int64_t(d[2]) - m.nextZ ||
    (pd[2] % int32_t(S) != 0 && m.nextZ + pd[2] != d[2]))
    throw std::logic_error("an appended volume of " + std::to_string(pd[2]) +
      " slices does not fit at z0 = " + std::to_string(m.nextZ) + " of " + std::to_string(d[2]) +
      " (only the last one may end inside a 16-slice slab)");
  if (part.scalarType != m.type)
    throw std::invalid_argument(std::string("the appended volume holds ") +
      scalarName(part.scalarType) + " labels, not " + scalarName(m.type));
  if (part.background != m.options.background)
    throw std::invalid_argument("the appended volume was built with another background label");
  const auto& excluded = m.options.excluded;
  std::vector<uint32_t> labelIds(part.labels.size());
  for (size_t i = 0; i < part.labels.size(); ++i)
  {
    if (std::binary_search(excluded.begin(), excluded.end(), part.labels[i].value))
      throw std::invalid_argument("the appended volume holds a label this builder excludes");
  }

  // Each pool is interned in the part's id order, which is the order its own scan first saw
  // the nodes: the ids of the merged pools are then the first-seen order of one scan over both.
  std::vector<uint32_t> leafIds(part.leaves.size());
  for (size_t i = 0; i < part.leaves.size(); ++i)
    leafIds[i] = m.leaves.intern(part.leaves[i]);

  // Node references in the part are bit offsets; offsets[k] is node k's, ascending.
  auto remapStream = [](const std::vector<uint32_t>& stream, uint64_t count, uint32_t refBits,
                       const auto& remapRef, const auto& intern, std::vector<uint32_t>& offsets,
                       std::vector<uint32_t>& ids) {
    offsets.resize(size_t(count));
    ids.resize(size_t(count));
    uint64_t at = 0;
    for (uint64_t k = 0; k < count; ++k)
    {
      offsets[k] = uint32_t(at);
      const uint32_t header = Volume::nodeHeader(stream, at);
      const uint32_t n = build::popcount8(layout::nodeMixedMask(header));
      uint32_t refs[8];
      for (uint32_t r = 0; r < n; ++r)
        refs[r] = remapRef(Volume::nodeChildRef(stream, at, r, refBits));
      ids[k] = intern(header, refs);
      at += layout::NODE_HEADER_BITS + uint64_t(n) * refBits;
    }
  };
  auto idAt = [](const std::vector<uint32_t>& offsets, const std::vector<uint32_t>& ids,
                uint32_t ref, const char* what) {
    const auto it = std::lower_bound(offsets.begin(), offsets.end(), ref >> 1);
    if (it == offsets.end() || *it != (ref >> 1))
      throw std::runtime_error(std::string("the appended volume has a ") + what +
        " reference that is not at a node start");
    return (ids[size_t(it - offsets.begin())] << 1) | (ref & 1u);
  };
  std::vector<uint32_t> midOffsets, midIds, rootOffsets, rootIds;
  remapStream(
    part.mids, part.midCount, part.widths.leafRefBits,
    [&](uint32_t ref) {
      if (layout::leafRefIndex(ref) >= leafIds.size())
        throw std::runtime_error("the appended volume has a leaf reference out of range");
      return layout::leafRef(leafIds[layout::leafRefIndex(ref)], layout::leafRefSymmetry(ref), ref & 1u);
    },
    [&](uint32_t header, const uint32_t* refs) {
      m.mids.widenTo(m.leaves.refBits());
      return m.mids.intern(header, refs);
    },
    midOffsets, midIds);
  remapStream(
    part.roots, part.rootCount, part.widths.midRefBits,
    [&](uint32_t ref) { return idAt(midOffsets, midIds, ref, "mid"); },
    [&](uint32_t header, const uint32_t* refs) {
      m.roots.widenTo(bitWidth(m.mids.size() ? m.mids.size() - 1 : 0) + 1);
      return m.roots.intern(header, refs);
    },
    rootOffsets, rootIds);
  std::vector<uint32_t>().swap(midOffsets);
  std::vector<uint32_t>().swap(midIds);

  for (size_t i = 0; i < part.labels.size(); ++i)
  {
    const LabelInfo& from = part.labels[i];
    labelIds[i] = m.labelId(from.value);
    LabelInfo& info = m.labels[labelIds[i]];
    info.voxels += from.voxels;
    for (int a = 0; a < 3; ++a)
    {
      const int32_t shift = a == 2 ? m.nextZ : 0;
      info.bounds[2 * a] = std::min(info.bounds[2 * a], from.bounds[2 * a] + shift);
      info.bounds[2 * a + 1] = std::max(info.bounds[2 * a + 1], from.bounds[2 * a + 1] + shift);
    }
  }
  m.blocks.widenTo(PendingLabel, bitWidth(m.labels.empty() ? 0 : m.labels.size() - 1));
  m.blocks.widenTo(PendingRoot, bitWidth(m.roots.size() ? m.roots.size() - 1 : 0) + 1);

  // The part's blocks are in (cell, label) order; its cells are a z-range of this volume's.
  const uint64_t cellShift =
    uint64_t(m.cells[0]) * uint64_t(m.cells[1]) * uint64_t(m.nextZ / int32_t(S));
  for (uint64_t i = 0; i < part.blockCount; ++i)
  {
    const Block b = part.block(i);
    if (b.label >= labelIds.size())
      throw std::runtime_error("the appended volume has a label index out of range");
    PendingBlocks::Record r;
    r[PendingCell] = uint32_t(b.cell + cellShift);
    r[PendingBox] = 0;
    for (int a = 0; a < 3; ++a)
      r[PendingBox] |= (uint32_t(b.lo[a]) << (4 * a)) | (uint32_t(b.hi[a]) << (12 + 4 * a));
    r[PendingLabel] = labelIds[b.label];
    r[PendingRoot] = idAt(rootOffsets, rootIds, b.root, "root");
    m.blocks.push_back(r);
  }
  m.nextZ += pd[2];
}

std::array<int32_t, 2> Builder::pieceZRange(int32_t depth, int piece, int pieces)
{
  if (pieces < 1 || piece < 0 || piece >= pieces || depth < 0)
    throw std::invalid_argument("piece " + std::to_string(piece) + " of " +
      std::to_string(pieces) + " of " + std::to_string(depth) + " slices does not exist");
  const int64_t slabs = (int64_t(depth) + SlabDepth - 1) / SlabDepth;
  if (piece >= slabs)
    return { { 0, 0 } };
  const int64_t count = std::min<int64_t>(pieces, slabs);
  const int64_t first = piece * (slabs / count) + std::min<int64_t>(piece, slabs % count);
  const int64_t n = slabs / count + (piece < slabs % count ? 1 : 0);
  return { { int32_t(first * SlabDepth),
    int32_t(std::min<int64_t>(depth, (first + n) * SlabDepth)) } };
}

Builder::Builder(
  const Geometry& geometry, ScalarType type, const BuildOptions& options, ParallelFor parallel)
  : impl(new Impl)
{
  const std::string problem = checkGeometry(geometry);
  if (!problem.empty())
    throw std::invalid_argument(problem);
  impl->geometry = geometry;
  impl->type = type;
  impl->options = options;
  // Background is left out like an excluded label; patterns are normalised to the type's width.
  auto& ex = impl->options.excluded;
  ex.push_back(options.background);
  for (auto& v : ex)
  {
    uint64_t tmp = 0;
    scalarStore(type, &tmp, 0, v);
    v = scalarLoad(type, &tmp, 0);
  }
  impl->options.background = ex.back();
  std::sort(ex.begin(), ex.end());
  ex.erase(std::unique(ex.begin(), ex.end()), ex.end());
  impl->parallel = parallel ? parallel : ParallelFor(sequentialFor);
  impl->cells = geometry.cellCounts();
  impl->blocks.widenTo(PendingCell, bitWidth(geometry.cellCount() - 1));
  impl->blocks.widenTo(PendingBox, layout::BLOCK_BOUNDS_BITS);
}

Builder::~Builder() = default;

int32_t Builder::nextSlab() const
{
  return impl->nextZ;
}

void Builder::addSlab(int32_t z0, int32_t nz, const void* data)
{
  Impl& m = *impl;
  if (m.blockMode)
    throw std::logic_error("cannot add slabs to a builder given blocks");
  const auto& d = m.geometry.dims;
  if (z0 != m.nextZ || nz != std::min<int32_t>(SlabDepth, d[2] - z0) || nz <= 0)
    throw std::logic_error("slab out of order: expected z0 = " + std::to_string(m.nextZ));
  const int64_t rowStride = d[0], sliceStride = int64_t(d[0]) * d[1];
  const uint32_t ncx = uint32_t(m.cells[0]);
  const ScalarType type = m.type;
  const uint64_t background = m.options.background;
  const auto& excluded = m.options.excluded;
  auto& results = m.rowResults;
  results.resize(ncx); // on the first slab: a builder given blocks never needs them
  const uint32_t cz = uint32_t(z0) / S;
  // One row of cells at a time: scanned in parallel, then merged in cell order so that ids and
  // block order depend on the data only.
  for (uint32_t cy = 0; cy < uint32_t(m.cells[1]); ++cy)
  {
    const uint32_t ny = std::min<uint32_t>(S, uint32_t(d[1]) - cy * S);
    m.parallel(0, ncx, 1, [&](uint64_t begin, uint64_t end) {
      for (uint64_t cx = begin; cx < end; ++cx)
      {
        const uint32_t nx = std::min<uint32_t>(S, uint32_t(d[0]) - uint32_t(cx) * S);
        const size_t origin = size_t(cx) * S + size_t(cy) * S * size_t(rowStride);
        switch (type)
        {
#define SVDAG_SCAN(Enum, T)                                                                        \
  case ScalarType::Enum:                                                                           \
    scanCell<T>(static_cast<const T*>(data) + origin, rowStride, sliceStride, nx, ny,              \
      uint32_t(nz), T(background), excluded, results[cx]);                                         \
    break;
          SVDAG_SCAN(Int8, int8_t)
          SVDAG_SCAN(UInt8, uint8_t)
          SVDAG_SCAN(Int16, int16_t)
          SVDAG_SCAN(UInt16, uint16_t)
          SVDAG_SCAN(Int32, int32_t)
          SVDAG_SCAN(UInt32, uint32_t)
          SVDAG_SCAN(Int64, int64_t)
          SVDAG_SCAN(UInt64, uint64_t)
#undef SVDAG_SCAN
        }
        auto& labels = results[cx].labels;
        for (CellLabel& cl : labels)
          canonicalizeLeaves(cl);
        // Blocks are interned in the order finish() writes them (by cell, then label value), so
        // the pools are in first-use order over the blocks: what a .svdag 3.0 file rebuilds.
        std::sort(labels.begin(), labels.end(), [type](const CellLabel& a, const CellLabel& b) {
          return scalarLess(type, a.value, b.value);
        });
      }
    });
    for (uint32_t cx = 0; cx < ncx; ++cx)
    {
      const uint32_t cell = cx + ncx * (cy + uint32_t(m.cells[1]) * cz);
      const std::array<int32_t, 3> origin{ { int32_t(cx * S), int32_t(cy * S), int32_t(cz * S) } };
      for (const CellLabel& cl : results[cx].labels)
        m.addBlock(cell, origin, cl);
    }
  }
  m.nextZ = z0 + nz;
}

void Builder::startBlocks()
{
  Impl& m = *impl;
  if (!m.blockMode && m.nextZ != 0)
    throw std::logic_error("cannot add blocks to a builder given slabs or volumes");
  m.blockMode = true;
}

void Builder::addBlock(uint32_t cell, const CellOccupancy& block)
{
  Impl& m = *impl;
  startBlocks();
  const bool first = m.blocks.size() == 0;
  if (uint64_t(cell) >= m.geometry.cellCount())
    throw std::logic_error("block in cell " + std::to_string(cell) + " outside the volume");
  if (!first &&
    (cell < m.lastBlockCell ||
      (cell == m.lastBlockCell && !scalarLess(m.type, m.lastBlockValue, block.value))))
    throw std::logic_error("blocks out of order: by cell, then by label value");
  m.lastBlockCell = cell;
  m.lastBlockValue = block.value;
  const uint32_t ncx = uint32_t(m.cells[0]), ncy = uint32_t(m.cells[1]);
  const std::array<int32_t, 3> origin{ { int32_t((cell % ncx) * S),
    int32_t((cell / ncx % ncy) * S), int32_t((cell / ncx / ncy) * S) } };
  m.addBlock(cell, origin, block);
}

Volume Builder::finish()
{
  return compacted(finishPooled());
}

Volume Builder::finishPooled()
{
  Impl& m = *impl;
  if (!m.blockMode && m.nextZ != m.geometry.dims[2])
    throw std::logic_error("missing slabs: next expected z0 = " + std::to_string(m.nextZ));
  // Lookups are over: free every table before the packed output is assembled.
  std::vector<CellResult>().swap(m.rowResults);
  m.leaves.releaseTable();
  m.mids.releaseTable();
  m.roots.releaseTable();
  m.labelTable.clear();

  Volume v;
  v.geometry = m.geometry;
  v.scalarType = m.type;
  v.background = m.options.background;
  FieldWidths& w = v.widths;

  auto checkWidth = [](uint32_t bits, const char* what) {
    if (bits > 32)
      throw std::length_error(std::string("SVDAG too large: ") + what + " need more than 32 bits");
    return bits;
  };
  // Leaves keep their ids. A reference is (id << 1) | complement.
  w.leafRefBits = checkWidth(m.leaves.refBits(), "leaf references");
  v.leaves = m.leaves.take();

  // The mid pool already is the final stream: its references are leaf ids at the final width.
  m.mids.widenTo(w.leafRefBits);
  v.midCount = m.mids.size();
  const uint64_t lastMid = m.mids.size() ? m.mids.offset(uint32_t(m.mids.size() - 1)) : 0;
  w.midRefBits = checkWidth(bitWidth(lastMid) + 1, "mid references");

  // Roots refer to mid ids; the output refers to mid bit offsets, at the final width.
  v.rootCount = m.roots.size();
  GrowArray<uint32_t> rootOffsets;
  {
    uint64_t bits = 0;
    for (uint32_t id = 0; id < m.roots.size(); ++id)
    {
      rootOffsets.push_back(uint32_t(bits));
      uint32_t refs[8];
      const uint32_t header = m.roots.read(id, refs);
      bits += layout::NODE_HEADER_BITS +
        uint64_t(build::popcount8(layout::nodeMixedMask(header))) * w.midRefBits;
      if (bits > 0xFFFFFFFFull)
        throw std::length_error("SVDAG too large: the root stream exceeds 2^32 bits");
    }
    v.roots.assign(size_t((bits + 31) / 32 + 1), 0u);
    for (uint32_t id = 0; id < m.roots.size(); ++id)
    {
      uint32_t refs[8];
      const uint32_t header = m.roots.read(id, refs);
      uint64_t at = rootOffsets[id];
      writeBits(v.roots, at, layout::NODE_HEADER_BITS, header);
      at += layout::NODE_HEADER_BITS;
      for (uint32_t r = 0; r < build::popcount8(layout::nodeMixedMask(header)); ++r, at += w.midRefBits)
      {
        const uint64_t target = m.mids.offset(refs[r] >> 1);
        writeBits(v.roots, at, w.midRefBits, uint32_t((target << 1) | (refs[r] & 1u)));
      }
    }
  }
  m.roots.release();
  v.mids = m.mids.takeStream();
  m.mids.release();
  const uint64_t lastRoot = rootOffsets.empty() ? 0 : rootOffsets.back();
  w.rootRefBits = checkWidth(bitWidth(lastRoot) + 1, "root references");

  // Label table sorted by value; blocks refer to the sorted index.
  std::vector<uint32_t> order(m.labels.size());
  std::iota(order.begin(), order.end(), 0u);
  const ScalarType type = m.type;
  std::sort(order.begin(), order.end(), [&](uint32_t a, uint32_t b) {
    return scalarLess(type, m.labels[a].value, m.labels[b].value);
  });
  std::vector<uint32_t> rank(order.size());
  v.labels.resize(order.size());
  for (uint32_t i = 0; i < order.size(); ++i)
  {
    rank[order[i]] = i;
    v.labels[i] = m.labels[order[i]];
  }
  std::vector<LabelInfo>().swap(m.labels);
  w.labelBits = bitWidth(v.labels.empty() ? 0 : v.labels.size() - 1);
  w.cellBits = bitWidth(m.geometry.cellCount() - 1);

  v.blockCount = m.blocks.size();
  const uint32_t recordBits = w.blockBits();
  v.blocks.assign((v.blockCount * recordBits + 31) / 32 + 1, 0u);
  // Blocks come in cell order; within a cell they are written by label index (the sorted
  // table's order), so that blocks are sorted by (cell, label) as Volume::validate requires.
  std::vector<std::pair<uint32_t, uint64_t>> cellRun; // (label index, pending block)
  uint64_t written = 0;
  auto writeBlock = [&](const PendingBlocks::Record& b) {
    const uint64_t base = written++ * recordBits;
    writeBits(v.blocks, base, w.cellBits, b[PendingCell]);
    writeBits(v.blocks, base + layout::blockBoundsOffset(w.cellBits), layout::BLOCK_BOUNDS_BITS,
      b[PendingBox]);
    writeBits(v.blocks, base + layout::blockLabelOffset(w.cellBits), w.labelBits, rank[b[PendingLabel]]);
    const uint64_t root =
      (uint64_t(rootOffsets[b[PendingRoot] >> 1]) << 1) | (b[PendingRoot] & 1u);
    writeBits(v.blocks, base + layout::blockRootOffset(w.cellBits, w.labelBits), w.rootRefBits,
      uint32_t(root));
  };
  for (uint64_t i = 0; i < m.blocks.size();)
  {
    const uint32_t cell = m.blocks[i][PendingCell];
    cellRun.clear();
    for (; i < m.blocks.size() && m.blocks[i][PendingCell] == cell; ++i)
      cellRun.emplace_back(rank[m.blocks[i][PendingLabel]], i);
    std::sort(cellRun.begin(), cellRun.end());
    for (const auto& entry : cellRun)
      writeBlock(m.blocks[entry.second]);
  }
  m.blocks.release();
  return v;
}

Volume Builder::build(const Geometry& geometry, ScalarType type, const void* data,
  const BuildOptions& options, ParallelFor parallel)
{
  Builder builder(geometry, type, options, parallel);
  const size_t slice = size_t(geometry.dims[0]) * size_t(geometry.dims[1]) * size_t(scalarSize(type));
  for (int32_t z0 = 0; z0 < geometry.dims[2]; z0 += SlabDepth)
  {
    const int32_t nz = std::min(SlabDepth, geometry.dims[2] - z0);
    builder.addSlab(z0, nz, static_cast<const uint8_t*>(data) + size_t(z0) * slice);
  }
  return builder.finish();
}

} // namespace svdag
