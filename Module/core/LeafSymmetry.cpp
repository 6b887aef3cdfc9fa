#include "svdag/LeafSymmetry.h"

#include "svdag/Layout.h"

#include <algorithm>
#include <array>
#include <stdexcept>
#include <string>

namespace svdag
{
namespace
{
// Mirrors of a whole mask along one axis (bit x + 4 y + 16 z), by swapping bit groups.
uint64_t swapGroups(uint64_t m, uint64_t low, uint32_t shift)
{
  return ((m >> shift) & low) | ((m & low) << shift);
}
uint64_t mirrorX(uint64_t m)
{
  return swapGroups(swapGroups(m, 0x5555555555555555ull, 1), 0x3333333333333333ull, 2);
}
uint64_t mirrorY(uint64_t m)
{
  return swapGroups(swapGroups(m, 0x0F0F0F0F0F0F0F0Full, 4), 0x00FF00FF00FF00FFull, 8);
}
uint64_t mirrorZ(uint64_t m)
{
  return swapGroups(swapGroups(m, 0x0000FFFF0000FFFFull, 16), 0x00000000FFFFFFFFull, 32);
}
// `mirrored` where `yes` (0 or 1), else `m`: without a branch, as symmetries change from leaf
// to leaf.
uint64_t select(uint32_t yes, uint64_t mirrored, uint64_t m)
{
  return m ^ ((m ^ mirrored) & (uint64_t(0) - yes));
}

// Symmetry 8 p + m reads child voxel (x, y, z) from the stored voxel whose coordinate j is child
// coordinate p_j, mirrored where bit j of m is set: the stored mask mirrored along its axes j,
// then its axes permuted by p. Mirrors are shifts. A permutation of the axes permutes the six
// bits of a voxel's index, which a few exchanges of two index bits do (delta swaps: no table to
// miss the cache), found from Layout.h's definition, the one the shaders use.
struct Symmetries
{
  // Each exchange puts one index bit where it belongs for good, so five sort all six.
  static constexpr uint32_t Steps = 5;
  struct Exchange
  {
    uint64_t lower = 0; // voxels whose index has bit a set and bit b clear (a < b)
    uint32_t distance = 0; // 2^b - 2^a: where each goes
  };
  Exchange exchanges[layout::LEAF_SYMMETRY_COUNT / 8][Steps];
  uint8_t composition[layout::LEAF_SYMMETRY_COUNT][layout::LEAF_SYMMETRY_COUNT]; // [a][b]: a after b
  uint32_t inverse[layout::LEAF_SYMMETRY_COUNT];

  Symmetries()
  {
    for (uint32_t p = 0; p < layout::LEAF_SYMMETRY_COUNT / 8; ++p)
    {
      // Index bit k of a stored voxel is index bit target[k] of the child voxel it lands on.
      uint32_t target[6];
      for (uint32_t k = 0; k < 6; ++k)
      {
        const uint32_t i = 1u << k;
        uint32_t y = 0;
        while (layout::leafSymmetryBit(8 * p, y % 4, (y / 4) % 4, y / 16) != i)
          ++y;
        target[k] = uint32_t(__builtin_ctz(y));
      }
      uint32_t at[6] = { 0, 1, 2, 3, 4, 5 }; // where stored index bit k is after the exchanges
      uint32_t step = 0;
      for (uint32_t k = 0; k < 6; ++k)
      {
        if (at[k] == target[k])
          continue;
        const uint32_t a = std::min(at[k], target[k]), b = std::max(at[k], target[k]);
        for (uint32_t& position : at)
          position = position == a ? b : position == b ? a : position;
        Exchange& e = this->exchanges[p][step++];
        e.distance = (1u << b) - (1u << a);
        for (uint32_t q = 0; q < 64; ++q)
          if (((q >> a) & 1u) && !((q >> b) & 1u))
            e.lower |= uint64_t(1) << q;
      }
    }
    // Bit y of a child's mask under symmetry s reads bit source[s][y] of the stored mask.
    uint8_t source[layout::LEAF_SYMMETRY_COUNT][64];
    for (uint32_t s = 0; s < layout::LEAF_SYMMETRY_COUNT; ++s)
      for (uint32_t y = 0; y < 64; ++y)
        source[s][y] = uint8_t(layout::leafSymmetryBit(s, y % 4, (y / 4) % 4, y / 16));
    // The exchanges and mirrors above must be the definition for every symmetry: checked bit by
    // bit.
    for (uint32_t s = 0; s < layout::LEAF_SYMMETRY_COUNT; ++s)
      for (uint32_t y = 0; y < 64; ++y)
        if (apply(s, uint64_t(1) << source[s][y]) != uint64_t(1) << y)
          throw std::logic_error(
            "leaf symmetry " + std::to_string(s) + " is not a permutation after mirrors");
    // A symmetry moves voxel coordinates by an affine map, so where the voxels (0,0,0), (1,0,0),
    // (0,1,0) and (0,0,1) (bits 0, 1, 4 and 16) read from tells the 48 apart.
    auto key = [](const auto& sourceOf) {
      return uint32_t(sourceOf(0)) | (uint32_t(sourceOf(1)) << 6) |
        (uint32_t(sourceOf(4)) << 12) | (uint32_t(sourceOf(16)) << 18);
    };
    std::array<std::pair<uint32_t, uint32_t>, layout::LEAF_SYMMETRY_COUNT> byKey; // key, symmetry
    for (uint32_t s = 0; s < layout::LEAF_SYMMETRY_COUNT; ++s)
      byKey[s] = { key([&](uint32_t y) { return source[s][y]; }), s };
    std::sort(byKey.begin(), byKey.end());
    for (size_t i = 1; i < byKey.size(); ++i)
      if (byKey[i].first == byKey[i - 1].first)
        throw std::logic_error("two leaf symmetries move the same voxels");
    // a after b: bit y reads bit source[a][y] of b's image, which reads bit source[b][that].
    for (uint32_t a = 0; a < layout::LEAF_SYMMETRY_COUNT; ++a)
      for (uint32_t b = 0; b < layout::LEAF_SYMMETRY_COUNT; ++b)
      {
        const uint32_t k = key([&](uint32_t y) { return source[b][source[a][y]]; });
        const auto found = std::lower_bound(
          byKey.begin(), byKey.end(), std::make_pair(k, uint32_t(0)));
        if (found == byKey.end() || found->first != k)
          throw std::logic_error("leaf symmetries not closed under composition");
        this->composition[a][b] = uint8_t(found->second);
        if (found->second == 0) // symmetry 0 moves nothing
          this->inverse[b] = a;
      }
  }

