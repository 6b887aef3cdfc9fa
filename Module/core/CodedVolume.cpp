// The coded form of a Volume (CodedVolume.h). Every decision is coded by one procedure for both
// directions (RangeCoder.h): the writer passes the true values, the reader gets them back.
#include "CodedVolume.h"

#include "Bits.h"
#include "RangeCoder.h"
#include "svdag/Builder.h"
#include "svdag/LeafSymmetry.h"

#include <algorithm>
#include <array>
#include <exception>
#include <memory>
#include <string>
#include <type_traits>

namespace svdag
{
namespace coded
{
namespace
{
using coding::BitModel;
using coding::CorruptStream;

constexpr uint32_t LeafCount = 64; // 4^3 leaves of a 16^3 cell
constexpr uint64_t AllOnes = ~uint64_t(0);
using LeafMasks = std::array<uint64_t, LeafCount>;

// Leaf (lx + 4 ly + 16 lz) of child c of the cell's octant o, both x fastest.
constexpr uint32_t leafOf(uint32_t o, uint32_t c)
{
  return (2 * (o & 1) + (c & 1)) + 4 * (2 * ((o >> 1) & 1) + ((c >> 1) & 1)) +
    16 * (2 * (o >> 2) + (c >> 2));
}

uint32_t bitAt(const uint64_t* masks, uint32_t x, uint32_t y, uint32_t z)
{
  return uint32_t(masks[(x >> 2) + 4 * (y >> 2) + 16 * (z >> 2)] >>
           layout::leafBit(x & 3, y & 3, z & 3)) & 1u;
}

// What an octant or leaf of a block holds of the voxels still free in its cell.
enum State : uint32_t
{
  NoFree = 0, // nothing to code: no free voxel there
  None = 1,
  All = 2,
  Some = 3
};

// Label values are coded in the order of their type (scalarLess): as unsigned keys.
uint64_t orderKey(ScalarType t, uint64_t pattern)
{
  return scalarSigned(t) ? pattern ^ (uint64_t(1) << 63) : pattern;
}

struct Models
{
  enum Numbers
  {
    FirstLabel,
    LabelStep,
    CellGap,
    NumberKinds
  };
  BitModel width[NumberKinds][128]; // binary trees over a number's bit width, 0..64
  BitModel gapZero;
  BitModel present[3][3];           // neighbour cells holding the label (1..3), labels so far
  BitModel more[4][2];              // one more label beyond the neighbours', by how many so far
  BitModel takesAll;                // the cell's last block holds every free voxel
  // An octant (level 0, 8^3) or leaf (level 1, 4^3): is it some of its free voxels, and if not,
  // all of them? By whether it is wholly free, whether the block is its cell's last, and the
  // states of its -x, -y and -z neighbours in the block.
  BitModel some[2][2][2][64];
  BitModel all[2][2][2][64];
  // A voxel: its -x, -y, -z neighbours in the block (0, 1, or 2 outside the cell), the three
  // diagonal ones before it, and how many of its six neighbours are not free (0, 1, 2+).
  BitModel voxel[27][8][3];
};

template <class Coder>
constexpr bool writing()
{
  return std::is_same<Coder, coding::Encoder>::value;
}

// A number of up to 64 bits: its width from a tree of models, the bits below its leading one
// with probability 1/2.
template <class Coder>
uint64_t number(Coder& c, BitModel* tree, uint64_t value)
{
  uint32_t width = writing<Coder>() ? bits::bitWidth(value) : 0;
  uint32_t node = 1;
  for (int i = 6; i >= 0; --i)
    node = 2 * node + c.bit(tree[node], (width >> i) & 1u);
  width = node - 128;
  if (width > 64)
    throw CorruptStream("the coded volume holds a number wider than 64 bits");
  if (width <= 1)
    return width;
  uint32_t rest = width - 1;
  uint64_t v = 1;
  if (rest > 32)
  {
    v = (v << (rest - 32)) | c.direct(uint32_t(value >> 32) & layout::lowMask(rest - 32), rest - 32);
    rest = 32;
  }
  return (v << rest) | c.direct(uint32_t(value) & layout::lowMask(rest), rest);
}

// The sorted label indices of the non-empty cells coded so far.
class CellLabels
{
public:
  void add(uint64_t cell, const std::vector<uint32_t>& labels)
  {
    Cells.push_back(cell);
    Labels.insert(Labels.end(), labels.begin(), labels.end());
    Starts.push_back(Labels.size());
  }
  // The labels of a cell (none if it is empty or not coded yet).
  std::pair<const uint32_t*, const uint32_t*> of(uint64_t cell) const
  {
    const auto it = std::lower_bound(Cells.begin(), Cells.end(), cell);
    if (it == Cells.end() || *it != cell)
      return { nullptr, nullptr };
    const size_t k = size_t(it - Cells.begin());
    return { Labels.data() + Starts[k], Labels.data() + Starts[k + 1] };
  }

private:
  std::vector<uint64_t> Cells;
  std::vector<uint32_t> Labels;
  std::vector<size_t> Starts{ 0 };
};

// Voxels of a cell inside the volume.
LeafMasks insideMasks(const std::array<uint32_t, 3>& extent)
{
  LeafMasks m{};
  if (extent[0] == 16 && extent[1] == 16 && extent[2] == 16)
  {
    m.fill(AllOnes);
    return m;
  }
  for (uint32_t z = 0; z < extent[2]; ++z)
    for (uint32_t y = 0; y < extent[1]; ++y)
      for (uint32_t x = 0; x < extent[0]; ++x)
        m[(x >> 2) + 4 * (y >> 2) + 16 * (z >> 2)] |= uint64_t(1) << layout::leafBit(x & 3, y & 3, z & 3);
  return m;
}

// A leaf's voxels and the layer before it on each axis (5^3, x fastest): the state of each as a
// neighbour of the leaf's voxels in this block (0 or 1; 2 outside the cell). The leaf's own
// voxels start at 0 and are set as they are coded.
struct Neighbourhood
{
  uint8_t v[125];
  static uint32_t index(uint32_t b) { return ((b & 3) + 1) + 5 * (((b >> 2) & 3) + 1) + 25 * ((b >> 4) + 1); }
  void load(const uint64_t* mine, uint32_t l)
  {
    std::fill(v, v + 125, uint8_t(0));
    const uint32_t x0 = 4 * (l & 3), y0 = 4 * ((l >> 2) & 3), z0 = 4 * (l >> 4);
    // A voxel of the layer before the leaf: 2 outside the cell.
    auto at = [&](int32_t i, int32_t j, int32_t k) {
      const int32_t x = int32_t(x0) + i, y = int32_t(y0) + j, z = int32_t(z0) + k;
      v[(i + 1) + 5 * (j + 1) + 25 * (k + 1)] = (x < 0 || y < 0 || z < 0)
        ? uint8_t(2)
        : uint8_t(bitAt(mine, uint32_t(x), uint32_t(y), uint32_t(z)));
    };
    for (int32_t k = -1; k < 4; ++k)
      for (int32_t j = -1; j < 4; ++j)
        at(-1, j, k);
    for (int32_t k = -1; k < 4; ++k)
      for (int32_t i = 0; i < 4; ++i)
        at(i, -1, k);
    for (int32_t j = 0; j < 4; ++j)
      for (int32_t i = 0; i < 4; ++i)
        at(i, j, -1);
  }
};

// How many of each voxel's six neighbours in the cell are not free (0, 1 or 2 and more), for the
// voxels of one leaf at once, as two bit masks.
class TakenNeighbours
{
public:
  TakenNeighbours(const uint64_t* free, uint32_t l)
  {
    constexpr uint64_t X0 = 0x1111111111111111ull, X3 = X0 << 3; // voxels at x = 0, x = 3
    constexpr uint64_t Y0 = 0x000F000F000F000Full, Y3 = Y0 << 12;
    const uint32_t lx = l & 3, ly = (l >> 2) & 3, lz = l >> 4;
    auto taken = [free](uint32_t leaf) { return ~free[leaf]; };
    const uint64_t t = taken(l);
    const uint64_t sides[6] = {
      ((t << 1) & ~X0) | (lx ? (taken(l - 1) & X3) >> 3 : 0),
      ((t >> 1) & ~X3) | (lx < 3 ? (taken(l + 1) & X0) << 3 : 0),
      ((t << 4) & ~Y0) | (ly ? (taken(l - 4) & Y3) >> 12 : 0),
      ((t >> 4) & ~Y3) | (ly < 3 ? (taken(l + 4) & Y0) << 12 : 0),
      (t << 16) | (lz ? taken(l - 16) >> 48 : 0),
      (t >> 16) | (lz < 3 ? taken(l + 16) << 48 : 0),
    };
    for (const uint64_t side : sides)
    {
      AtLeastTwo |= AtLeastOne & side;
      AtLeastOne |= side;
    }
  }
  uint32_t count(uint32_t b) const
  {
    return uint32_t((AtLeastOne >> b) & 1u) + uint32_t((AtLeastTwo >> b) & 1u);
  }

private:
  uint64_t AtLeastOne = 0, AtLeastTwo = 0;
};

template <class Coder>
class Coding
{
public:
  Coding(Coder& coder, const Frame& frame)
    : C(coder)
    , F(frame)
    , M(new Models())
  {
  }

