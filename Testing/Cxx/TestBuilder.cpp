// Lossless round trips and structural invariants of the builder: every scalar type, odd shapes,
// label values at the type's limits, thread-count independence and exact deduplication.
#include "ThreadedFor.h"
#include "svdag/Builder.h"
#include "svdag/Compact.h"
#include "svdag/Decoder.h"
#include "svdag/LeafSymmetry.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <map>
#ifdef __GLIBC__
#include <malloc.h>
#endif
#include <random>
#include <set>
#include <tuple>

namespace
{
using svdag::ScalarType;

// Patterns of the values a volume of type t holds (sign-extended for signed types).
std::vector<uint64_t> typedPatterns(ScalarType t, const std::vector<int64_t>& values)
{
  std::vector<uint64_t> out;
  for (int64_t v : values)
  {
    uint64_t tmp = 0;
    svdag::scalarStore(t, &tmp, 0, uint64_t(v));
    out.push_back(svdag::scalarLoad(t, &tmp, 0));
  }
  return out;
}

struct Case
{
  std::string name;
  svdag::Geometry geometry;
  std::vector<uint64_t> labels; // patterns, x fastest
};

svdag::Geometry dims(int x, int y, int z)
{
  svdag::Geometry g;
  g.dims = { { x, y, z } };
  return g;
}

// Volumes exercising shapes and label patterns; values are patterns of type t.
std::vector<Case> cases(ScalarType t)
{
  std::vector<Case> out;
  std::mt19937_64 rng(7);
  const std::vector<uint64_t> extremes = typedPatterns(t,
    { 0, 1, -1, int64_t(svdag::scalarMin(t)), int64_t(svdag::scalarMax(t)),
      int64_t(svdag::scalarMax(t)) - 1, int64_t(svdag::scalarMin(t)) + 1 });
  auto add = [&](const std::string& name, svdag::Geometry g, auto value) {
    Case c{ name, g, {} };
    c.labels.resize(g.voxelCount());
    for (int z = 0, i = 0; z < g.dims[2]; ++z)
      for (int y = 0; y < g.dims[1]; ++y)
        for (int x = 0; x < g.dims[0]; ++x, ++i)
          c.labels[size_t(i)] = value(x, y, z);
    out.push_back(std::move(c));
  };
  add("1x1x1 background", dims(1, 1, 1), [](int, int, int) { return uint64_t(0); });
  add("1x1x1 label", dims(1, 1, 1), [&](int, int, int) { return extremes[4]; });
  add("1x1x40", dims(1, 1, 40), [&](int, int, int z) { return extremes[size_t(z) % extremes.size()]; });
  add("40x1x1", dims(40, 1, 1), [&](int x, int, int) { return extremes[size_t(x / 3) % extremes.size()]; });
  add("all background 37x21x19", dims(37, 21, 19), [](int, int, int) { return uint64_t(0); });
  add("full 32x32x32", dims(32, 32, 32), [&](int, int, int) { return extremes[1]; });
  add("full 17x33x40", dims(17, 33, 40), [&](int, int, int) { return extremes[2]; });
  add("checkerboard 19x18x17", dims(19, 18, 17),
    [&](int x, int y, int z) { return extremes[size_t((x + y + z) & 1) + 3]; });
  add("random extremes 37x21x19", dims(37, 21, 19),
    [&](int, int, int) { return extremes[rng() % extremes.size()]; });
  add("random 50 labels 33x17x49", dims(33, 17, 49), [&](int, int, int) {
    return typedPatterns(t, { int64_t(rng() % 50) - (svdag::scalarSigned(t) ? 25 : 0) })[0];
  });
  add("spheres 48x40x36", dims(48, 40, 36), [&](int x, int y, int z) {
    const int d2 = (x - 20) * (x - 20) + (y - 18) * (y - 18) + (z - 16) * (z - 16);
    return d2 < 100 ? extremes[3] : (d2 < 250 ? extremes[5] : uint64_t(0));
  });
  return out;
}

std::vector<uint8_t> toTyped(ScalarType t, const std::vector<uint64_t>& patterns)
{
  std::vector<uint8_t> out(patterns.size() * size_t(svdag::scalarSize(t)));
  for (size_t i = 0; i < patterns.size(); ++i)
    svdag::scalarStore(t, out.data(), i, patterns[i]);
  return out;
}

class EveryType : public ::testing::TestWithParam<ScalarType>
{
};

TEST_P(EveryType, RoundTripIsBitExact)
{
  const ScalarType t = GetParam();
  for (const Case& c : cases(t))
  {
    SCOPED_TRACE(c.name);
    const std::vector<uint8_t> input = toTyped(t, c.labels);
    const svdag::Volume v = svdag::Builder::build(c.geometry, t, input.data());
    EXPECT_NO_THROW(v.validate());
    std::vector<uint8_t> decoded(input.size(), 0xAB);
    svdag::decode(v, decoded.data());
    EXPECT_EQ(decoded, input);

    // Label table: sorted, exact counts and bounds, background not stored.
    std::map<uint64_t, uint64_t> counts;
    for (uint64_t l : c.labels)
      if (l != 0)
        ++counts[l];
    ASSERT_EQ(v.labels.size(), counts.size());
    uint64_t total = 0;
    for (const auto& info : v.labels)
    {
      EXPECT_EQ(info.voxels, counts[info.value]);
      total += info.voxels;
    }
    EXPECT_EQ(total, c.labels.size() - std::count(c.labels.begin(), c.labels.end(), 0u));
    for (size_t i = 1; i < v.labels.size(); ++i)
      EXPECT_TRUE(svdag::scalarLess(t, v.labels[i - 1].value, v.labels[i].value));

    // Blocks sorted by (cell, label): each cell's labels in table order, once each.
    for (uint64_t i = 1; i < v.blockCount; ++i)
    {
      const svdag::Block p = v.block(i - 1), b = v.block(i);
      ASSERT_TRUE(p.cell < b.cell || (p.cell == b.cell && p.label < b.label)) << "block " << i;
    }
    // The allocating decode gives the same bytes.
    EXPECT_EQ(svdag::decode(v), input);

    // Random access agrees with the dense volume.
    const auto& d = c.geometry.dims;
    for (int k = 0; k < d[2]; k += 3)
      for (int j = 0; j < d[1]; j += 2)
        for (int i = 0; i < d[0]; i += 5)
          ASSERT_EQ(v.labelAt(i, j, k), c.labels[size_t(i + d[0] * (j + d[1] * k))]);
  }
}

INSTANTIATE_TEST_SUITE_P(Builder, EveryType,
  ::testing::Values(ScalarType::Int8, ScalarType::UInt8, ScalarType::Int16, ScalarType::UInt16,
    ScalarType::Int32, ScalarType::UInt32, ScalarType::Int64, ScalarType::UInt64),
  [](const ::testing::TestParamInfo<ScalarType>& info) { return svdag::scalarName(info.param); });

TEST(Builder, LabelBoundsAreTight)
{
  svdag::Geometry g = dims(40, 30, 20);
  std::vector<uint16_t> data(g.voxelCount(), 0);
  // Label 7 occupies exactly x 3..35, y 5..6, z 17..19 (spans cells on x and z).
  for (int z = 17; z < 20; ++z)
    for (int y = 5; y < 7; ++y)
      for (int x = 3; x < 36; ++x)
        data[size_t(x + 40 * (y + 30 * z))] = 7;
  const svdag::Volume v = svdag::Builder::build(g, ScalarType::UInt16, data.data());
  ASSERT_EQ(v.labels.size(), 1u);
  const std::array<int32_t, 6> expected{ { 3, 35, 5, 6, 17, 19 } };
  EXPECT_EQ(v.labels[0].bounds, expected);
  EXPECT_EQ(v.labels[0].voxels, 33u * 2u * 3u);
  for (uint64_t b = 0; b < v.blockCount; ++b)
  {
    const svdag::Block blk = v.block(b);
    EXPECT_EQ(blk.lo[1], 5);
    EXPECT_EQ(blk.hi[1], 6);
  }
}

TEST(Builder, BackgroundAndExcludedLabels)
{
  svdag::Geometry g = dims(20, 18, 17);
  std::vector<int32_t> data(g.voxelCount());
  std::mt19937 rng(3);
  for (auto& x : data)
    x = int32_t(rng() % 6) - 2; // -2 .. 3
  svdag::BuildOptions options;
  options.background = uint64_t(int64_t(-2));
  options.excluded = { 3, uint64_t(int64_t(-1)) };
  const svdag::Volume v = svdag::Builder::build(g, ScalarType::Int32, data.data(), options);
  EXPECT_EQ(v.labels.size(), 3u); // 0, 1, 2
  std::vector<int32_t> decoded(data.size());
  svdag::decode(v, decoded.data());
  for (size_t i = 0; i < data.size(); ++i)
  {
    const int32_t expected = (data[i] == 3 || data[i] == -1) ? -2 : data[i];
    ASSERT_EQ(decoded[i], expected);
  }
}

TEST(Builder, OutputDoesNotDependOnThreads)
{
  svdag::Geometry g = dims(70, 50, 45);
  std::vector<uint32_t> data(g.voxelCount());
  std::mt19937 rng(11);
  // Blobs of labels so that nodes repeat within and across cells.
  for (int z = 0; z < 45; ++z)
    for (int y = 0; y < 50; ++y)
      for (int x = 0; x < 70; ++x)
        data[size_t(x + 70 * (y + 50 * z))] = uint32_t((x / 7 + 3 * (y / 5) + 11 * (z / 9)) % 13);
  const svdag::Volume one = svdag::Builder::build(g, ScalarType::UInt32, data.data());
  for (unsigned threads : { 2u, 3u, 8u })
  {
    const svdag::Volume many = svdag::Builder::build(
      g, ScalarType::UInt32, data.data(), {}, threadedFor(threads));
    EXPECT_TRUE(many == one) << threads << " threads changed the output";
  }
}

// Decodes every stored node and leaf; no two may be equal or complements of each other, and all
// must be canonical (voxel (0,0,0) empty).
TEST(Builder, NodesAreUniqueAndCanonical)
{
  svdag::Geometry g = dims(64, 64, 48);
  std::vector<uint16_t> data(g.voxelCount());
  std::mt19937 rng(5);
  std::vector<std::array<int, 4>> seeds(40);
  for (auto& s : seeds)
    s = { int(rng() % 64), int(rng() % 64), int(rng() % 48), int(rng() % 9) };
  for (int z = 0; z < 48; ++z)
    for (int y = 0; y < 64; ++y)
      for (int x = 0; x < 64; ++x)
      {
        int best = 0, bestD = 1 << 30;
        for (const auto& s : seeds)
        {
          const int d = (x - s[0]) * (x - s[0]) + (y - s[1]) * (y - s[1]) + (z - s[2]) * (z - s[2]);
          if (d < bestD)
            bestD = d, best = s[3];
        }
        data[size_t(x + 64 * (y + 64 * z))] = uint16_t(best);
      }
  // The pools as files store them (pooled() makes the built compact volume's nodes canonical
  // again: what the builder's pools held).
  const svdag::Volume v = svdag::pooled(svdag::Builder::build(g, ScalarType::UInt16, data.data()));
  v.validate();
  std::set<uint64_t> leaves;
  for (uint64_t m : v.leaves)
  {
    EXPECT_EQ(m & 1u, 0u) << "leaf not canonical";
    EXPECT_NE(m, 0u) << "empty leaf stored";
    EXPECT_TRUE(leaves.insert(m).second) << "duplicate leaf";
    EXPECT_EQ(leaves.count(~m), 0u) << "leaf stored with its complement";
    // One leaf per class: the smallest of its images under the 48 symmetries and complement.
    for (uint32_t s = 0; s < svdag::layout::LEAF_SYMMETRY_COUNT; ++s)
    {
      const uint64_t image = svdag::leafUnderSymmetry(s, m);
      EXPECT_LE(m, (image & 1u) ? ~image : image) << "leaf not its class's smallest mask";
    }
  }
  std::set<uint64_t> classes;
  for (uint64_t m : v.leaves)
    EXPECT_TRUE(classes.insert(svdag::canonicalLeaf(m).stored).second) << "two leaves of one class";
  auto nodes = [](const std::vector<uint32_t>& stream, uint64_t count, uint32_t refBits) {
    std::set<std::vector<uint32_t>> seen;
    uint64_t offset = 0;
    for (uint64_t n = 0; n < count; ++n)
    {
      const uint32_t header = svdag::Volume::nodeHeader(stream, offset);
      std::vector<uint32_t> key{ header };
      const uint32_t mixed = svdag::layout::nodeMixedMask(header);
      for (uint32_t r = 0; r < svdag::layout::bitCount(mixed); ++r)
        key.push_back(svdag::Volume::nodeChildRef(stream, offset, r, refBits));
      // Canonical: child 0 empty, or mixed through a plain (non-complemented) reference.
      EXPECT_FALSE(svdag::layout::nodeFullMask(header) & 1u);
      if (mixed & 1u)
        EXPECT_FALSE(svdag::layout::refComplement(key[1]));
      EXPECT_TRUE(seen.insert(key).second) << "duplicate node at bit " << offset;
      offset += svdag::Volume::nodeBits(stream, offset, refBits);
    }
    return offset;
  };
  EXPECT_EQ((nodes(v.mids, v.midCount, v.widths.leafRefBits) + 31) / 32 + 1, v.mids.size());
  EXPECT_EQ((nodes(v.roots, v.rootCount, v.widths.midRefBits) + 31) / 32 + 1, v.roots.size());
  // Sharing must actually happen on such a volume.
  EXPECT_LT(v.midCount, v.blockCount * 8);
}

TEST(Builder, RejectsBadGeometryAndSlabOrder)
{
  svdag::Geometry g = dims(0, 4, 4);
  EXPECT_THROW(svdag::Builder(g, ScalarType::UInt8), std::invalid_argument);
  g = dims(2147483647, 2147483647, 2147483647);
  EXPECT_THROW(svdag::Builder(g, ScalarType::UInt8), std::invalid_argument);
  g = dims(4, 4, 4);
  g.spacing[1] = -1;
  EXPECT_THROW(svdag::Builder(g, ScalarType::UInt8), std::invalid_argument);
  g = dims(4, 4, 40);
  svdag::Builder b(g, ScalarType::UInt8);
  std::vector<uint8_t> slab(4 * 4 * 16, 1);
  EXPECT_THROW(b.addSlab(16, 16, slab.data()), std::logic_error);
  b.addSlab(0, 16, slab.data());
  EXPECT_THROW(b.finish(), std::logic_error);
  EXPECT_THROW(b.addSlab(16, 8, slab.data()), std::logic_error);
}

TEST(Builder, DecodeSlabMatchesWholeDecode)
{
  svdag::Geometry g = dims(23, 19, 41);
  std::vector<uint8_t> data(g.voxelCount());
  std::mt19937 rng(2);
  for (auto& x : data)
    x = uint8_t(rng() % 4);
  const svdag::Volume v = svdag::Builder::build(g, ScalarType::UInt8, data.data());
  for (int z0 : { 0, 5, 16, 30 })
  {
    const int nz = std::min(13, 41 - z0);
    std::vector<uint8_t> part(size_t(23 * 19 * nz));
    svdag::decodeSlab(v, z0, nz, part.data(), threadedFor(2));
    EXPECT_TRUE(std::equal(part.begin(), part.end(), data.begin() + 23 * 19 * z0));
  }
}

// A cell-like volume of `labels` labels with ragged boundaries: boxes of blob^3 voxels, one
// voxel in `noise` switched to a neighbouring box's label at random, so that leaves, mids and
// roots are mostly unique.
std::vector<uint32_t> raggedCells(
  const svdag::Geometry& g, uint32_t labels, int blob, uint32_t noise, uint32_t seed)
{
  std::vector<uint32_t> data(g.voxelCount());
  std::mt19937 rng(seed);
  auto labelAt = [&](int x, int y, int z) {
    uint64_t h = uint64_t(x / blob) * 0x9E3779B97F4A7C15ULL ^
      uint64_t(y / blob) * 0xC2B2AE3D27D4EB4FULL ^ uint64_t(z / blob) * 0x165667B19E3779F9ULL;
    h ^= h >> 29;
    return uint32_t(1 + (h * 0xBF58476D1CE4E5B9ULL >> 40) % labels);
  };
  size_t i = 0;
  for (int z = 0; z < g.dims[2]; ++z)
    for (int y = 0; y < g.dims[1]; ++y)
      for (int x = 0; x < g.dims[0]; ++x, ++i)
        data[i] = (rng() % noise == 0) ? labelAt(x + 2, y, z + 1) : labelAt(x, y, z);
  return data;
}

// The builder keeps its pools bit-packed at the widths the counts need so far and widens them in
// place (leaf references in mid nodes, mid ids in roots, label and root ids in pending blocks)
// when a count crosses a power of two: every widening must keep the output lossless and exact.
TEST(Builder, PoolsWidenAcrossSlabs)
{
  const svdag::Geometry g = dims(96, 80, 72);
  const std::vector<uint32_t> data = raggedCells(g, 700, 6, 4, 5);
  svdag::Builder builder(g, ScalarType::UInt32);
  for (int32_t z0 = 0; z0 < g.dims[2]; z0 += svdag::Builder::SlabDepth)
    builder.addSlab(z0, std::min(svdag::Builder::SlabDepth, g.dims[2] - z0),
      data.data() + size_t(g.dims[0]) * size_t(g.dims[1]) * size_t(z0));
  const svdag::Volume v = builder.finishPooled();
  // Enough of everything that each width grew several times while slabs came in.
  ASSERT_GT(v.leaves.size(), 8192u);
  ASSERT_GT(v.midCount, 4096u);
  ASSERT_GT(v.rootCount, 1024u);
  ASSERT_GT(v.labels.size(), 512u);
  EXPECT_NO_THROW(v.validate());
  EXPECT_EQ(v.widths.leafRefBits, 1 + svdag::layout::LEAF_SYMMETRY_BITS +
      (32 - uint32_t(__builtin_clz(uint32_t(v.leaves.size() - 1)))));
  std::vector<uint32_t> decoded(data.size());
  svdag::decode(v, decoded.data());
  EXPECT_TRUE(decoded == data);
  const svdag::Volume threaded =
    svdag::Builder::build(g, ScalarType::UInt32, data.data(), {}, threadedFor(3));
  EXPECT_TRUE(threaded == svdag::compacted(v));
}

#ifdef __GLIBC__
size_t heapInUse()
{
  const struct mallinfo2 m = mallinfo2();
  return m.uordblks + m.hblkhd;
}

// The target: the builder's own state (the slab is the caller's) stays within 1.5x the
// compressed output plus a constant, measured after every slab. The constant covers the scan
// buffers of one row of cells (64 leaf masks per label per cell: with 10^3-voxel labels, about
// 20 labels in each of the row's 10 cells) and the pools' minimum sizes. (The old builder kept
// about 4.4x the output; the shared volumes measure 1.48-1.59x without a constant.)
TEST(Builder, StateStaysNearOutputSize)
{
  const svdag::Geometry g = dims(160, 160, 128);
  const std::vector<uint32_t> data = raggedCells(g, 900, 10, 4, 9);
  const size_t slice = size_t(g.dims[0]) * size_t(g.dims[1]);
  const size_t before = heapInUse();
  size_t peak = 0;
  svdag::Volume v;
  {
    svdag::Builder b(g, ScalarType::UInt32);
    for (int32_t z0 = 0; z0 < g.dims[2]; z0 += svdag::Builder::SlabDepth)
    {
      b.addSlab(z0, std::min(svdag::Builder::SlabDepth, g.dims[2] - z0), data.data() + slice * size_t(z0));
      peak = std::max(peak, heapInUse() - before);
    }
    v = b.finishPooled();
  }
  // The pools against the pooled output they become. The compact form handed out is 10-15%
  // smaller (here 715 KB against 826 KB, which puts this state at 1.59x it plus the constant):
  // the compaction shrinks the output after the pools, it does not change them.
  const double output = double(v.memory().total());
  ASSERT_GT(output, 8e5); // large enough that the constant does not decide the test
  const double constant = 256 * 1024;
  EXPECT_LE(double(peak), 1.5 * output + constant)
    << "builder state " << peak << " bytes for " << output << " bytes of output";
}
#endif
} // namespace

