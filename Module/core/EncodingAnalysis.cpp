#include "svdag/EncodingAnalysis.h"
#include "svdag/Compact.h"

#include "Bits.h"
#include "svdag/LeafSymmetry.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <stdexcept>
#include <unordered_set>
#include <vector>

namespace svdag
{

const char* encodingLevelName(EncodingLevel level)
{
  switch (level)
  {
    case EncodingLevel::Blocks:
      return "blocks";
    case EncodingLevel::Roots:
      return "roots";
    case EncodingLevel::Mids:
      return "mids";
    case EncodingLevel::Leaves:
      return "leaves";
  }
  return "?";
}

namespace
{
constexpr uint32_t SymmetryCount = layout::LEAF_SYMMETRY_COUNT; // 6 permutations x 8 mirrors
constexpr uint32_t MirrorCount = 8; // transforms 0..7: the identity permutation, every mirror
constexpr uint32_t MirrorRefBits = 3;
constexpr uint32_t SymmetryRefBits = layout::LEAF_SYMMETRY_BITS;

using bits::bitWidth;
using bits::mix64;

// Transform t maps a node N to N' with N'(y) = N(A(y)) (Layout.h, leafSymmetryBit: A permutes
// and mirrors the axes). The same A acts on the octants of a node and inside each child, so N'
// has at octant o the transform of N's child at A(o); leaves go through leafUnderSymmetry.
struct Symmetries
{
  uint8_t octant[SymmetryCount][8];