  // The label values, sorted by value (written: given; read: filled in).
  void labelValues(std::vector<uint64_t>& values)
  {
    const ScalarType t = F.scalarType;
    const uint64_t minKey = orderKey(t, scalarMin(t)), maxKey = orderKey(t, scalarMax(t));
    if (!writing<Coder>())
    {
      values.clear();
      values.reserve(size_t(std::min<uint64_t>(F.labelCount, 1u << 16)));
    }
    uint64_t previous = 0;
    for (uint64_t i = 0; i < F.labelCount; ++i)
    {
      const uint64_t key = writing<Coder>() ? orderKey(t, values[size_t(i)]) : 0;
      const uint64_t step = number(C, M->width[i ? Models::LabelStep : Models::FirstLabel],
        i ? key - previous - 1 : key - minKey);
      const uint64_t start = i ? previous + 1 : minKey;
      if ((i && previous == maxKey) || step > maxKey - start)
        throw CorruptStream("the coded volume holds a label value outside its type");
      previous = start + step;
      if (!writing<Coder>())
      {
        const uint64_t value = orderKey(t, previous); // the key's own inverse
        if (value == F.background)
          throw CorruptStream("the coded volume's label table holds the background value");
        values.push_back(value);
      }
    }
  }

  // Every block, cell by cell. Source (written) gives them, Sink (read) takes them:
  //   uint64_t source.nextCell()                     the next non-empty cell, or cellCount
  //   void source.cell(labels, masks)                that cell's labels and occupancy, then on
  //   void sink.block(cell, label, masks)            one decoded block
  template <class Side>
  void cells(Side& side)
  {
    const Geometry& g = F.geometry;
    const uint64_t cellCount = g.cellCount();
    const std::array<int32_t, 3> cells = g.cellCounts();
    const uint64_t ncx = uint64_t(cells[0]), ncxy = ncx * uint64_t(cells[1]);
    const uint32_t labelBits = bits::bitWidth(F.labelCount ? F.labelCount - 1 : 0);
    CellLabels coded;
    std::vector<uint32_t> labels;
    std::vector<LeafMasks> masks;
    std::vector<std::pair<uint32_t, uint32_t>> candidates; // label, neighbours holding it
    uint64_t previous = ~uint64_t(0), blocks = 0;
    for (;;)
    {
      uint64_t next = 0;
      if constexpr (writing<Coder>())
        next = side.nextCell();
      uint64_t gap = next - previous - 1;
      if (C.bit(M->gapZero, gap != 0))
      {
        gap = number(C, M->width[Models::CellGap], gap - 1);
        if (gap >= cellCount)
          throw CorruptStream("the coded volume skips past its last cell");
        ++gap;
      }
      else
        gap = 0;
      const uint64_t cell = previous + 1 + gap;
      if (cell > cellCount)
        throw CorruptStream("the coded volume skips past its last cell");
      if (cell == cellCount)
        break;
      previous = cell;
      const uint64_t cx = cell % ncx, cy = cell / ncx % uint64_t(cells[1]), cz = cell / ncxy;

      candidates.clear();
      for (const uint64_t neighbour : { cx ? cell - 1 : cellCount, cy ? cell - ncx : cellCount,
             cz ? cell - ncxy : cellCount })
      {
        const auto range = coded.of(neighbour);
        for (const uint32_t* l = range.first; l != range.second; ++l)
          candidates.emplace_back(*l, 1u);
      }
      std::sort(candidates.begin(), candidates.end());
      size_t unique = 0;
      for (size_t i = 0; i < candidates.size(); ++i)
      {
        if (unique && candidates[unique - 1].first == candidates[i].first)
          ++candidates[unique - 1].second;
        else
          candidates[unique++] = candidates[i];
      }
      candidates.resize(unique);

      if constexpr (writing<Coder>())
        side.cell(labels, masks);
      cellLabels(candidates, labels, labelBits);
      blocks += labels.size();
      if (blocks > F.blockCount)
        throw CorruptStream("the coded volume holds more blocks than its header says");
      coded.add(cell, labels);

      std::array<uint32_t, 3> extent;
      for (int a = 0; a < 3; ++a)
      {
        const uint64_t c = a == 0 ? cx : (a == 1 ? cy : cz);
        extent[a] = uint32_t(std::min<uint64_t>(16, uint64_t(g.dims[a]) - 16 * c));
      }
      LeafMasks free = insideMasks(extent);
      LeafMasks mine{};
      for (size_t j = 0; j < labels.size(); ++j)
      {
        if (writing<Coder>())
          mine = masks[j];
        else
          mine.fill(0);
        occupancy(free.data(), mine.data(), j + 1 == labels.size());
        uint64_t any = 0;
        for (uint32_t l = 0; l < LeafCount; ++l)
        {
          any |= mine[l];
          free[l] &= ~mine[l];
        }
        if (!any)
          throw CorruptStream("the coded volume holds an empty block");
        if constexpr (!writing<Coder>())
          side.block(cell, labels[j], mine);
      }
    }
    if (blocks != F.blockCount)
      throw CorruptStream("the coded volume holds fewer blocks than its header says");
  }

private:
  // A cell's labels (sorted label indices): which of its neighbours' it holds, then any others.
  void cellLabels(const std::vector<std::pair<uint32_t, uint32_t>>& candidates,
    std::vector<uint32_t>& labels, uint32_t labelBits)
  {
    std::vector<uint32_t> others;
    if (writing<Coder>())
    {
      for (const uint32_t l : labels)
      {
        if (!std::binary_search(candidates.begin(), candidates.end(), std::make_pair(l, 0u),
              [](const auto& a, const auto& b) { return a.first < b.first; }))
          others.push_back(l);
      }
    }
    std::vector<uint32_t> found;
    for (const auto& candidate : candidates)
    {
      const uint32_t present = writing<Coder>()
        ? uint32_t(std::binary_search(labels.begin(), labels.end(), candidate.first))
        : 0u;
      if (C.bit(M->present[std::min(candidate.second, 3u) - 1][std::min<size_t>(found.size(), 2)],
            present))
        found.push_back(candidate.first);
    }
    const size_t fromNeighbours = found.size();
    for (size_t i = 0;; ++i)
    {
      if (!C.bit(M->more[std::min<size_t>(i, 3)][fromNeighbours ? 1 : 0],
            writing<Coder>() && i < others.size()))
        break;
      if (found.size() >= size_t(LeafCount) * LeafCount)
        throw CorruptStream("the coded volume holds more labels in a cell than it has voxels");
      const uint32_t label = C.direct(writing<Coder>() ? others[i] : 0u, labelBits);
      if (label >= F.labelCount)
        throw CorruptStream("the coded volume holds a label index past its label table");
      found.push_back(label);
    }
    std::sort(found.begin(), found.end());
    if (std::adjacent_find(found.begin(), found.end()) != found.end())
      throw CorruptStream("the coded volume holds a label twice in one cell");
    if (found.empty())
      throw CorruptStream("the coded volume holds a cell without labels");
    labels = std::move(found);
  }