// The volumes of consecutive z-ranges, each built on its own, merged in z order.
namespace merge
{
// Splits the 16-slice slabs of dims[2] into `parts` ranges as even as possible (fewer if there
// are not enough slabs).
std::vector<std::pair<int, int>> zRanges(int nz, int parts)
{
  const int slabs = (nz + 15) / 16;
  parts = std::min(parts, slabs);
  std::vector<std::pair<int, int>> out;
  for (int p = 0, first = 0; p < parts; ++p)
  {
    const int count = slabs / parts + (p < slabs % parts ? 1 : 0);
    out.emplace_back(16 * first, std::min(nz, 16 * (first + count)));
    first += count;
  }
  return out;
}

svdag::Volume buildRange(const svdag::Geometry& whole, ScalarType t, const std::vector<uint8_t>& data,
  std::pair<int, int> range, const svdag::BuildOptions& options)
{
  svdag::Geometry g = whole;
  g.dims[2] = range.second - range.first;
  const size_t slice = size_t(whole.dims[0]) * size_t(whole.dims[1]) * size_t(svdag::scalarSize(t));
  return svdag::Builder::build(g, t, data.data() + slice * size_t(range.first), options);
}

// Merges parts [first, last) by halves, as a tree reduction does.
svdag::Volume mergeTree(const svdag::Geometry& whole, ScalarType t, const std::vector<svdag::Volume>& parts,
  size_t first, size_t last, const svdag::BuildOptions& options)
{
  if (last - first == 1)
    return parts[first];
  const size_t mid = first + (last - first) / 2;
  svdag::Volume lower = mergeTree(whole, t, parts, first, mid, options);
  svdag::Volume upper = mergeTree(whole, t, parts, mid, last, options);
  svdag::Geometry g = whole;
  g.dims[2] = lower.geometry.dims[2] + upper.geometry.dims[2];
  svdag::Builder b(g, t, options);
  b.addVolume(lower);
  b.addVolume(upper);
  return b.finish();
}
} // namespace merge

