// Procedurally generated volumes of any size, for tests past today's limits (files over 4 GiB,
// more blocks than one BLAS holds): the packed block records, the node pools and the label table
// are written directly, no voxel is scanned, in time linear in the number of cells and in
// parallel over z slices of cells. Every volume passes Volume::validate().
//
// Each cell holds at most one block, of one of a few shapes (ShapeId) sharing a small DAG: three
// root nodes, one mid node and one leaf, reached by plain and complemented references, so blocks
// exercise every level and both polarities. The label table's voxel counts and bounds are summed
// from what the blocks hold.
#pragma once

#include "ThreadedFor.h"

#include "svdag/Volume.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <climits>
#include <cmath>
#include <cstdint>
#include <fstream>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

namespace bigvolume
{

enum ShapeId : uint32_t
{
  HighCube = 0,   // the 8^3 cube of octant 7 (cell-local 8..15 on every axis): 512 voxels
  AllButHighCube, // its complement, the cell without that cube: 3584 voxels
  Notched,        // octant 6 full; in octant 0 a mid node: child 1 full, a 2^3 leaf cube in child 7
  NotchedInverse, // the complement of Notched
  HollowCube,     // octant 7 less Notched's mid node (its complemented reference): 440 voxels
  ShapeCount
};

// What a cell holds: no block, or one block of a shape and a label index.
struct CellBlock
{
  bool present = false;
  uint32_t shape = 0;
  uint32_t label = 0;
};

// A shape's root reference and what it holds, measured with Volume::occupancy.
struct ShapeInfo
{
  uint32_t rootRef = 0;
  uint32_t box = 0; // the record's bounds field: lo x, y, z then hi x, y, z, 4 bits each
  uint64_t voxels = 0;
  std::array<int32_t, 3> lo{ {} };
  std::array<int32_t, 3> hi{ {} };
};

using Clock = std::chrono::steady_clock;

inline double secondsSince(Clock::time_point start)
{
  return std::chrono::duration<double>(Clock::now() - start).count();
}

// MemAvailable from /proc/meminfo, in bytes; 0 when it cannot be read (the limit tests skip
// below what they need).
inline uint64_t availableMemory()
{
  std::ifstream in("/proc/meminfo");
  std::string key, rest;
  uint64_t kib = 0;
  while (in >> key >> kib)
  {
    if (key == "MemAvailable:")
      return kib * 1024;
    std::getline(in, rest);
  }
  return 0;
}

inline uint32_t bitWidth(uint64_t v)
{
  return v ? uint32_t(64 - __builtin_clzll(v)) : 0u;
}

inline uint64_t hash64(uint64_t x)
{
  x += 0x9e3779b97f4a7c15ull;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ull;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebull;
  return x ^ (x >> 31);
}

// A value in [0, n) from 32 hash bits, without a division.
inline uint32_t pick(uint64_t bits32, uint32_t n)
{
  return uint32_t(((bits32 & 0xFFFFFFFFull) * n) >> 32);
}

// Appends bit fields to a zeroed word stream from any bit offset. The words it fills whole are
// its own; the first and the last, which it may share with the writer of a neighbouring range of
// records, are ORed in atomically.
class BitWriter
{
public:
  BitWriter(uint32_t* words, uint64_t bitOffset)
    : Words(words)
    , Word(bitOffset >> 5)
    , Used(uint32_t(bitOffset & 31))
    , Shared(Used != 0)
  {
  }
  void put(uint32_t value, uint32_t width) // value < 2^width, width <= 32
  {
    Acc |= uint64_t(value) << Used;
    Used += width;
    if (Used >= 32)
    {
      emit(uint32_t(Acc));
      Acc >>= 32;
      Used -= 32;
    }
  }
  void finish()
  {
    if (Used > 0)
      __atomic_fetch_or(&Words[Word], uint32_t(Acc), __ATOMIC_RELAXED);
  }

private:
  void emit(uint32_t w)
  {
    if (Shared)
      __atomic_fetch_or(&Words[Word], w, __ATOMIC_RELAXED);
    else
      Words[Word] = w;
    Shared = false;
    ++Word;
  }
  uint32_t* Words;
  uint64_t Word;
  uint32_t Used;
  bool Shared;
  uint64_t Acc = 0;
};

// Writes the shared pools into v (roots, mids, leaves, their counts and reference widths) and
// returns the shapes, indexed by ShapeId.
inline std::vector<ShapeInfo> addShapes(svdag::Volume& v)
{
  // Leaf 0: the 2^3 cube at leaf-local 1..2 (bit x + 4 y + 16 z; bit 0 clear: canonical).
  uint64_t leaf = 0;
  for (uint32_t z = 1; z <= 2; ++z)
    for (uint32_t y = 1; y <= 2; ++y)
      for (uint32_t x = 1; x <= 2; ++x)
        leaf |= uint64_t(1) << svdag::layout::leafBit(x, y, z);
  v.leaves = { leaf };
  v.widths.leafRefBits = bitWidth(0) + 1;
  // Mid 0 at bit 0: child 7 mixed (leaf 0), child 1 full.
  v.midCount = 1;
  v.mids.assign(2, 0u);
  {
    BitWriter w(v.mids.data(), 0);
    w.put(0x80u | (0x02u << 8), svdag::layout::NODE_HEADER_BITS);
    w.put(0u << 1, v.widths.leafRefBits);
    w.finish();
  }
  v.widths.midRefBits = bitWidth(0) + 1;
  // Root 0 at bit 0: octant 7 full. Root 1 at bit 16: octant 0 mixed (mid 0), octant 6 full.
  // Root 2 at bit 33: octant 7 mixed (mid 0, complemented).
  const uint32_t rootAt[3] = { 0, 16, 33 };
  v.rootCount = 3;
  v.roots.assign(3, 0u);
  {
    BitWriter w(v.roots.data(), 0);
    w.put(0x80u << 8, svdag::layout::NODE_HEADER_BITS);
    w.put(0x01u | (0x40u << 8), svdag::layout::NODE_HEADER_BITS);
    w.put(0u << 1, v.widths.midRefBits);
    w.put(0x80u, svdag::layout::NODE_HEADER_BITS);
    w.put((0u << 1) | 1u, v.widths.midRefBits);
    w.finish();
  }
  v.widths.rootRefBits = bitWidth(rootAt[2]) + 1;

  std::vector<ShapeInfo> shapes(ShapeCount);
  shapes[HighCube].rootRef = rootAt[0] << 1;
  shapes[AllButHighCube].rootRef = (rootAt[0] << 1) | 1u;
  shapes[Notched].rootRef = rootAt[1] << 1;
  shapes[NotchedInverse].rootRef = (rootAt[1] << 1) | 1u;
  shapes[HollowCube].rootRef = rootAt[2] << 1;

  // Measure each shape with the volume's own decoder: one block per shape in a probe volume.
  svdag::Volume probe;
  probe.geometry.dims = { { 16, 16, 16 } };
  probe.widths = v.widths;
  probe.widths.cellBits = 0;
  probe.widths.labelBits = 0;
  probe.roots = v.roots;
  probe.mids = v.mids;
  probe.leaves = v.leaves;
  probe.blockCount = ShapeCount;
  probe.blocks.assign((ShapeCount * probe.widths.blockBits() + 31) / 32 + 1, 0u);
  {
    BitWriter w(probe.blocks.data(), 0);
    for (const ShapeInfo& s : shapes)
    {
      w.put(0, svdag::layout::BLOCK_BOUNDS_BITS);
      w.put(s.rootRef, probe.widths.rootRefBits);
    }
    w.finish();
  }
  std::vector<uint8_t> occupancy(4096);
  for (uint32_t i = 0; i < ShapeCount; ++i)
  {
    ShapeInfo& s = shapes[i];
    probe.occupancy(i, occupancy.data());
    s.lo = { { 15, 15, 15 } };
    s.hi = { { 0, 0, 0 } };
    for (int32_t z = 0; z < 16; ++z)
      for (int32_t y = 0; y < 16; ++y)
        for (int32_t x = 0; x < 16; ++x)
        {
          if (!occupancy[size_t(x + 16 * (y + 16 * z))])
            continue;
          ++s.voxels;
          const int32_t p[3] = { x, y, z };
          for (int a = 0; a < 3; ++a)
          {
            s.lo[a] = std::min(s.lo[a], p[a]);
            s.hi[a] = std::max(s.hi[a], p[a]);
          }
        }
    if (s.voxels == 0)
      throw std::logic_error("bigVolume: an empty shape");
    s.box = 0;
    for (int a = 0; a < 3; ++a)
      s.box |= (uint32_t(s.lo[a]) << (4 * a)) | (uint32_t(s.hi[a]) << (12 + 4 * a));
  }
  return shapes;
}

// The record width bigVolume gives a grid of cells and a label count.
inline uint32_t recordBits(const std::array<int32_t, 3>& cells, uint32_t labelCount)
{
  svdag::Volume scratch;
  addShapes(scratch);
  const uint64_t cellCount = uint64_t(cells[0]) * uint64_t(cells[1]) * uint64_t(cells[2]);
  return svdag::layout::blockRecordBits(bitWidth(cellCount - 1),
    bitWidth(std::max(labelCount, 1u) - 1), scratch.widths.rootRefBits);
}

// A volume of cells[0] x cells[1] x cells[2] cells of 16^3 voxels (UInt32 labels 1..labelCount,
// background 0) where cell (x, y, z) holds place(x, y, z). place must be a pure function of the
// cell, is called twice per cell from several threads, and must use every label index at least
// once. threads 0: one per core.
template <typename Place>
svdag::Volume bigVolume(
  const std::array<int32_t, 3>& cells, uint32_t labelCount, const Place& place,
  unsigned threads = 0)
{
  if (threads == 0)
    threads = std::max(1u, std::thread::hardware_concurrency());
  svdag::Volume v;
  for (int a = 0; a < 3; ++a)
  {
    if (cells[a] < 1 || int64_t(cells[a]) * 16 > INT32_MAX)
      throw std::invalid_argument("bigVolume: cell counts must be in 1 .. (2^31 - 1) / 16");
    v.geometry.dims[a] = cells[a] * 16;
  }
  const uint64_t cellCount = v.geometry.cellCount();
  if (cellCount > (uint64_t(1) << 32) || labelCount == 0)
    throw std::invalid_argument("bigVolume: more than 2^32 cells, or no labels");
  v.scalarType = svdag::ScalarType::UInt32;
  v.background = 0;
  const std::vector<ShapeInfo> shapes = addShapes(v);
  v.widths.cellBits = bitWidth(cellCount - 1);
  v.widths.labelBits = bitWidth(labelCount - 1);
  const uint32_t recordBits = v.widths.blockBits();

  // Pass 1: blocks per z slice, hence where each slice's records start.
  const size_t slices = size_t(cells[2]);
  std::vector<uint64_t> first(slices + 1, 0);
  threadedFor(threads)(0, slices, 1, [&](uint64_t b, uint64_t e) {
    for (uint64_t z = b; z < e; ++z)
    {
      uint64_t n = 0;
      for (int32_t y = 0; y < cells[1]; ++y)
        for (int32_t x = 0; x < cells[0]; ++x)
          n += place(x, y, int32_t(z)).present ? 1 : 0;
      first[z + 1] = n;
    }
  });
  for (size_t z = 0; z < slices; ++z)
    first[z + 1] += first[z];
  v.blockCount = first[slices];
  v.blocks.assign(size_t((v.blockCount * recordBits + 31) / 32 + 1), 0u);

  // Pass 2: the records, and per slice each label's voxel count and bounds.
  struct LabelSum
  {
    uint64_t voxels = 0;
    std::array<int32_t, 6> bounds{ { INT32_MAX, INT32_MIN, INT32_MAX, INT32_MIN, INT32_MAX,
      INT32_MIN } };
  };
  std::vector<LabelSum> sums(slices * labelCount);
  std::vector<uint64_t> written(slices, 0);
  std::atomic<bool> unknown{ false };
  const svdag::FieldWidths w = v.widths;
  threadedFor(threads)(0, slices, 1, [&](uint64_t b, uint64_t e) {
    for (uint64_t z = b; z < e; ++z)
    {
      BitWriter out(v.blocks.data(), first[z] * recordBits);
      LabelSum* sum = &sums[size_t(z) * labelCount];
      uint64_t n = 0;
      for (int32_t y = 0; y < cells[1]; ++y)
      {
        for (int32_t x = 0; x < cells[0]; ++x)
        {
          const CellBlock c = place(x, y, int32_t(z));
          if (!c.present)
            continue;
          if (c.shape >= ShapeCount || c.label >= labelCount)
          {
            unknown = true; // thrown once the threads are done
            continue;
          }
          const ShapeInfo& s = shapes[c.shape];
          out.put(uint32_t(x + uint64_t(cells[0]) * (y + uint64_t(cells[1]) * z)), w.cellBits);
          out.put(s.box, svdag::layout::BLOCK_BOUNDS_BITS);
          out.put(c.label, w.labelBits);
          out.put(s.rootRef, w.rootRefBits);
          LabelSum& l = sum[c.label];
          l.voxels += s.voxels;
          const int32_t origin[3] = { 16 * x, 16 * y, 16 * int32_t(z) };
          for (int a = 0; a < 3; ++a)
          {
            l.bounds[2 * a] = std::min(l.bounds[2 * a], origin[a] + s.lo[a]);
            l.bounds[2 * a + 1] = std::max(l.bounds[2 * a + 1], origin[a] + s.hi[a]);
          }
          ++n;
        }
      }
      out.finish();
      written[z] = n;
    }
  });
  if (unknown)
    throw std::logic_error("bigVolume: place gave an unknown shape or label");
  for (size_t z = 0; z < slices; ++z)
  {
    if (written[z] != first[z + 1] - first[z])
      throw std::logic_error("bigVolume: place is not a pure function of the cell");
  }

  v.labels.resize(labelCount);
  for (uint32_t l = 0; l < labelCount; ++l)
  {
    LabelSum total;
    for (size_t z = 0; z < slices; ++z)
    {
      const LabelSum& s = sums[z * labelCount + l];
      total.voxels += s.voxels;
      for (int a = 0; a < 3; ++a)
      {
        total.bounds[2 * a] = std::min(total.bounds[2 * a], s.bounds[2 * a]);
        total.bounds[2 * a + 1] = std::max(total.bounds[2 * a + 1], s.bounds[2 * a + 1]);
      }
    }
    if (total.voxels == 0)
      throw std::logic_error("bigVolume: label " + std::to_string(l) + " holds no block");
    v.labels[l].value = l + 1;
    v.labels[l].voxels = total.voxels;
    v.labels[l].bounds = total.bounds;
  }
  return v;
}

// The shape and label bigVolume(blockCount, ...) gives the block of linear cell index i.
inline CellBlock hashedBlock(uint64_t i, uint32_t labelCount)
{
  const uint64_t h = hash64(i);
  return { true, pick(h, ShapeCount), pick(h >> 32, labelCount) };
}

// The grid bigVolume(blockCount) uses: near-cubic, at least blockCount cells.
inline std::array<int32_t, 3> cubicGrid(uint64_t blockCount)
{
  const int64_t c = std::max<int64_t>(1, int64_t(std::ceil(std::cbrt(double(blockCount)))));
  const int64_t layer = c * c;
  const int64_t layers = std::max<int64_t>(1, (int64_t(blockCount) + layer - 1) / layer);
  return { { int32_t(c), int32_t(c), int32_t(layers) } };
}

// blockCount blocks in the first blockCount cells (in cell order) of cubicGrid(blockCount), each of
// a shape and label hashed from its cell index (hashedBlock); the remaining cells are empty.
inline svdag::Volume bigVolume(uint64_t blockCount, uint32_t labelCount = 3, unsigned threads = 0)
{
  const std::array<int32_t, 3> cells = cubicGrid(blockCount);
  return bigVolume(cells, labelCount,
    [&](int32_t x, int32_t y, int32_t z) {
      const uint64_t i =
        uint64_t(x) + uint64_t(cells[0]) * (uint64_t(y) + uint64_t(cells[1]) * uint64_t(z));
      return i < blockCount ? hashedBlock(i, labelCount) : CellBlock();
    },
    threads);
}

} // namespace bigvolume