  static uint32_t neighbourStates(const uint8_t* states, uint32_t i, bool x, bool y, bool z,
    uint32_t dy, uint32_t dz)
  {
    return (x ? uint32_t(states[i - 1]) << 4 : 0u) | (y ? uint32_t(states[i - dy]) << 2 : 0u) |
      (z ? uint32_t(states[i - dz]) : 0u);
  }

  // One block's occupancy of the free voxels (written: given in mine; read: filled in).
  void occupancy(const uint64_t* free, uint64_t* mine, bool last)
  {
    if (last)
    {
      uint32_t takesAll = 1;
      if (writing<Coder>())
      {
        for (uint32_t l = 0; l < LeafCount; ++l)
          takesAll &= mine[l] == free[l] ? 1u : 0u;
      }
      if (C.bit(M->takesAll, takesAll))
      {
        std::copy(free, free + LeafCount, mine);
        return;
      }
    }
    uint8_t octants[8] = {};
    uint8_t leaves[LeafCount] = {};
    for (uint32_t o = 0; o < 8; ++o)
    {
      uint64_t anyFree = 0, anyMine = 0;
      bool wholeFree = true, allMine = true;
      for (uint32_t c = 0; c < 8; ++c)
      {
        const uint32_t l = leafOf(o, c);
        anyFree |= free[l];
        wholeFree = wholeFree && free[l] == AllOnes;
        if (writing<Coder>())
        {
          anyMine |= mine[l];
          allMine = allMine && mine[l] == free[l];
        }
      }
      if (!anyFree)
      {
        for (uint32_t c = 0; c < 8; ++c)
          mine[leafOf(o, c)] = 0;
        continue;
      }
      const uint32_t ctx = neighbourStates(octants, o, o & 1, o & 2, o & 4, 2, 4);
      const uint32_t state = !anyMine ? None : (allMine ? All : Some);
      if (C.bit(M->some[0][wholeFree][last][ctx], state == Some))
      {
        octants[o] = Some;
        for (uint32_t c = 0; c < 8; ++c)
          leaf(free, mine, leafOf(o, c), leaves, last);
      }
      else
      {
        octants[o] = C.bit(M->all[0][wholeFree][last][ctx], state == All) ? All : None;
        for (uint32_t c = 0; c < 8; ++c)
        {
          const uint32_t l = leafOf(o, c);
          mine[l] = octants[o] == All ? free[l] : 0;
          leaves[l] = free[l] ? octants[o] : uint8_t(NoFree);
        }
      }
    }
  }