TEST_P(EveryType, MergedPartsEqualTheWholeBuild)
{
  const ScalarType t = GetParam();
  std::vector<Case> all = cases(t);
  // A tall case with labels shared across many slabs, so that every partition dedups nodes and
  // labels that an earlier part already holds.
  std::mt19937_64 rng(11);
  Case tall{ "tall 23x19x120", dims(23, 19, 120), {} };
  for (int z = 0; z < 120; ++z)
    for (int y = 0; y < 19; ++y)
      for (int x = 0; x < 23; ++x)
        tall.labels.push_back(typedPatterns(t, { ((x / 5 + y / 4 + z / 7) % 9) ? int64_t((x / 5 + 3 * (y / 4) + z / 30) % 13) : int64_t(rng() % 3) })[0]);
  all.push_back(tall);
  svdag::BuildOptions options;
  options.background = typedPatterns(t, { 1 })[0];
  options.excluded = typedPatterns(t, { 5 });
  for (const svdag::BuildOptions& opts : { svdag::BuildOptions{}, options })
  {
    for (const Case& c : all)
    {
      SCOPED_TRACE(c.name);
      const std::vector<uint8_t> input = toTyped(t, c.labels);
      const svdag::Volume whole = svdag::Builder::build(c.geometry, t, input.data(), opts);
      for (int parts : { 1, 2, 3, 7 })
      {
        SCOPED_TRACE(parts);
        std::vector<svdag::Volume> built;
        for (const auto& range : merge::zRanges(c.geometry.dims[2], parts))
          built.push_back(merge::buildRange(c.geometry, t, input, range, opts));
        // A chain (one builder fed every part, and slabs after a part) and a tree.
        svdag::Builder chain(c.geometry, t, opts);
        for (const svdag::Volume& part : built)
          chain.addVolume(part);
        svdag::Volume chained = chain.finish();
        ASSERT_NO_THROW(chained.validate());
        EXPECT_TRUE(chained == whole);
        svdag::Volume tree = merge::mergeTree(c.geometry, t, built, 0, built.size(), opts);
        EXPECT_TRUE(tree == whole);
      }
      if (c.geometry.dims[2] > 16)
      {
        // A part then slabs.
        svdag::Builder mixed(c.geometry, t, opts);
        mixed.addVolume(merge::buildRange(c.geometry, t, input, { 0, 16 }, opts));
        const size_t slice = size_t(c.geometry.dims[0]) * size_t(c.geometry.dims[1]) * size_t(svdag::scalarSize(t));
        for (int z0 = 16; z0 < c.geometry.dims[2]; z0 += 16)
          mixed.addSlab(z0, std::min(16, c.geometry.dims[2] - z0), input.data() + slice * size_t(z0));
        EXPECT_TRUE(mixed.finish() == whole);
      }
    }
  }
}

