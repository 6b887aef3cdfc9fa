#include "svdag/LeafSymmetry.h"

#include "svdag/Layout.h"

namespace svdag
{
namespace
{
// Whole masks through one table per symmetry and byte: built once from Layout.h's definition,
// the one the shaders use.
struct Tables
{
  uint64_t bytes[layout::LEAF_SYMMETRY_COUNT][8][256];
  uint32_t inverse[layout::LEAF_SYMMETRY_COUNT];

  Tables()
  {
    for (uint32_t s = 0; s < layout::LEAF_SYMMETRY_COUNT; ++s)
    {
      // Bit x of the stored mask lands on every child bit y whose voxel reads it.
      uint32_t destination[64];
      for (uint32_t y = 0; y < 64; ++y)
        destination[layout::leafSymmetryBit(s, y % 4, (y / 4) % 4, y / 16)] = y;
      for (uint32_t b = 0; b < 8; ++b)
        for (uint32_t v = 0; v < 256; ++v)
        {
          uint64_t out = 0;
          for (uint32_t k = 0; k < 8; ++k)
            if ((v >> k) & 1u)
              out |= uint64_t(1) << destination[8 * b + k];
          bytes[s][b][v] = out;
        }
    }
    for (uint32_t s = 0; s < layout::LEAF_SYMMETRY_COUNT; ++s)
      for (uint32_t t = 0; t < layout::LEAF_SYMMETRY_COUNT; ++t)
      {
        bool undoes = true;
        for (uint32_t b = 0; b < 64 && undoes; ++b)
          undoes = apply(t, apply(s, uint64_t(1) << b)) == uint64_t(1) << b;
        if (undoes)
        {
          inverse[s] = t;
          break;
        }
      }
  }

  uint64_t apply(uint32_t s, uint64_t mask) const
  {
    uint64_t out = 0;
    for (uint32_t b = 0; b < 8; ++b)
      out |= bytes[s][b][(mask >> (8 * b)) & 0xFFu];
    return out;
  }
};

const Tables& tables()
{
  static const Tables t; // 786 KiB, built on first use
  return t;
}
} // namespace

uint64_t leafUnderSymmetry(uint32_t s, uint64_t stored)
{
  return tables().apply(s, stored);
}

uint32_t inverseLeafSymmetry(uint32_t s)
{
  return tables().inverse[s];
}

CanonicalLeaf canonicalLeaf(uint64_t mask)
{
  const Tables& t = tables();
  CanonicalLeaf best;
  best.stored = ~uint64_t(0);
  uint32_t bestImage = 0;
  for (uint32_t u = 0; u < layout::LEAF_SYMMETRY_COUNT; ++u)
  {
    uint64_t image = t.apply(u, mask);
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
  best.symmetry = t.inverse[bestImage];
  return best;
}

} // namespace svdag