  uint64_t permute(uint32_t p, uint64_t mask) const
  {
    for (const Exchange& e : this->exchanges[p])
    {
      const uint64_t t = ((mask >> e.distance) ^ mask) & e.lower;
      mask ^= t ^ (t << e.distance);
    }
    return mask;
  }

  uint64_t apply(uint32_t s, uint64_t mask) const
  {
    mask = select(s & 1u, mirrorX(mask), mask);
    mask = select((s >> 1) & 1u, mirrorY(mask), mask);
    mask = select((s >> 2) & 1u, mirrorZ(mask), mask);
    return permute(s >> 3, mask);
  }
};

const Symmetries& symmetries()
{
  static const Symmetries t;
  return t;
}
} // namespace

void leafImages(uint64_t mask, uint64_t images[layout::LEAF_SYMMETRY_COUNT])
{
  // Symmetry 8 p + m: stored coordinate j is child coordinate p_j (permutation p), mirrored when
  // bit j of m is set. So its image is the permuted mask (symmetry 8 p) mirrored along child
  // axis p_j for every set bit j: one permutation per p, then a mirror per image.
  const Symmetries& t = symmetries();
  for (uint32_t p = 0; p < layout::LEAF_SYMMETRY_COUNT / 8; ++p)
  {
    const uint64_t permuted = t.permute(p, mask);
    uint32_t childAxis[3];
    for (uint32_t j = 0; j < 3; ++j)
      childAxis[j] = layout::leafSymmetryCoordinate(8 * p, j, 0, 1, 2);
    for (uint32_t m = 0; m < 8; ++m)
    {
      uint64_t image = permuted;
      for (uint32_t j = 0; j < 3; ++j)
        if ((m >> j) & 1u)
          image = childAxis[j] == 0 ? mirrorX(image) : childAxis[j] == 1 ? mirrorY(image) : mirrorZ(image);
      images[8 * p + m] = image;
    }
  }
}

uint64_t leafUnderSymmetry(uint32_t s, uint64_t stored)
{
  return symmetries().apply(s, stored);
}

uint32_t inverseLeafSymmetry(uint32_t s)
{
  return symmetries().inverse[s];
}

uint32_t composeLeafSymmetries(uint32_t a, uint32_t b)
{
  return symmetries().composition[a][b];
}

CanonicalLeaf canonicalLeaf(uint64_t mask)
{
  uint64_t images[layout::LEAF_SYMMETRY_COUNT];
  leafImages(mask, images);
  CanonicalLeaf best;
  best.stored = ~uint64_t(0);
  uint32_t bestImage = 0;
  for (uint32_t u = 0; u < layout::LEAF_SYMMETRY_COUNT; ++u)
  {
    uint64_t image = images[u];
    const uint32_t complement = uint32_t(image & 1u);
    if (complement)
      image = ~image;
    if (image < best.stored)
    {
      best.stored = image;
      best.complement = complement;
      bestImage = u;
    }
  }
  best.symmetry = symmetries().inverse[bestImage];
  return best;
}

} // namespace svdag