TEST(Builder, AddVolumeRejectsPartsThatDoNotFit)
{
  std::vector<uint8_t> data(8 * 8 * 40, 3);
  const svdag::Volume whole = svdag::Builder::build(dims(8, 8, 40), ScalarType::UInt8, data.data());
  const svdag::Volume slab = svdag::Builder::build(dims(8, 8, 16), ScalarType::UInt8, data.data());
  const svdag::Volume tail = svdag::Builder::build(dims(8, 8, 8), ScalarType::UInt8, data.data());
  {
    svdag::Builder b(dims(8, 9, 40), ScalarType::UInt8);
    EXPECT_THROW(b.addVolume(slab), std::invalid_argument); // other y size
  }
  {
    svdag::Builder b(dims(8, 8, 40), ScalarType::Int8);
    EXPECT_THROW(b.addVolume(slab), std::invalid_argument); // other type
  }
  {
    svdag::BuildOptions other;
    other.background = 7;
    svdag::Builder b(dims(8, 8, 40), ScalarType::UInt8, other);
    EXPECT_THROW(b.addVolume(slab), std::invalid_argument); // other background
  }
  {
    svdag::BuildOptions excluding;
    excluding.excluded = { 3 };
    svdag::Builder b(dims(8, 8, 40), ScalarType::UInt8, excluding);
    EXPECT_THROW(b.addVolume(slab), std::invalid_argument); // holds an excluded label
  }
  {
    svdag::Builder b(dims(8, 8, 40), ScalarType::UInt8);
    EXPECT_THROW(b.addVolume(tail), std::logic_error); // 8 slices, not the last ones
    b.addVolume(slab);
    b.addVolume(slab);
    EXPECT_THROW(b.addVolume(slab), std::logic_error); // 16 slices, 8 left
    b.addVolume(tail);
    EXPECT_TRUE(b.finish() == whole);
  }
  {
    svdag::Builder b(dims(8, 8, 40), ScalarType::UInt8);
    b.addSlab(0, 16, data.data());
    b.addSlab(16, 16, data.data());
    b.addSlab(32, 8, data.data());
    EXPECT_THROW(b.addVolume(tail), std::logic_error); // nothing left
  }
}

