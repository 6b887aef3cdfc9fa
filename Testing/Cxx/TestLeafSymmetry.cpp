// The 48 leaf symmetries (Layout.h leafSymmetryBit, svdag/LeafSymmetry.h) against geometry worked
// out by hand, bit-by-bit evaluation of the definition, and the group's laws; canonicalLeaf
// against a brute force over every symmetry.
#include "svdag/Layout.h"
#include "svdag/LeafSymmetry.h"

#include <gtest/gtest.h>

#include <random>
#include <set>

namespace
{
using svdag::layout::leafBit;
using svdag::layout::leafSymmetryBit;
constexpr uint32_t Count = svdag::layout::LEAF_SYMMETRY_COUNT;

uint64_t voxel(uint32_t x, uint32_t y, uint32_t z)
{
  return uint64_t(1) << leafBit(x, y, z);
}

// The definition, one bit at a time: child voxel (x, y, z) reads stored bit leafSymmetryBit.
uint64_t slowly(uint32_t s, uint64_t stored)
{
  uint64_t out = 0;
  for (uint32_t z = 0; z < 4; ++z)
    for (uint32_t y = 0; y < 4; ++y)
      for (uint32_t x = 0; x < 4; ++x)
        if ((stored >> leafSymmetryBit(s, x, y, z)) & 1u)
          out |= voxel(x, y, z);
  return out;
}

std::vector<uint64_t> randomMasks()
{
  std::mt19937_64 rng(7);
  std::vector<uint64_t> masks = { 0, ~uint64_t(0), 1, uint64_t(1) << 63, 0x0123456789ABCDEFull };
  for (int i = 0; i < 200; ++i)
    masks.push_back(rng() & rng()); // sparser masks, as leaves on a surface
  return masks;
}
} // namespace

TEST(LeafSymmetry, MirrorsAndPermutationsMoveVoxelsAsWorkedOutByHand)
{
  EXPECT_EQ(svdag::leafUnderSymmetry(0, voxel(1, 2, 3)), voxel(1, 2, 3)); // identity
  EXPECT_EQ(svdag::leafUnderSymmetry(1, voxel(0, 0, 0)), voxel(3, 0, 0)); // mirror x
  EXPECT_EQ(svdag::leafUnderSymmetry(2, voxel(1, 0, 2)), voxel(1, 3, 2)); // mirror y
  EXPECT_EQ(svdag::leafUnderSymmetry(4, voxel(1, 1, 0)), voxel(1, 1, 3)); // mirror z
  // Permutation 021 (s = 8): the child's voxel (x, y, z) reads the stored voxel (x, z, y).
  EXPECT_EQ(svdag::leafUnderSymmetry(8, voxel(1, 2, 3)), voxel(1, 3, 2));
  // Permutation 120 (s = 24): child (x, y, z) reads stored (y, z, x).
  EXPECT_EQ(svdag::leafUnderSymmetry(24, voxel(1, 2, 3)), voxel(3, 1, 2));
}

TEST(LeafSymmetry, WholeMasksAgreeWithTheBitDefinitionAndFormAGroup)
{
  const std::vector<uint64_t> masks = randomMasks();
  std::set<std::vector<uint64_t>> distinct;
  for (uint32_t s = 0; s < Count; ++s)
  {
    std::vector<uint64_t> images;
    for (uint64_t m : masks)
    {
      const uint64_t image = svdag::leafUnderSymmetry(s, m);
      ASSERT_EQ(image, slowly(s, m)) << "symmetry " << s;
      uint64_t all[Count];
      svdag::leafImages(m, all);
      ASSERT_EQ(all[s], image) << "leafImages, symmetry " << s;
      EXPECT_EQ(__builtin_popcountll(image), __builtin_popcountll(m));
      EXPECT_EQ(svdag::leafUnderSymmetry(svdag::inverseLeafSymmetry(s), image), m);
      images.push_back(image);
    }
    distinct.insert(images);
    // Closure: applying two symmetries is one of the 48.
    for (uint32_t t = 0; t < Count; t += 7)
    {
      bool found = false;
      for (uint32_t u = 0; u < Count && !found; ++u)
      {
        found = true;
        for (uint64_t m : masks)
          found = found &&
            svdag::leafUnderSymmetry(t, svdag::leafUnderSymmetry(s, m)) == svdag::leafUnderSymmetry(u, m);
      }
      EXPECT_TRUE(found) << s << " then " << t;
    }
  }
  EXPECT_EQ(distinct.size(), size_t(Count));
}

// composeLeafSymmetries names the one symmetry that does two in turn, for every pair, against
// the bit-by-bit definition (slowly).
TEST(LeafSymmetry, ComposingTwoSymmetriesIsDoingThemInTurn)
{
  const std::vector<uint64_t> masks = randomMasks();
  for (uint32_t a = 0; a < Count; ++a)
    for (uint32_t b = 0; b < Count; ++b)
    {
      const uint32_t c = svdag::composeLeafSymmetries(a, b);
      ASSERT_LT(c, Count);
      for (uint64_t m : masks)
        ASSERT_EQ(slowly(c, m), slowly(a, slowly(b, m))) << a << " after " << b;
    }
  for (uint32_t s = 0; s < Count; ++s)
  {
    EXPECT_EQ(svdag::composeLeafSymmetries(svdag::inverseLeafSymmetry(s), s), 0u);
    EXPECT_EQ(svdag::composeLeafSymmetries(s, 0), s);
  }
}

TEST(LeafSymmetry, CanonicalLeafIsTheSmallestImageAndGivesTheMaskBack)
{
  for (uint64_t m : randomMasks())
  {
    if (m == 0 || m == ~uint64_t(0))
      continue; // only mixed leaves are stored
    uint64_t smallest = ~uint64_t(0);
    for (uint32_t s = 0; s < Count; ++s)
    {
      const uint64_t image = slowly(s, m);
      smallest = std::min(smallest, (image & 1u) ? ~image : image);
    }
    const svdag::CanonicalLeaf c = svdag::canonicalLeaf(m);
    EXPECT_EQ(c.stored, smallest);
    EXPECT_EQ(c.stored & 1u, 0u);
    EXPECT_LT(c.symmetry, Count);
    const uint64_t back = svdag::leafUnderSymmetry(c.symmetry, c.stored);
    EXPECT_EQ(c.complement ? ~back : back, m);
    // Every image of m has the same stored form.
    for (uint32_t s = 0; s < Count; s += 5)
      EXPECT_EQ(svdag::canonicalLeaf(slowly(s, m)).stored, c.stored);
  }
}
