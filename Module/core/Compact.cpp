#include "svdag/Compact.h"

#include "Bits.h"
#include "PooledGraph.h"
#include "svdag/LeafSymmetry.h"

#include <algorithm>
#include <stdexcept>
#include <string>
#include <unordered_map>
#include <vector>

namespace svdag
{
namespace
{
using bits::bitWidth;
using bits::readBits;
using bits::writeBits;

constexpr uint32_t Unplaced = 0xFFFFFFFFu;

using Children = PooledGraph::Node;

void fail(const std::string& what)
{
  throw std::runtime_error("compact volume: " + what);
}

// The width of a reference to `largest` with `extra` more bits (complement, symmetry).
uint32_t refWidth(uint64_t largest, uint32_t extra)
{
  const uint32_t width = bitWidth(largest) + extra;
  if (width > 32)
    throw std::length_error("SVDAG too large: a reference needs more than 32 bits");
  return width;
}

std::vector<uint32_t> wordsFor(uint64_t bits)
{
  if (bits > 0xFFFFFFFFull)
    throw std::length_error("SVDAG too large: a node stream exceeds 2^32 bits");
  return std::vector<uint32_t>(size_t((bits + 31) / 32 + 1), 0u);
}

void writeField(std::vector<uint32_t>& words, uint64_t& at, uint32_t width, uint64_t value)
{
  writeBits(words, at, width, uint32_t(value));
  at += width;
}

// The index of the node starting at a bit offset of a node stream (either form), in constant
// time, -1 where none starts. Nodes take 16 bits at least, so offset / 16 tells them apart: a
// bit per 16 bits of stream marks where nodes start, and a count per 64 of those bits ranks them
// (about a tenth of the stream's own size).
class NodeAt
{
public:
  explicit NodeAt(const std::vector<uint32_t>& starts)
    : Starts(starts)
  {
    const size_t slots = starts.empty() ? 0 : size_t(starts.back() >> 4) + 1;
    this->Marks.assign(slots / 64 + 1, 0);
    for (uint32_t start : starts)
      this->Marks[start >> 10] |= uint64_t(1) << ((start >> 4) & 63);
    this->Ranks.resize(this->Marks.size());
    uint32_t rank = 0;
    for (size_t w = 0; w < this->Marks.size(); ++w)
    {
      this->Ranks[w] = rank;
      rank += bits::popcount64(this->Marks[w]);
    }
  }
  int64_t operator()(uint64_t offset) const
  {
    const uint64_t word = offset >> 10;
    const uint32_t bit = uint32_t((offset >> 4) & 63);
    if (word >= this->Marks.size() || !((this->Marks[size_t(word)] >> bit) & 1u))
      return -1;
    const uint32_t index = this->Ranks[size_t(word)] +
      bits::popcount64(this->Marks[size_t(word)] & ((uint64_t(1) << bit) - 1));
    return this->Starts[index] == offset ? int64_t(index) : -1;
  }

private:
  const std::vector<uint32_t>& Starts;
  std::vector<uint64_t> Marks;
  std::vector<uint32_t> Ranks;
};

// A count of uses that stops at 2: once or more than once is all the compact form asks.
void countUse(std::vector<uint8_t>& uses, size_t i)
{
  uses[i] = uint8_t(uses[i] < 2 ? uses[i] + 1 : 2);
}

// Rewrites the block records' root references (block and old reference -> the root's index by
// rootOf -> new offset) at the new root reference width, record by record: in place where the
// records do not grow (a volume of billions of blocks is not copied), else into a new stream.
template <typename Lookup>
void rewriteBlocks(Volume& v, uint32_t rootRefBits, const Lookup& rootOf,
  const std::vector<uint32_t>& newStarts)
{
  const FieldWidths old = v.widths;
  FieldWidths& w = v.widths;
  w.rootRefBits = rootRefBits;
  const uint32_t oldBits = old.blockBits(), recordBits = w.blockBits();
  std::vector<uint32_t> grown;
  if (recordBits > oldBits)
    grown.assign(size_t((v.blockCount * recordBits + 31) / 32 + 1), 0u);
  std::vector<uint32_t>& out = recordBits > oldBits ? grown : v.blocks;
  const uint32_t rootAt = layout::blockRootOffset(old.cellBits, old.labelBits);
  for (uint64_t i = 0; i < v.blockCount; ++i)
  {
    // Everything before the root reference is the same fields at the same widths.
    const uint64_t from = i * oldBits;
    const uint32_t root = readBits(v.blocks, from + rootAt, old.rootRefBits);
    const int64_t k = rootOf(i, root);
    if (k < 0)
      fail("a block's root reference is not at a root node");
    const uint32_t widths[3] = { old.cellBits, layout::BLOCK_BOUNDS_BITS, old.labelBits };
    uint32_t fields[3];
    uint64_t at = from;
    for (uint32_t f = 0; f < 3; ++f)
    {
      fields[f] = readBits(v.blocks, at, widths[f]);
      at += widths[f];
    }
    uint64_t to = i * recordBits;
    for (uint32_t f = 0; f < 3; ++f)
    {
      bits::replaceBits(out, to, widths[f], fields[f]);
      to += widths[f];
    }
    bits::replaceBits(out, to, rootRefBits, uint32_t((uint64_t(newStarts[size_t(k)]) << 1) | (root & 1u)));
  }
  if (recordBits > oldBits)
    v.blocks = std::move(grown);
  else // the words past the last record are zero, as a stream's padding is
    v.blocks.resize(size_t((v.blockCount * recordBits + 31) / 32 + 1));
  if (!v.blocks.empty())
  {
    const uint64_t used = v.blockCount * recordBits;
    if (used % 32)
      v.blocks[size_t(used / 32)] &= layout::lowMask(uint32_t(used % 32));
    std::fill(v.blocks.begin() + std::ptrdiff_t((used + 31) / 32), v.blocks.end(), 0u);
  }
}

uint32_t complementedNode(uint32_t header)
{
  const uint32_t mixed = layout::nodeMixedMask(header);
  return mixed | ((~(mixed | layout::nodeFullMask(header)) & 0xFFu) << 8);
}

// Reads the compact node at bit `at` of a stream holding `total` data bits into `n` (its
// references to start at `first` in its level's array): returns its first COMPACT_HEADER_BITS
// and sets `bits` to its length (nodeBits(header)), every bound checked.
template <typename NodeBits>
uint32_t readCompactNode(const std::vector<uint32_t>& stream, uint64_t total, uint64_t at,
  const NodeBits& nodeBits, const std::string& level, Children& n, uint32_t first, uint64_t& bits)
{
  if (stream.empty() || at + layout::COMPACT_HEADER_BITS > total + 32) // padding: the rest
    fail(level + " stream shorter than its node count");
  const uint32_t header = Volume::nodeHeaderAndFlags(stream, at);
  bits = nodeBits(header);
  if (at + bits > total)
    fail("a " + level + " node runs past the end of its stream");
  n.header = header & 0xFFFFu;
  n.count = layout::bitCount(layout::nodeMixedMask(header));
  n.first = first;
  if (n.header & (n.header >> 8) & 0xFFu)
    fail("a " + level + " node's child is both mixed and full");
  return header;
}

} // namespace

PooledGraph pooledGraph(const Volume& v)
{
  if (v.form != DagForm::Pooled)
    throw std::logic_error("pooledGraph: the volume is not in the pooled form");
  PooledGraph g;
  g.mids.resize(size_t(v.midCount));
  g.roots.resize(size_t(v.rootCount));
  std::vector<uint32_t> midStarts(g.mids.size()), rootStarts(g.roots.size());
  // One pass over each stream: a node's header, then its references in order, kept as
  // `child(reference)` gives them.
  auto walk = [](const std::vector<uint32_t>& stream, std::vector<Children>& nodes,
                std::vector<uint32_t>& starts, uint32_t refBits, std::vector<uint32_t>& refs,
                const auto& child) {
    refs.reserve(nodes.size() * 4);
    uint64_t at = 0;
    for (size_t i = 0; i < nodes.size(); ++i)
    {
      Children& n = nodes[i];
      starts[i] = uint32_t(at);
      n.header = readBits(stream, at, layout::NODE_HEADER_BITS);
      n.count = layout::bitCount(layout::nodeMixedMask(n.header));
      n.first = uint32_t(refs.size());
      at += layout::NODE_HEADER_BITS;
      for (uint32_t r = 0; r < n.count; ++r, at += refBits)
        refs.push_back(child(readBits(stream, at, refBits)));
    }
  };
  walk(v.mids, g.mids, midStarts, v.widths.leafRefBits, g.leafRefs, [](uint32_t ref) { return ref; });
  const NodeAt midAt(midStarts);
  walk(v.roots, g.roots, rootStarts, v.widths.midRefBits, g.midRefs, [&](uint32_t ref) {
    const int64_t mid = midAt(layout::refTarget(ref));
    if (mid < 0)
      fail("a root's reference is not at a mid node");
    return uint32_t(mid << 1) | (ref & 1u);
  });
  const NodeAt rootAt(rootStarts);
  const uint32_t recordBits = v.widths.blockBits();
  const uint32_t rootField = layout::blockRootOffset(v.widths.cellBits, v.widths.labelBits);
  g.blockRoots.resize(size_t(v.blockCount));
  for (uint64_t b = 0; b < v.blockCount; ++b)
  {
    const uint32_t ref = readBits(v.blocks, b * recordBits + rootField, v.widths.rootRefBits);
    const int64_t root = rootAt(layout::refTarget(ref));
    if (root < 0)
      fail("a block's root reference is not at a root node");
    g.blockRoots[size_t(b)] = uint32_t(root << 1) | (ref & 1u);
  }
  return g;
}

Volume compacted(Volume v)
{
  if (v.form == DagForm::Compact)
    return v;
  PooledGraph graph = pooledGraph(v);
  return compacted(std::move(v), std::move(graph));
}

Volume compacted(Volume v, PooledGraph graph)
{
  if (v.form == DagForm::Compact)
    return v;
  std::vector<Children> mids = std::move(graph.mids), roots = std::move(graph.roots);
  std::vector<uint32_t> leafRefs = std::move(graph.leafRefs), midRefs = std::move(graph.midRefs);
  const std::vector<uint32_t> blockRoots = std::move(graph.blockRoots);
  if (mids.size() != v.midCount || roots.size() != v.rootCount ||
    blockRoots.size() != v.blockCount)
    throw std::logic_error("compacted: the graph is not the volume's");
  // What is read is held above: the pooled node streams go before the compact ones are made.
  std::vector<uint32_t>().swap(v.mids);
  std::vector<uint32_t>().swap(v.roots);
  std::vector<uint8_t> leafUses(v.leaves.size()), midUses(mids.size());
  for (uint32_t ref : leafRefs)
    countUse(leafUses, layout::leafRefIndex(ref));
  for (uint32_t ref : midRefs)
    countUse(midUses, ref >> 1);

  // Order: roots as the blocks first use them; at a root's first use its chained mids (one
  // after another, child order), then its shared mids not placed yet.
  std::vector<uint32_t> rootOrder, midOrder;
  std::vector<uint8_t> midFold; // chained mids: written complemented (as the root sees them)
  rootOrder.reserve(roots.size());
  midOrder.reserve(mids.size());
  midFold.reserve(mids.size());
  {
    std::vector<uint8_t> rootPlaced(roots.size()), midPlaced(mids.size());
    for (uint64_t b = 0; b < v.blockCount; ++b)
    {
      const uint32_t root = blockRoots[size_t(b)] >> 1;
      if (rootPlaced[size_t(root)])
        continue;
      rootPlaced[size_t(root)] = 1;
      rootOrder.push_back(uint32_t(root));
      const Children& n = roots[size_t(root)];
      for (int pass = 0; pass < 2; ++pass)
        for (uint32_t r = 0; r < n.count; ++r)
        {
          const uint32_t ref = midRefs[n.first + r];
          const uint32_t mid = ref >> 1;
          if ((midUses[mid] == 1) != (pass == 0) || midPlaced[mid])
            continue;
          midPlaced[mid] = 1;
          midOrder.push_back(mid);
          midFold.push_back(uint8_t(pass == 0 ? (ref & 1u) : 0u));
        }
    }
    if (rootOrder.size() != roots.size() || midOrder.size() != mids.size())
      fail("a node no block reaches");
  }

  // Shared leaves numbered by first use in the new mid order; each mid's flags (its inline
  // leaves: those used once) on the way.
  std::vector<uint32_t> leafIndex(v.leaves.size(), Unplaced);
  std::vector<uint64_t> sharedLeaves;
  std::vector<uint8_t> midFlags(mids.size());
  for (uint32_t mid : midOrder)
  {
    const Children& n = mids[mid];
    uint32_t flags = 0;
    for (uint32_t r = 0; r < n.count; ++r)
    {
      // Few branches: whether a leaf is used once changes from child to child.
      const uint32_t leaf = layout::leafRefIndex(leafRefs[n.first + r]);
      const uint32_t once = leafUses[leaf] == 1;
      flags |= once << r;
      if ((leafIndex[leaf] == Unplaced) & !once)
      {
        leafIndex[leaf] = uint32_t(sharedLeaves.size());
        sharedLeaves.push_back(v.leaves[leaf]);
      }
    }
    midFlags[mid] = uint8_t(flags);
  }
  const uint32_t leafRefBits =
    refWidth(sharedLeaves.empty() ? 0 : sharedLeaves.size() - 1, 1 + layout::LEAF_SYMMETRY_BITS);

  // The mid stream.
  std::vector<uint32_t> newMidStart(mids.size());
  uint64_t midBits = 0, lastMid = 0;
  for (uint32_t mid : midOrder)
  {
    lastMid = midBits;
    newMidStart[mid] = uint32_t(midBits);
    midBits += layout::compactMidBits(mids[mid].header | (uint32_t(midFlags[mid]) << 16), leafRefBits);
  }
  std::vector<uint32_t> midStream = wordsFor(midBits);
  for (size_t k = 0; k < midOrder.size(); ++k)
  {
    const Children& n = mids[midOrder[k]];
    const uint32_t flags = midFlags[midOrder[k]];
    const bool fold = midFold[k] != 0;
    uint64_t at = newMidStart[midOrder[k]];
    writeField(midStream, at, layout::NODE_HEADER_BITS, fold ? complementedNode(n.header) : n.header);
    writeField(midStream, at, n.count, flags);
    const uint64_t flip = fold ? ~uint64_t(0) : 0;
    for (uint32_t shared = ~flags & layout::lowMask(n.count); shared; shared &= shared - 1)
    {
      const uint32_t ref = leafRefs[n.first + uint32_t(__builtin_ctz(shared))];
      writeField(midStream, at, leafRefBits,
        layout::leafRef(leafIndex[layout::leafRefIndex(ref)], layout::leafRefSymmetry(ref),
          (ref & 1u) ^ uint32_t(flip & 1u)));
    }
    for (uint32_t inlined = flags; inlined; inlined &= inlined - 1)
    {
      const uint32_t ref = leafRefs[n.first + uint32_t(__builtin_ctz(inlined))];
      const uint64_t mask = v.leafMask(ref) ^ (uint64_t(0) - (ref & 1u)) ^ flip;
      writeField(midStream, at, 32, mask);
      writeField(midStream, at, 32, mask >> 32);
    }
  }
  const uint32_t midRefBits = refWidth(lastMid, 1);
  std::vector<uint32_t>().swap(leafRefs);
  std::vector<Children>().swap(mids);

  // The root stream.
  std::vector<uint32_t> newRootStart(roots.size());
  std::vector<uint8_t> rootFlags(roots.size());
  uint64_t rootBits = 0, lastRoot = 0;
  for (uint32_t root : rootOrder)
  {
    const Children& n = roots[root];
    for (uint32_t r = 0; r < n.count; ++r)
      if (midUses[midRefs[n.first + r] >> 1] == 1)
        rootFlags[root] = uint8_t(rootFlags[root] | (1u << r));
    lastRoot = rootBits;
    newRootStart[root] = uint32_t(rootBits);
    rootBits += layout::compactRootBits(roots[root].header | (uint32_t(rootFlags[root]) << 16), midRefBits);
  }
  std::vector<uint32_t> rootStream = wordsFor(rootBits);
  for (uint32_t root : rootOrder)
  {
    const Children& n = roots[root];
    const uint32_t flags = rootFlags[root];
    uint64_t at = newRootStart[root];
    writeField(rootStream, at, layout::NODE_HEADER_BITS, n.header);
    writeField(rootStream, at, n.count, flags);
    if (flags)
    {
      const uint32_t first = uint32_t(__builtin_ctz(flags));
      writeField(rootStream, at, midRefBits - 1, newMidStart[midRefs[n.first + first] >> 1]);
    }
    for (uint32_t r = 0; r < n.count; ++r)
      if (!((flags >> r) & 1u))
      {
        const uint32_t ref = midRefs[n.first + r];
        writeField(rootStream, at, midRefBits, (uint64_t(newMidStart[ref >> 1]) << 1) | (ref & 1u));
      }
  }

  v.mids = std::move(midStream);
  v.roots = std::move(rootStream);
  v.leaves = std::move(sharedLeaves);
  v.widths.leafRefBits = leafRefBits;
  v.widths.midRefBits = midRefBits;
  rewriteBlocks(v, refWidth(lastRoot, 1),
    [&](uint64_t block, uint32_t) { return int64_t(blockRoots[size_t(block)] >> 1); }, newRootStart);
  v.form = DagForm::Compact;
  return v;
}

Volume pooled(Volume v)
{
  if (v.form == DagForm::Pooled)
    return v;
  const uint64_t midTotal = v.mids.empty() ? 0 : uint64_t(v.mids.size() - 1) * 32;
  const uint64_t rootTotal = v.roots.empty() ? 0 : uint64_t(v.roots.size() - 1) * 32;
  if (v.widths.leafRefBits < 1 + layout::LEAF_SYMMETRY_BITS || v.widths.leafRefBits > 32 ||
    v.widths.midRefBits < 1 || v.widths.midRefBits > 32)
    fail("reference widths out of range");
  if (midTotal > 0xFFFFFFFFull || rootTotal > 0xFFFFFFFFull)
    fail("a node stream longer than 2^32 bits");

  // Leaves: the shared ones keep their index; inline ones are stored canonical, once per class.
  const size_t sharedLeaves = v.leaves.size();
  std::vector<uint64_t> leaves = std::move(v.leaves);
  std::unordered_map<uint64_t, uint32_t> leafOf;
  for (size_t i = 0; i < leaves.size(); ++i)
    leafOf.emplace(leaves[i], uint32_t(i));
  auto inlineRef = [&](uint64_t mask) {
    if (mask == 0 || mask == ~uint64_t(0))
      fail("an inline leaf is not mixed");
    const CanonicalLeaf c = canonicalLeaf(mask);
    const auto found = leafOf.emplace(c.stored, uint32_t(leaves.size()));
    if (found.second)
      leaves.push_back(c.stored);
    return layout::leafRef(found.first->second, c.symmetry, c.complement);
  };

  // Mids, in stream order, each made canonical again.
  std::vector<Children> mids(size_t(v.midCount));
  std::vector<uint32_t> leafRefs;
  std::vector<uint32_t> midStarts(mids.size());
  std::vector<uint8_t> midFlipped(mids.size());
  uint64_t at = 0;
  for (size_t i = 0; i < mids.size(); ++i)
  {
    Children& n = mids[i];
    uint64_t bits;
    const uint32_t header = readCompactNode(v.mids, midTotal, at,
      [&](uint32_t h) { return layout::compactMidBits(h, v.widths.leafRefBits); }, "mid", n,
      uint32_t(leafRefs.size()), bits);
    midStarts[i] = uint32_t(at);
    for (uint32_t r = 0; r < n.count; ++r)
    {
      if (layout::compactChildFlagged(header, r))
      {
        const uint64_t m = at + layout::compactMidMaskOffset(header, r, v.widths.leafRefBits);
        leafRefs.push_back(inlineRef(uint64_t(readBits(v.mids, m, 32)) |
          (uint64_t(readBits(v.mids, m + 32, 32)) << 32)));
      }
      else
      {
        const uint32_t ref = readBits(v.mids,
          at + layout::compactMidRefOffset(header, r, v.widths.leafRefBits), v.widths.leafRefBits);
        if (layout::leafRefIndex(ref) >= sharedLeaves ||
          layout::leafRefSymmetry(ref) >= layout::LEAF_SYMMETRY_COUNT)
          fail("a leaf reference is out of range");
        leafRefs.push_back(ref);
      }
    }
    // Canonical: the first child empty, or mixed through a reference without the complement.
    const bool firstFull = (n.header >> 8) & 1u;
    const bool firstComplemented = (n.header & 1u) && (leafRefs[n.first] & 1u);
    if (firstFull || firstComplemented)
    {
      n.header = complementedNode(n.header);
      for (uint32_t r = 0; r < n.count; ++r)
        leafRefs[n.first + r] ^= 1u;
      midFlipped[i] = 1;
    }
    at += bits;
  }
  if (midTotal - at >= 32)
    fail("mid stream longer than its nodes");

  // Roots, in stream order: chained mids become references to them.
  const NodeAt midAt(midStarts);
  std::vector<Children> roots(size_t(v.rootCount));
  std::vector<uint32_t> midRefs; // mid index << 1 | complement
  std::vector<uint32_t> rootStarts(roots.size());
  at = 0;
  for (size_t i = 0; i < roots.size(); ++i)
  {
    Children& n = roots[i];
    uint64_t bits;
    const uint32_t header = readCompactNode(v.roots, rootTotal, at,
      [&](uint32_t h) { return layout::compactRootBits(h, v.widths.midRefBits); }, "root", n,
      uint32_t(midRefs.size()), bits);
    rootStarts[i] = uint32_t(at);
    int64_t chained = -1;
    if (layout::compactFlags(header))
    {
      chained = midAt(readBits(v.roots, at + layout::compactPrefixBits(header),
        v.widths.midRefBits - 1));
      if (chained < 0)
        fail("a root's chained mids do not start at a mid node");
    }
    for (uint32_t r = 0; r < n.count; ++r)
    {
      int64_t mid;
      uint32_t complement = 0;
      if (layout::compactChildFlagged(header, r))
      {
        mid = chained++;
        if (size_t(mid) >= mids.size())
          fail("a root's chained mids run past the last mid node");
      }
      else
      {
        const uint32_t ref = readBits(v.roots,
          at + layout::compactRootRefOffset(header, r, v.widths.midRefBits), v.widths.midRefBits);
        mid = midAt(layout::refTarget(ref));
        if (mid < 0)
          fail("a root's reference is not at a mid node");
        complement = ref & 1u;
      }
      midRefs.push_back(uint32_t(mid << 1) | (complement ^ midFlipped[size_t(mid)]));
    }
    at += bits;
  }
  if (rootTotal - at >= 32)
    fail("root stream longer than its nodes");

  // The pooled streams, nodes in the same order.
  const uint32_t leafRefBits =
    refWidth(leaves.empty() ? 0 : leaves.size() - 1, 1 + layout::LEAF_SYMMETRY_BITS);
  std::vector<uint32_t> newMidStart(mids.size());
  uint64_t midBits = 0;
  for (size_t i = 0; i < mids.size(); ++i)
  {
    newMidStart[i] = uint32_t(midBits);
    midBits += layout::NODE_HEADER_BITS + uint64_t(mids[i].count) * leafRefBits;
  }
  const uint32_t midRefBits = refWidth(mids.empty() ? 0 : newMidStart.back(), 1);
  std::vector<uint32_t> midStream = wordsFor(midBits);
  for (size_t i = 0; i < mids.size(); ++i)
  {
    uint64_t to = newMidStart[i];
    writeField(midStream, to, layout::NODE_HEADER_BITS, mids[i].header);
    for (uint32_t r = 0; r < mids[i].count; ++r)
      writeField(midStream, to, leafRefBits, leafRefs[mids[i].first + r]);
  }
  std::vector<uint32_t> newRootStart(roots.size());
  uint64_t rootBits = 0;
  for (size_t i = 0; i < roots.size(); ++i)
  {
    newRootStart[i] = uint32_t(rootBits);
    rootBits += layout::NODE_HEADER_BITS + uint64_t(roots[i].count) * midRefBits;
  }
  std::vector<uint32_t> rootStream = wordsFor(rootBits);
  for (size_t i = 0; i < roots.size(); ++i)
  {
    uint64_t to = newRootStart[i];
    writeField(rootStream, to, layout::NODE_HEADER_BITS, roots[i].header);
    for (uint32_t r = 0; r < roots[i].count; ++r)
    {
      const uint32_t ref = midRefs[roots[i].first + r];
      writeField(rootStream, to, midRefBits, (uint64_t(newMidStart[ref >> 1]) << 1) | (ref & 1u));
    }
  }

  v.mids = std::move(midStream);
  v.roots = std::move(rootStream);
  v.leaves = std::move(leaves);
  v.widths.leafRefBits = leafRefBits;
  v.widths.midRefBits = midRefBits;
  const NodeAt rootAt(rootStarts);
  rewriteBlocks(v, refWidth(roots.empty() ? 0 : newRootStart.back(), 1),
    [&](uint64_t, uint32_t ref) { return rootAt(layout::refTarget(ref)); }, newRootStart);
  v.form = DagForm::Pooled;
  return v;
}

const Volume& pooledView(const Volume& volume, Volume& holder)
{
  if (volume.form == DagForm::Pooled)
    return volume;
  holder = pooled(volume);
  return holder;
}

} // namespace svdag