TEST(Builder, PiecesShareOutWholeSlabsInOrder)
{
  // 70 slices: 5 slabs; 3 pieces take 2, 2 and 1 of them, the last one 6 slices deep.
  using R = std::array<int32_t, 2>;
  EXPECT_EQ(svdag::Builder::pieceZRange(70, 0, 3), (R{ { 0, 32 } }));
  EXPECT_EQ(svdag::Builder::pieceZRange(70, 1, 3), (R{ { 32, 64 } }));
  EXPECT_EQ(svdag::Builder::pieceZRange(70, 2, 3), (R{ { 64, 70 } }));
  EXPECT_EQ(svdag::Builder::pieceZRange(70, 0, 1), (R{ { 0, 70 } }));
  // More pieces than slabs: the last ones are empty.
  EXPECT_EQ(svdag::Builder::pieceZRange(20, 1, 4), (R{ { 16, 20 } }));
  EXPECT_EQ(svdag::Builder::pieceZRange(20, 2, 4), (R{ { 0, 0 } }));
  EXPECT_THROW(svdag::Builder::pieceZRange(20, 4, 4), std::invalid_argument);
  EXPECT_THROW(svdag::Builder::pieceZRange(20, -1, 4), std::invalid_argument);
  EXPECT_THROW(svdag::Builder::pieceZRange(20, 0, 0), std::invalid_argument);

  svdag::Geometry g;
  g.dims = { { 4, 5, 70 } };
  g.spacing = { { 1, 1, 2 } };
  g.origin = { { 1, 2, 3 } };
  g.direction = { { 0, 0, -1, 0, 1, 0, 1, 0, 0 } }; // the third axis points along -x
  const svdag::Geometry part = g.zRange(32, 64);
  EXPECT_EQ(part.dims, (std::array<int32_t, 3>{ { 4, 5, 32 } }));
  EXPECT_EQ(part.origin, (std::array<double, 3>{ { 1 - 64, 2, 3 } }));
  EXPECT_EQ(part.direction, g.direction);
  EXPECT_THROW(g.zRange(64, 71), std::out_of_range);
  EXPECT_THROW(g.zRange(10, 9), std::out_of_range);
}