  void leaf(const uint64_t* free, uint64_t* mine, uint32_t l, uint8_t* states, bool last)
  {
    if (!free[l])
    {
      mine[l] = 0;
      return;
    }
    const bool wholeFree = free[l] == AllOnes;
    const uint32_t ctx = neighbourStates(states, l, l & 3, l & 12, l & 48, 4, 16);
    const uint32_t state = mine[l] == 0 ? None : (mine[l] == free[l] ? All : Some);
    if (!C.bit(M->some[1][wholeFree][last][ctx], state == Some))
    {
      states[l] = uint8_t(C.bit(M->all[1][wholeFree][last][ctx], state == All) ? All : None);
      mine[l] = states[l] == All ? free[l] : 0;
      return;
    }
    states[l] = Some;
    const uint64_t given = mine[l];
    if (!writing<Coder>())
      mine[l] = 0;
    // The leaf and the layer before it on each axis, as states of their voxels: 0 or 1 for
    // this block's occupancy, 2 outside the cell (Neighbourhood). Only voxels before the current
    // one in the coding order (leaves in octant order, bits in x, y, z order) are read: every
    // neighbour with no coordinate larger is one of them.
    Neighbourhood n;
    n.load(mine, l);
    const TakenNeighbours taken(free, l);
    for (uint64_t rest = free[l]; rest; rest &= rest - 1)
    {
      const uint32_t b = uint32_t(__builtin_ctzll(rest));
      const uint32_t at = Neighbourhood::index(b);
      const uint32_t axes = uint32_t(n.v[at - 1]) * 9 + uint32_t(n.v[at - 5]) * 3 + n.v[at - 25];
      const uint32_t diagonals = (n.v[at - 6] & 1u) | ((n.v[at - 26] & 1u) << 1) |
        ((n.v[at - 30] & 1u) << 2);
      const uint32_t v = C.bit(M->voxel[axes][diagonals][taken.count(b)], uint32_t(given >> b) & 1u);
      n.v[at] = uint8_t(v);
      if (!writing<Coder>())
        mine[l] |= uint64_t(v) << b;
    }
    if (mine[l] == 0 || mine[l] == free[l])
      throw CorruptStream("the coded volume holds a leaf coded voxel by voxel that is not mixed");
  }

