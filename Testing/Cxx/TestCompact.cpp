// The compact form (Layout.h, Compact.h) against the pooled form it is made from: the same
// occupancy through either form's lookups, the sizes its definition gives (counted from the
// pooled references, independently of the packer), the round trip pooled <-> compact, and
// corrupt compact streams refused without reading out of bounds.
#include "svdag/Builder.h"
#include "svdag/Compact.h"
#include "svdag/Decoder.h"

#include <gtest/gtest.h>

#include <map>
#include <random>
#include <vector>

namespace
{
using svdag::ScalarType;

svdag::Geometry dims(int x, int y, int z)
{
  svdag::Geometry g;
  g.dims = { { x, y, z } };
  return g;
}

// Cells with labels in blobs, some noise, and repeats (shared leaves and mids) at odd sizes.
svdag::Volume sample(int seed, int nx, int ny, int nz)
{
  const svdag::Geometry g = dims(nx, ny, nz);
  std::vector<uint16_t> data(g.voxelCount());
  std::mt19937 rng{ uint32_t(seed) };
  std::vector<std::array<int, 4>> seeds(30);
  for (auto& s : seeds)
    s = { int(rng() % uint32_t(nx)), int(rng() % uint32_t(ny)), int(rng() % uint32_t(nz)), int(rng() % 7) };
  size_t i = 0;
  for (int z = 0; z < nz; ++z)
    for (int y = 0; y < ny; ++y)
      for (int x = 0; x < nx; ++x, ++i)
      {
        int best = 0, bestD = 1 << 30;
        for (const auto& s : seeds)
        {
          const int d = (x - s[0]) * (x - s[0]) + (y - s[1]) * (y - s[1]) + (z - s[2]) * (z - s[2]);
          if (d < bestD)
            bestD = d, best = s[3];
        }
        data[i] = rng() % 53 == 0 ? uint16_t(rng() % 9) : uint16_t(((x / 4 + y / 4) % 3 == 0) ? 8 : best);
      }
  return svdag::Builder::build(g, ScalarType::UInt16, data.data());
}

uint32_t width(uint64_t v)
{
  uint32_t w = 0;
  for (; v; v >>= 1)
    ++w;
  return w;
}

TEST(Compact, HoldsThePooledOccupancyInTheSizesItsDefinitionGives)
{
  for (int seed : { 1, 2, 3 })
  {
    SCOPED_TRACE("seed " + std::to_string(seed));
    const svdag::Volume compact = sample(seed, 45, 38, 51);
    ASSERT_EQ(compact.form, svdag::DagForm::Compact);
    const svdag::Volume pool = svdag::pooled(compact);
    ASSERT_EQ(pool.form, svdag::DagForm::Pooled);
    ASSERT_NO_THROW(pool.validate());
    EXPECT_TRUE(svdag::compacted(pool) == compact);

    // The same 64 leaf masks of every block through the pooled and the compact lookups.
    ASSERT_EQ(pool.blockCount, compact.blockCount);
    for (uint64_t b = 0; b < pool.blockCount; ++b)
    {
      uint64_t a[64], c[64];
      pool.leafMasks(b, a);
      compact.leafMasks(b, c);
      ASSERT_TRUE(std::equal(a, a + 64, c)) << "block " << b;
      ASSERT_EQ(pool.block(b).cell, compact.block(b).cell);
      ASSERT_EQ(pool.block(b).label, compact.block(b).label);
    }

    // Counted from the pooled references: leaves and mids used once become flagged children.
    std::vector<uint32_t> leafUses(pool.leaves.size());
    std::map<uint64_t, uint32_t> midUses;
    std::vector<uint32_t> midChildren; // mixed children per pooled mid
    uint64_t at = 0;
    for (uint64_t m = 0; m < pool.midCount; ++m)
    {
      const uint32_t k = svdag::layout::bitCount(svdag::layout::nodeMixedMask(svdag::Volume::nodeHeader(pool.mids, at)));
      for (uint32_t r = 0; r < k; ++r)
        ++leafUses[svdag::layout::leafRefIndex(svdag::Volume::nodeChildRef(pool.mids, at, r, pool.widths.leafRefBits))];
      midChildren.push_back(k);
      at += svdag::Volume::nodeBits(pool.mids, at, pool.widths.leafRefBits);
    }
    at = 0;
    uint64_t rootBits = 0;
    std::vector<std::vector<uint64_t>> rootTargets;
    for (uint64_t n = 0; n < pool.rootCount; ++n)
    {
      const uint32_t k = svdag::layout::bitCount(svdag::layout::nodeMixedMask(svdag::Volume::nodeHeader(pool.roots, at)));
      rootTargets.emplace_back();
      for (uint32_t r = 0; r < k; ++r)
      {
        const uint64_t target = svdag::layout::refTarget(svdag::Volume::nodeChildRef(pool.roots, at, r, pool.widths.midRefBits));
        ++midUses[target];
        rootTargets.back().push_back(target);
      }
      at += svdag::Volume::nodeBits(pool.roots, at, pool.widths.midRefBits);
    }
    uint64_t shared = 0;
    for (uint32_t u : leafUses)
      shared += u > 1;
    EXPECT_EQ(compact.leaves.size(), shared);
    const uint32_t leafRefBits = width(shared ? shared - 1 : 0) + 7;
    EXPECT_EQ(compact.widths.leafRefBits, leafRefBits);
    // Mid bits: masks, a flag per mixed child, a reference per shared leaf, 64 per inline one.
    uint64_t midBits = 0;
    at = 0;
    for (uint64_t m = 0; m < pool.midCount; ++m)
    {
      midBits += 16 + midChildren[m];
      for (uint32_t r = 0; r < midChildren[m]; ++r)
        midBits += leafUses[svdag::layout::leafRefIndex(svdag::Volume::nodeChildRef(pool.mids, at, r,
                     pool.widths.leafRefBits))] > 1 ? leafRefBits : 64;
      at += svdag::Volume::nodeBits(pool.mids, at, pool.widths.leafRefBits);
    }
    EXPECT_EQ(compact.mids.size(), (midBits + 31) / 32 + 1);
    // Root bits: masks, a flag per mixed child, a base if any mid is used once, a reference per
    // shared mid (the mid reference width follows from the compact mid stream).
    const uint32_t midRefBits = compact.widths.midRefBits;
    EXPECT_LE(midRefBits, width(midBits) + 1);
    for (const auto& targets : rootTargets)
    {
      uint64_t once = 0;
      for (uint64_t t : targets)
        once += midUses[t] == 1;
      rootBits += 16 + targets.size() + (once ? midRefBits - 1 : 0) + (targets.size() - once) * midRefBits;
    }
    EXPECT_EQ(compact.roots.size(), (rootBits + 31) / 32 + 1);
    EXPECT_LT(compact.memory().total(), pool.memory().total());
  }
}

TEST(Compact, EveryVoxelDecodesAsThePooledForm)
{
  const svdag::Volume compact = sample(7, 70, 33, 40);
  const svdag::Volume pool = svdag::pooled(compact);
  std::vector<uint16_t> a(size_t(compact.geometry.voxelCount())), b(a.size());
  svdag::decode(compact, a.data());
  svdag::decode(pool, b.data());
  EXPECT_TRUE(a == b);
  for (int i = 0; i < 2000; ++i)
  {
    const int x = i * 37 % 70, y = i * 11 % 33, z = i * 7 % 40;
    ASSERT_EQ(compact.labelAt(x, y, z), pool.labelAt(x, y, z));
  }
}

TEST(Compact, EdgeCasesRoundTrip)
{
  // No blocks; one solid label (complemented empty roots, no mids); a checkerboard (one leaf
  // shared everywhere, complements).
  const svdag::Geometry g = dims(20, 17, 33);
  std::vector<uint8_t> zeros(g.voxelCount()), ones(g.voxelCount(), 4), checker(g.voxelCount());
  for (int z = 0, i = 0; z < 33; ++z)
    for (int y = 0; y < 17; ++y)
      for (int x = 0; x < 20; ++x, ++i)
        checker[size_t(i)] = uint8_t((x + y + z) % 2 + 1);
  for (const auto* data : { &zeros, &ones, &checker })
  {
    const svdag::Volume c = svdag::Builder::build(g, ScalarType::UInt8, data->data());
    const svdag::Volume p = svdag::pooled(c);
    EXPECT_NO_THROW(p.validate());
    EXPECT_TRUE(svdag::compacted(p) == c);
    EXPECT_TRUE(svdag::pooled(p) == p); // each form is returned as it is
    EXPECT_TRUE(svdag::compacted(c) == c);
    std::vector<uint8_t> out(data->size());
    svdag::decode(c, out.data());
    EXPECT_TRUE(out == *data);
  }
}

// Random edits to a compact volume's streams: pooled() (and so validate() and the file writer)
// refuses them with a runtime_error or yields a volume that validates or is refused by
// validate(); none reads outside the streams (the sanitized build checks that).
TEST(Compact, CorruptStreamsAreRefusedCleanly)
{
  const svdag::Volume good = sample(11, 40, 40, 40);
  std::mt19937_64 rng(3);
  size_t refused = 0, accepted = 0;
  for (int i = 0; i < 600; ++i)
  {
    svdag::Volume bad = good;
    std::vector<uint32_t>& stream = i % 3 == 0 ? bad.roots : i % 3 == 1 ? bad.mids : bad.blocks;
    const size_t words = stream.size() - 1; // not the padding word
    stream[size_t(rng() % words)] ^= uint32_t(1) << (rng() % 32);
    if (i % 50 == 0)
      bad.widths.midRefBits = uint32_t(rng() % 40);
    try
    {
      svdag::pooled(bad).validate();
      ++accepted;
    }
    catch (const std::runtime_error&)
    {
      ++refused;
    }
    catch (const std::length_error&)
    {
      ++refused;
    }
  }
  EXPECT_GT(refused, accepted);
}

} // namespace
