// The 48 symmetries of a 4^3 leaf (Layout.h: leafSymmetryBit) on whole 64-bit masks, for the C++
// side: the builder stores one leaf per class of masks equal up to a symmetry and complement, and
// every reader turns a stored leaf back into its child's occupancy.
#pragma once

#include <cstdint>

namespace svdag
{

// The occupancy of a child reached under symmetry s (0..47) of the stored leaf mask `stored`:
// bit leafBit(x, y, z) of the result is bit leafSymmetryBit(s, x, y, z) of `stored`.
uint64_t leafUnderSymmetry(uint32_t s, uint64_t stored);
// All 48 at once, faster: images[s] == leafUnderSymmetry(s, mask).
void leafImages(uint64_t mask, uint64_t images[48]);
// The symmetry that undoes s: leafUnderSymmetry(inverseLeafSymmetry(s), leafUnderSymmetry(s, m))
// == m for every mask m.
uint32_t inverseLeafSymmetry(uint32_t s);
// The symmetry that does b, then a (both 0..47):
// leafUnderSymmetry(composeLeafSymmetries(a, b), m) == leafUnderSymmetry(a, leafUnderSymmetry(b, m))
// for every mask m.
uint32_t composeLeafSymmetries(uint32_t a, uint32_t b);

struct CanonicalLeaf
{
  uint64_t stored = 0;     // the class's stored mask: bit 0 clear, the smallest of the class
  uint32_t symmetry = 0;   // mask == leafUnderSymmetry(symmetry, stored) ^ (complement ? ~0 : 0)
  uint32_t complement = 0;
};
// The stored form of a mixed mask and how to get the mask back from it. Where several
// symmetries give the stored mask, the first in order wins, so equal masks get equal references.
CanonicalLeaf canonicalLeaf(uint64_t mask);

} // namespace svdag