  Coder& C;
  const Frame& F;
  std::unique_ptr<Models> M;
};

// The writer's side: the blocks of one chunk of the volume, cell by cell, their cells numbered
// from the chunk's first.
class VolumeSource
{
public:
  VolumeSource(const Volume& v, uint64_t first, uint64_t end, uint64_t firstCell, uint64_t cellCount)
    : V(v)
    , Next(first)
    , End(end)
    , FirstCell(firstCell)
    , CellCount(cellCount)
  {
  }
  uint64_t nextCell() const { return Next < End ? V.block(Next).cell - FirstCell : CellCount; }
  void cell(std::vector<uint32_t>& labels, std::vector<LeafMasks>& masks)
  {
    const uint32_t cell = V.block(Next).cell;
    labels.clear();
    masks.clear();
    for (; Next < End && V.block(Next).cell == cell; ++Next)
    {
      labels.push_back(V.block(Next).label);
      masks.emplace_back();
      V.leafMasks(Next, masks.back().data());
    }
  }

private:
  const Volume& V;
  uint64_t Next, End, FirstCell, CellCount;
};

// The reader's side of one chunk: its blocks as they decode, compactly (most leaves of a block
// are empty or full), each mixed leaf with its code from canonicalLeaf's search, which runs here,
// in the chunk's thread, remembered per mask in a small direct-mapped cache (neighbouring blocks
// repeat leaves) that decoded() frees. addTo() then hands them to the one Builder, in order.
class ChunkBlocks
{
public:
  explicit ChunkBlocks(uint64_t firstCell)
    : FirstCell(firstCell)
    , Cache(size_t(1) << CacheBits)
  {
  }
  void block(uint64_t cell, uint32_t label, const LeafMasks& masks)
  {
    uint64_t full = 0, mixed = 0;
    for (uint32_t l = 0; l < LeafCount; ++l)
    {
      const uint64_t m = masks[l];
      if (m == AllOnes)
        full |= uint64_t(1) << l;
      else if (m != 0)
      {
        mixed |= uint64_t(1) << l;
        Entry& e = Cache[size_t(bits::mix64(m) >> (64 - CacheBits))];
        if (!e.valid || e.mask != m)
        {
          const CanonicalLeaf c = canonicalLeaf(m);
          e = Entry{ m, uint8_t((c.symmetry << 1) | c.complement), true };
        }
        Masks.push_back(m);
        Codes.push_back(e.code);
      }
    }
    Blocks.push_back({ FirstCell + cell, label, full, mixed });
  }
  // The chunk is decoded: its cache goes, so that only the decoding chunks hold one.
  void decoded() { std::vector<Entry>().swap(Cache); }
  // Frees what it held as it goes.
  void addTo(Builder& builder, const std::vector<uint64_t>& values)
  {
    CellOccupancy occupancy;
    size_t next = 0;
    for (const Record& r : Blocks)
    {
      occupancy.value = values[r.label];
      for (uint32_t l = 0; l < LeafCount; ++l)
      {
        occupancy.codes[l] = 0;
        if ((r.mixed >> l) & 1u)
        {
          occupancy.masks[l] = Masks[next];
          occupancy.codes[l] = Codes[next++];
        }
        else
          occupancy.masks[l] = ((r.full >> l) & 1u) ? AllOnes : 0;
      }
      builder.addBlock(uint32_t(r.cell), occupancy);
    }
    std::vector<Record>().swap(Blocks);
    std::vector<uint64_t>().swap(Masks);
    std::vector<uint8_t>().swap(Codes);
  }

private:
  static constexpr uint32_t CacheBits = 14;
  struct Entry
  {
    uint64_t mask = 0;
    uint8_t code = 0;
    bool valid = false;
  };
  struct Record
  {
    uint64_t cell;
    uint32_t label;
    uint64_t full, mixed; // leaves that are all ones, and mixed ones (in Masks and Codes)
  };
  uint64_t FirstCell;
  std::vector<Entry> Cache;
  std::vector<Record> Blocks;
  std::vector<uint64_t> Masks;
  std::vector<uint8_t> Codes;
};
} // namespace

Frame frameOf(const Volume& v)
{
  Frame f;
  f.geometry = v.geometry;
  f.scalarType = v.scalarType;
  f.background = v.background;
  f.labelCount = v.labels.size();
  f.blockCount = v.blockCount;
  return f;
}

uint32_t maxChunkCount(const Geometry& g)
{
  const uint64_t slabs = (uint64_t(g.dims[2]) + Builder::SlabDepth - 1) / Builder::SlabDepth;
  return uint32_t(std::max<uint64_t>(1, std::min<uint64_t>(slabs, MaxChunks)));
}

uint32_t chunkCount(const Geometry& g)
{
  return uint32_t(std::max<uint64_t>(
    1, std::min<uint64_t>(g.cellCount() / CellsPerChunk, maxChunkCount(g))));
}

namespace
{
// The section's table: chunk count, label stream bytes, then bytes and blocks of each chunk.
constexpr size_t TableFixedBytes = 4 + 8, TableChunkBytes = 16;

void appendLE(std::vector<uint8_t>& out, uint64_t v, int n)
{
  out.resize(out.size() + size_t(n));
  bits::storeLE(out.data() + out.size() - size_t(n), v, n);
}
using bits::loadLE;

// The geometry of chunk i and its first cell.
Frame chunkFrame(const Frame& whole, uint32_t i, uint32_t chunks, uint64_t& firstCell)
{
  const Geometry& g = whole.geometry;
  const std::array<int32_t, 2> z = Builder::pieceZRange(g.dims[2], int(i), int(chunks));
  Frame f = whole;
  f.geometry = g.zRange(z[0], z[1]);
  const std::array<int32_t, 3> cells = g.cellCounts();
  firstCell = uint64_t(z[0] / Builder::SlabDepth) * uint64_t(cells[0]) * uint64_t(cells[1]);
  return f;
}

// Runs f(i) for i in [0, n) through `parallel`; the first exception any call throws is thrown
// here once all have run (a parallel-for need not carry exceptions across threads).
template <class F>
void forEachChunk(uint32_t n, const ParallelFor& parallel, const F& f)
{
  std::vector<std::exception_ptr> errors(n);
  parallel(0, n, 1, [&](uint64_t begin, uint64_t end) {
    for (uint64_t i = begin; i < end; ++i)
    {
      try
      {
        f(uint32_t(i));
      }
      catch (...)
      {
        errors[size_t(i)] = std::current_exception();
      }
    }
  });
  for (const std::exception_ptr& e : errors)
  {
    if (e)
      std::rethrow_exception(e);
  }
}
} // namespace

std::vector<uint8_t> encode(const Volume& volume, const ParallelFor& parallel, uint32_t chunks)
{
  const Frame frame = frameOf(volume);
  std::vector<uint64_t> values;
  for (const LabelInfo& l : volume.labels)
    values.push_back(l.value);
  coding::Encoder labelEncoder;
  Coding<coding::Encoder>(labelEncoder, frame).labelValues(values);
  const std::vector<uint8_t> labelBytes = labelEncoder.finish();

  if (chunks == 0)
    chunks = chunkCount(volume.geometry);
  if (chunks > maxChunkCount(volume.geometry))
    throw std::invalid_argument("more chunks than the volume has slabs (or than MaxChunks)");
  std::vector<std::vector<uint8_t>> streams(chunks);
  std::vector<uint64_t> blocks(chunks);
  forEachChunk(chunks, parallel, [&](uint32_t i) {
    uint64_t firstCell;
    Frame f = chunkFrame(frame, i, chunks, firstCell);
    const uint64_t endCell = firstCell + f.geometry.cellCount();
    // Where a cell's blocks start (or would: cellBlocks finds the place in an empty cell too).
    auto firstBlockOf = [&](uint64_t cell) {
      return cell == volume.geometry.cellCount() ? volume.blockCount
                                                 : volume.cellBlocks(uint32_t(cell)).first;
    };
    const uint64_t first = firstBlockOf(firstCell), end = firstBlockOf(endCell);
    f.blockCount = blocks[i] = end - first;
    coding::Encoder encoder;
    VolumeSource source(volume, first, end, firstCell, f.geometry.cellCount());
    Coding<coding::Encoder>(encoder, f).cells(source);
    streams[i] = encoder.finish();
  });

  std::vector<uint8_t> out;
  appendLE(out, chunks, 4);
  appendLE(out, labelBytes.size(), 8);
  for (uint32_t i = 0; i < chunks; ++i)
  {
    appendLE(out, streams[i].size(), 8);
    appendLE(out, blocks[i], 8);
  }
  out.insert(out.end(), labelBytes.begin(), labelBytes.end());
  for (std::vector<uint8_t>& stream : streams)
  {
    out.insert(out.end(), stream.begin(), stream.end());
    std::vector<uint8_t>().swap(stream);
  }
  return out;
}

Volume decode(const uint8_t* data, size_t size, const Frame& frame, const ParallelFor& parallel)
{
  if (frame.labelCount > frame.blockCount)
    throw CorruptStream("the header counts more labels than blocks");
  // The table: as many chunks as the writer's rule gives, streams that fill the section exactly,
  // block counts that add up to the header's.
  if (size < TableFixedBytes)
    throw CorruptStream("the coded volume is truncated (its table)");
  const uint32_t chunks = uint32_t(loadLE(data, 4));
  if (chunks == 0 || chunks > maxChunkCount(frame.geometry))
    throw CorruptStream("the coded volume has " + std::to_string(chunks) + " chunks (1 to " +
      std::to_string(maxChunkCount(frame.geometry)) + " for its geometry)");
  const size_t tableBytes = TableFixedBytes + TableChunkBytes * chunks;
  if (size < tableBytes)
    throw CorruptStream("the coded volume is truncated (its table)");
  std::vector<uint64_t> offsets(size_t(chunks) + 2), blocks(chunks);
  offsets[0] = tableBytes;
  uint64_t totalBlocks = 0;
  for (uint32_t i = 0; i <= chunks; ++i)
  {
    const uint64_t bytes = i == 0 ? loadLE(data + 4, 8) : loadLE(data + TableFixedBytes + TableChunkBytes * (i - 1), 8);
    if (bytes > size - offsets[i])
      throw CorruptStream("the coded volume's streams run past its end");
    offsets[i + 1] = offsets[i] + bytes;
    if (i > 0)
    {
      blocks[i - 1] = loadLE(data + TableFixedBytes + TableChunkBytes * (i - 1) + 8, 8);
      if (blocks[i - 1] > frame.blockCount - totalBlocks)
        throw CorruptStream("the coded volume's chunks hold more blocks than its header says");
      totalBlocks += blocks[i - 1];
    }
  }
  if (offsets[chunks + 1] != size)
    throw CorruptStream("the coded volume's streams do not fill its section");
  if (totalBlocks != frame.blockCount)
    throw CorruptStream("the coded volume's chunks hold fewer blocks than its header says");

  std::vector<uint64_t> values;
  {
    coding::Decoder decoder(data + offsets[0], size_t(offsets[1] - offsets[0]));
    Coding<coding::Decoder>(decoder, frame).labelValues(values);
  }
  // The chunks decode side by side; the one builder then takes their blocks in order.
  std::vector<std::unique_ptr<ChunkBlocks>> parts(chunks);
  forEachChunk(chunks, parallel, [&](uint32_t i) {
    uint64_t firstCell;
    Frame f = chunkFrame(frame, i, chunks, firstCell);
    f.blockCount = blocks[i];
    coding::Decoder decoder(data + offsets[i + 1], size_t(offsets[i + 2] - offsets[i + 1]));
    parts[i].reset(new ChunkBlocks(firstCell));
    Coding<coding::Decoder>(decoder, f).cells(*parts[i]);
    parts[i]->decoded();
  });
  Builder whole(frame.geometry, frame.scalarType, BuildOptions{ frame.background, {} });
  whole.startBlocks();
  for (std::unique_ptr<ChunkBlocks>& part : parts)
  {
    part->addTo(whole, values);
    part.reset();
  }
  Volume v = whole.finishPooled();
  if (v.labels.size() != values.size())
    throw CorruptStream("the coded volume's label table holds a label no block has");
  return v;
}

std::string compareOccupancy(const Volume& a, const Volume& b)
{
  if (!(a.geometry == b.geometry) || a.scalarType != b.scalarType || a.background != b.background)
    return "geometry, scalar type or background";
  if (a.labels.size() != b.labels.size())
    return "label count";
  for (size_t i = 0; i < a.labels.size(); ++i)
  {
    if (!(a.labels[i] == b.labels[i]))
      return "label " + std::to_string(i);
  }
  if (a.blockCount != b.blockCount)
    return "block count";
  LeafMasks ma, mb;
  for (uint64_t i = 0; i < a.blockCount; ++i)
  {
    const Block ba = a.block(i), bb = b.block(i);
    a.leafMasks(i, ma.data());
    b.leafMasks(i, mb.data());
    if (ba.cell != bb.cell || ba.label != bb.label || ma != mb)
      return "block " + std::to_string(i);
  }
  return {};
}

} // namespace coded
} // namespace svdag