  Symmetries()
  {
    for (uint32_t t = 0; t < SymmetryCount; ++t)
      for (uint32_t o = 0; o < 8; ++o)
      {
        // Octant o's corner voxel in a 4^3 leaf: A keeps or mirrors each half.
        const uint32_t x = 2 * (o & 1u), y = 2 * ((o >> 1) & 1u), z = 2 * (o >> 2);
        uint32_t a[3];
        for (uint32_t j = 0; j < 3; ++j)
          a[j] = layout::leafSymmetryCoordinate(t, j, x, y, z) >> 1;
        octant[t][o] = uint8_t(a[0] + 2 * a[1] + 4 * a[2]);
      }
  }
};

// A node's children: mixed and full masks, and per mixed child its target index and complement.
struct Node
{
  uint32_t mixed = 0, full = 0;
  uint32_t firstChild = 0; // into the level's child arrays, in child order
};

struct Level
{
  std::vector<Node> nodes;
  std::vector<uint32_t> childTarget;    // index of the child node
  std::vector<uint8_t> childComplement;
  std::vector<uint64_t> childLeaf;      // mids only: the child's occupancy (leafMask of its ref)
  std::vector<uint64_t> offsets; // bit offsets in the stream, ascending
  uint64_t bits = 0;
};

// childIndex turns a child reference into the child's index (throws if there is none).
Level readLevel(const std::vector<uint32_t>& stream, uint64_t count, uint32_t refBits,
  const std::function<uint32_t(uint32_t)>& childIndex)
{
  Level level;
  level.nodes.resize(count);
  level.offsets.resize(count);
  uint64_t at = 0;
  for (uint64_t i = 0; i < count; ++i)
  {
    const uint32_t header = Volume::nodeHeader(stream, at);
    Node& n = level.nodes[i];
    n.mixed = layout::nodeMixedMask(header);
    n.full = layout::nodeFullMask(header);
    n.firstChild = uint32_t(level.childTarget.size());
    const uint32_t k = layout::bitCount(n.mixed);
    for (uint32_t r = 0; r < k; ++r)
    {
      const uint32_t ref = Volume::nodeChildRef(stream, at, r, refBits);
      level.childTarget.push_back(childIndex(ref));
      level.childComplement.push_back(layout::refComplement(ref) ? 1 : 0);
    }
    level.offsets[i] = at;
    at += Volume::nodeBits(stream, at, refBits);
  }
  level.bits = at;
  return level;
}

uint32_t indexOfOffset(const std::vector<uint64_t>& offsets, uint64_t offset)
{
  auto it = std::lower_bound(offsets.begin(), offsets.end(), offset);
  if (it == offsets.end() || *it != offset)
    throw std::runtime_error("analyzeEncoding: a reference is not at a node start");
  return uint32_t(it - offsets.begin());
}

// Hash of the canonical form of transform t of a node whose children's transformed hashes come
// from childKey(child slot, t) (flag in bit 0: the transformed child was complemented to make it
// canonical). Returns the hash with bit 0 = whether this node was complemented.
template <class ChildKey>
uint64_t transformedNode(const Symmetries& s, uint32_t t, const Level& level, const Node& n,
  const ChildKey& childKey)
{
  uint32_t mixed = 0, full = 0;
  uint64_t keys[8] = {};
  uint8_t complements[8] = {};
  uint32_t rankOf[8];
  {
    uint32_t rank = 0;
    for (uint32_t o = 0; o < 8; ++o)
      rankOf[o] = (n.mixed >> o) & 1u ? rank++ : 0;
  }
  for (uint32_t o = 0; o < 8; ++o)
  {
    const uint32_t src = s.octant[t][o];
    if ((n.mixed >> src) & 1u)
    {
      const uint32_t c = n.firstChild + rankOf[src];
      const uint64_t key = childKey(c, t);
      mixed |= 1u << o;
      keys[o] = key & ~uint64_t(1);
      complements[o] = uint8_t(level.childComplement[c] ^ (key & 1u));
    }
    else if ((n.full >> src) & 1u)
      full |= 1u << o;
  }
  // Canonical: voxel (0,0,0), in octant 0, empty; else store the complement.
  const bool flip = (full & 1u) || ((mixed & 1u) && complements[0]);
  if (flip)
  {
    full = ~(mixed | full) & 0xFFu;
    for (uint32_t o = 0; o < 8; ++o)
      complements[o] ^= 1u;
  }
  uint64_t h = mix64(uint64_t(mixed) | uint64_t(full) << 8 | uint64_t(0x5a) << 16);
  for (uint32_t o = 0; o < 8; ++o)
    if ((mixed >> o) & 1u)
      h = mix64(h ^ (keys[o] + complements[o] + o));
  return (h & ~uint64_t(1)) | (flip ? 1u : 0u);
}

uint64_t complementCanonical(uint64_t mask, uint64_t& flip)
{
  flip = mask & 1u;
  return flip ? ~mask : mask;
}

// Counts of the incoming references of each node -> the level's skew figures.
void incomingStatistics(std::vector<uint64_t> counts, LevelAnalysis& out)
{
  std::sort(counts.begin(), counts.end(), std::greater<uint64_t>());
  uint64_t total = 0;
  for (uint64_t c : counts)
    total += c;
  out.incomingReferences = total;
  if (counts.empty() || total == 0)
    return;
  out.maxIncoming = counts.front();
  out.referencedOnce = uint64_t(std::count(counts.begin(), counts.end(), uint64_t(1)));
  auto share = [&](double fraction) {
    const size_t k = std::max<size_t>(1, size_t(std::ceil(fraction * double(counts.size()))));
    uint64_t s = 0;
    for (size_t i = 0; i < k && i < counts.size(); ++i)
      s += counts[i];
    return double(s) / double(total);
  };
  out.top1PercentShare = share(0.01);
  out.top10PercentShare = share(0.10);
  double entropy = 0;
  for (uint64_t c : counts)
    if (c)
    {
      const double p = double(c) / double(total);
      entropy -= p * std::log2(p);
    }
  out.referenceEntropyBits = entropy;
}

// Classes of a level under the first `transforms` symmetries (min hash over them) and the bits of
// the shared level: nodeBits(i) for one representative of each class.
template <class Key, class Bits>
std::pair<uint64_t, uint64_t> classes(uint64_t count, uint32_t transforms, const Key& key,
  const Bits& nodeBits)
{
  std::unordered_set<uint64_t> seen;
  seen.reserve(size_t(count));
  uint64_t bits = 0;
  for (uint64_t i = 0; i < count; ++i)
  {
    uint64_t best = ~uint64_t(0);
    for (uint32_t t = 0; t < transforms; ++t)
      best = std::min(best, key(i, t));
    if (seen.insert(best).second)
      bits += nodeBits(i);
  }
  return { uint64_t(seen.size()), bits };
}

uint32_t sharedRefWidth(uint64_t targetUnits, uint32_t transformBits)
{
  // A reference names a target (index or bit offset), its complement and the transform.
  return bitWidth(targetUnits ? targetUnits - 1 : 0) + 1 + transformBits;
}
} // namespace

EncodingAnalysis analyzeEncoding(const Volume& volume, const ParallelFor& parallel)
{
  // The DAG's nodes and references, each node once (the compact form's chained and inline
  // children are nodes of their pools there).
  Volume holder;
  const Volume& v = pooledView(volume, holder);
  EncodingAnalysis a;
  a.labelTableBytes = v.memory().labels;
  {
    const MemoryUsage held =
      volume.form == DagForm::Compact ? volume.memory() : compacted(volume).memory();
    a[EncodingLevel::Blocks].compactBytes = held.blocks;
    a[EncodingLevel::Roots].compactBytes = held.roots;
    a[EncodingLevel::Mids].compactBytes = held.mids;
    a[EncodingLevel::Leaves].compactBytes = held.leaves;
  }

  const Symmetries sym;

  const uint64_t leafCount = v.leaves.size();
  // Each mid child's occupancy (its stored leaf under the reference's symmetry), in child order.
  std::vector<uint64_t> childLeaf;
  Level mids = readLevel(v.mids, v.midCount, v.widths.leafRefBits, [&](uint32_t ref) {
    if (layout::leafRefIndex(ref) >= leafCount ||
      layout::leafRefSymmetry(ref) >= layout::LEAF_SYMMETRY_COUNT)
      throw std::runtime_error("analyzeEncoding: a leaf reference is out of range");
    childLeaf.push_back(v.leafMask(ref));
    return layout::leafRefIndex(ref);
  });
  mids.childLeaf = std::move(childLeaf);
  Level roots = readLevel(v.roots, v.rootCount, v.widths.midRefBits,
    [&](uint32_t ref) { return indexOfOffset(mids.offsets, layout::refTarget(ref)); });
  std::vector<uint32_t> blockRoot(size_t(v.blockCount));
  for (uint64_t i = 0; i < v.blockCount; ++i)
    blockRoot[i] = indexOfOffset(roots.offsets, layout::refTarget(v.block(i).root));

  // What is stored today.
  LevelAnalysis& B = a[EncodingLevel::Blocks];
  LevelAnalysis& R = a[EncodingLevel::Roots];
  LevelAnalysis& M = a[EncodingLevel::Mids];
  LevelAnalysis& L = a[EncodingLevel::Leaves];
  B.nodes = v.blockCount;
  B.referenceWidth = v.widths.rootRefBits;
  B.references = v.blockCount;
  B.referenceBits = B.references * B.referenceWidth;
  B.bits = v.blockCount * v.widths.blockBits();
  B.headerBits = B.bits - B.referenceBits;
  auto nodeLevel = [](const Level& level, uint32_t width, LevelAnalysis& out) {
    out.nodes = level.nodes.size();
    out.bits = level.bits;
    out.headerBits = out.nodes * layout::NODE_HEADER_BITS;
    out.references = level.childTarget.size();
    out.referenceWidth = width;
    out.referenceBits = out.references * width;
  };
  nodeLevel(roots, v.widths.midRefBits, R);
  nodeLevel(mids, v.widths.leafRefBits, M);
  L.nodes = leafCount;
  L.bits = L.headerBits = leafCount * 64;

  // Skew of the references into each level.
  {
    std::vector<uint64_t> counts(roots.nodes.size());
    for (uint32_t r : blockRoot)
      ++counts[r];
    incomingStatistics(std::move(counts), R);
  }
  auto countTargets = [](const Level& parents, size_t n) {
    std::vector<uint64_t> counts(n);
    for (uint32_t c : parents.childTarget)
      ++counts[c];
    return counts;
  };
  incomingStatistics(countTargets(roots, mids.nodes.size()), M);
  incomingStatistics(countTargets(mids, size_t(leafCount)), L);

  // Symmetry classes, bottom up. Leaves: exact canonical masks.
  auto maskKey = [&](uint64_t mask, uint32_t t) {
    uint64_t flip;
    const uint64_t m = complementCanonical(leafUnderSymmetry(t, mask), flip);
    return (mix64(m) & ~uint64_t(1)) | flip;
  };
  auto leafKey = [&](uint32_t leaf, uint32_t t) { return maskKey(v.leaves[leaf], t); };
  auto midChildKey = [&](uint32_t slot, uint32_t t) { return maskKey(mids.childLeaf[slot], t); };
  std::vector<uint64_t> midKeys(mids.nodes.size() * SymmetryCount);
  parallel(0, mids.nodes.size(), 1024, [&](uint64_t begin, uint64_t end) {
    for (uint64_t i = begin; i < end; ++i)
      for (uint32_t t = 0; t < SymmetryCount; ++t)
        midKeys[i * SymmetryCount + t] = transformedNode(sym, t, mids, mids.nodes[i], midChildKey);
  });
  auto rootChildKey = [&](uint32_t slot, uint32_t t) {
    return midKeys[size_t(roots.childTarget[slot]) * SymmetryCount + t];
  };

  const uint32_t transformCounts[2] = { MirrorCount, SymmetryCount };
  const uint32_t transformBits[2] = { MirrorRefBits, SymmetryRefBits };
  for (int g = 0; g < 2; ++g)
  {
    const uint32_t n = transformCounts[g];
    auto leafClasses = classes(
      leafCount, n, [&](uint64_t i, uint32_t t) { return leafKey(uint32_t(i), t) & ~uint64_t(1); },
      [](uint64_t) { return uint64_t(64); });
    const uint32_t leafWidth = sharedRefWidth(leafClasses.first, transformBits[g]);
    auto midClasses = classes(
      mids.nodes.size(), n,
      [&](uint64_t i, uint32_t t) { return midKeys[size_t(i) * SymmetryCount + t] & ~uint64_t(1); },
      [&](uint64_t i) {
        return layout::NODE_HEADER_BITS + uint64_t(layout::bitCount(mids.nodes[i].mixed)) * leafWidth;
      });
    const uint32_t midWidth = sharedRefWidth(midClasses.second, transformBits[g]);
    auto rootClasses = classes(
      roots.nodes.size(), n,
      [&](uint64_t i, uint32_t t) {
        return transformedNode(sym, t, roots, roots.nodes[i], rootChildKey) & ~uint64_t(1);
      },
      [&](uint64_t i) {
        return layout::NODE_HEADER_BITS + uint64_t(layout::bitCount(roots.nodes[i].mixed)) * midWidth;
      });
    const uint32_t rootWidth = sharedRefWidth(rootClasses.second, transformBits[g]);
    const uint64_t blockBits = B.headerBits + B.references * rootWidth;
    const std::pair<uint64_t, uint64_t> perLevel[4] = { { B.nodes, blockBits }, rootClasses,
      midClasses, leafClasses };
    for (int l = 0; l < EncodingLevelCount; ++l)
    {
      LevelAnalysis& out = a.levels[size_t(l)];
      (g == 0 ? out.mirrorClasses : out.symmetryClasses) = perLevel[l].first;
      (g == 0 ? out.mirrorBits : out.symmetryBits) = perLevel[l].second;
    }
  }
  return a;
}

} // namespace svdag
