// The DAG as byte streams (DagStreams.h).
#include "DagStreams.h"

#include "Bits.h"
#include "PooledGraph.h"

#include <algorithm>
#include <stdexcept>
#include <string>

namespace svdag
{
namespace dagstreams
{
namespace
{
using bits::popcount8;
using bits::putVarint;

[[noreturn]] void fail(const std::string& what)
{
  throw std::runtime_error(what);
}

constexpr uint8_t ComplementFlag = 1u, SharedNodeFlag = 2u, SharedLeafFlag = 0x80u;

// Label values as unsigned keys in the type's order: flipping the sign bit of a sign-extended
// pattern orders signed values as unsigned ones.
uint64_t keyOf(ScalarType t, uint64_t pattern)
{
  return scalarSigned(t) ? pattern ^ (uint64_t(1) << 63) : pattern;
}
uint64_t patternOf(ScalarType t, uint64_t key)
{
  return keyOf(t, key); // the flip undoes itself
}

// Start offsets of a node stream's nodes, in order, and the ordinal of a node at an offset.
std::vector<uint64_t> nodeStarts(const std::vector<uint32_t>& stream, uint64_t count, uint32_t refBits)
{
  std::vector<uint64_t> starts(static_cast<size_t>(count));
  uint64_t offset = 0;
  for (uint64_t n = 0; n < count; ++n)
  {
    starts[size_t(n)] = offset;
    offset += Volume::nodeBits(stream, offset, refBits);
  }
  return starts;
}
size_t ordinalAt(const std::vector<uint64_t>& starts, uint64_t offset)
{
  return size_t(std::lower_bound(starts.begin(), starts.end(), offset) - starts.begin());
}

// First-use numbering of one pool: a reference to a node not numbered yet numbers it next.
struct Renumbering
{
  std::vector<int64_t> newIndex; // by old index, -1 until referenced
  std::vector<uint64_t> oldIndex; // by new index
  explicit Renumbering(uint64_t count)
    : newIndex(size_t(count), -1)
  {
  }
  // The shared flag for a node numbered before (its index appended to `indices`), else 0 (the
  // node is numbered next).
  uint8_t refer(uint64_t old, uint8_t sharedFlag, std::vector<uint8_t>& indices)
  {
    int64_t& n = newIndex[size_t(old)];
    if (n >= 0)
    {
      putVarint(indices, uint64_t(n));
      return sharedFlag;
    }
    n = int64_t(oldIndex.size());
    oldIndex.push_back(old);
    return 0;
  }
};

// Reads a stream front to back; every read is checked against its end.
class Reader
{
public:
  Reader(const std::vector<uint8_t>& bytes, uint32_t stream)
    : At(bytes.data())
    , End(bytes.data() + bytes.size())
    , Stream(stream)
  {
  }
  uint8_t byte()
  {
    if (this->At == this->End)
      fail(std::string(streamName(this->Stream)) + " stream ends early");
    return *this->At++;
  }
  uint64_t varint()
  {
    uint64_t v = 0;
    if (!bits::getVarint(this->At, this->End, v))
      fail(std::string(streamName(this->Stream)) + " stream ends early or holds a number above 64 bits");
    return v;
  }
  uint64_t u64le()
  {
    if (this->End - this->At < 8)
      fail(std::string(streamName(this->Stream)) + " stream ends early");
    const uint64_t v = bits::loadLE(this->At, 8);
    this->At += 8;
    return v;
  }
  void finish() const
  {
    if (this->At != this->End)
      fail(std::string(streamName(this->Stream)) + " stream holds more than its volume");
  }

private:
  const uint8_t* At;
  const uint8_t* End;
  uint32_t Stream;
};

// A reference as a decoded stream holds it (`field`) and as the graph does (`node`, PooledGraph).
struct Reference
{
  uint64_t field;
  uint64_t node;
};

// One pool as it is decoded: the nodes' start offsets (known once their headers are read) and
// how many of them references reached so far.
struct DecodedPool
{
  std::vector<uint64_t> starts;
  uint64_t referenced = 0;
  // The node a reference names: the next new one, or a shared one by index.
  uint64_t take(bool shared, Reader& indices, const char* what)
  {
    if (shared)
    {
      const uint64_t i = indices.varint();
      if (i >= this->referenced)
        fail(std::string(what) + " reference to a node not referenced before");
      return i;
    }
    if (this->referenced >= this->starts.size())
      fail(std::string("more ") + what + " references than " + what + " nodes");
    return this->referenced++;
  }
  // A root or mid reference from its flag byte (complement, shared): the node's start, shifted,
  // with the complement bit (the stream's field), and the node, shifted, with it (the graph's).
  Reference nodeReference(uint8_t flags, Reader& indices, const char* what)
  {
    if (flags & ~(ComplementFlag | SharedNodeFlag))
      fail(std::string(what) + " reference with unknown flags");
    const uint64_t node = this->take((flags & SharedNodeFlag) != 0, indices, what);
    return { (this->starts[size_t(node)] << 1) | (flags & ComplementFlag),
      (node << 1) | (flags & ComplementFlag) };
  }
  void checkAllReferenced(const char* what) const
  {
    if (this->referenced != this->starts.size())
      fail(std::string(what) + " nodes that no reference reaches");
  }
};

// Writes a field of a decoded stream (width at most 32, Volume::validate's rule), refusing a
// value the header's width cannot hold.
void writeField(std::vector<uint32_t>& words, uint64_t offset, uint32_t width, uint64_t value,
  const char* what)
{
  if ((value >> width) != 0)
    fail(std::string(what) + " wider than its field");
  bits::writeBits(words, offset, width, uint32_t(value));
}

// Fills in the child references of a pool's nodes, whose headers are in place: one flag byte a
// mixed child, in child order, which reference(flags) turns into the field's value and the
// graph's. Where `nodes` is given, it and `graphRefs` receive the pool's graph.
template <typename ReferenceOf>
void readReferences(std::vector<uint32_t>& words, const DecodedPool& pool, uint32_t refBits,
  Reader& refs, const char* what, const ReferenceOf& reference,
  std::vector<PooledGraph::Node>* nodes, std::vector<uint32_t>* graphRefs)
{
  if (nodes)
    nodes->reserve(pool.starts.size());
  for (const uint64_t start : pool.starts)
  {
    const uint32_t header = Volume::nodeHeader(words, start);
    const uint32_t mixed = layout::nodeMixedMask(header);
    if (nodes)
      nodes->push_back({ header, popcount8(mixed), uint32_t(graphRefs->size()) });
    for (uint32_t k = 0; k < popcount8(mixed); ++k)
    {
      const Reference r = reference(refs.byte());
      writeField(words, start + layout::NODE_HEADER_BITS + uint64_t(k) * refBits, refBits,
        r.field, what);
      if (graphRefs)
        graphRefs->push_back(uint32_t(r.node)); // no wider than the field just written
    }
  }
  refs.finish();
}

// A pool's node stream from its headers (2 bytes a node: mixed, full), references left zero, and
// the nodes' starts; sized once, from the headers, so that only their bytes bound the memory.
std::vector<uint32_t> readHeaders(const std::vector<uint8_t>& headers, uint32_t stream,
  uint64_t count, uint32_t refBits, DecodedPool& pool, const char* what)
{
  if (headers.size() / 2 != count || headers.size() % 2 != 0)
    fail(std::string(streamName(stream)) + " stream does not hold its " + what + " count");
  uint64_t total = 0;
  pool.starts.resize(size_t(count));
  for (uint64_t n = 0; n < count; ++n)
  {
    const uint32_t mixed = headers[size_t(2 * n)], full = headers[size_t(2 * n + 1)];
    if (mixed & full)
      fail(std::string(what) + " node with a child both mixed and full");
    pool.starts[size_t(n)] = total;
    total += layout::NODE_HEADER_BITS + uint64_t(popcount8(mixed)) * refBits;
  }
  std::vector<uint32_t> words(size_t((total + 31) / 32 + 1), 0u);
  for (uint64_t n = 0; n < count; ++n)
    bits::writeBits(words, pool.starts[size_t(n)], layout::NODE_HEADER_BITS,
      headers[size_t(2 * n)] | (uint32_t(headers[size_t(2 * n + 1)]) << 8));
  return words;
}
} // namespace

const char* streamName(uint32_t stream)
{
  static const char* const names[StreamCount] = { "label values", "block cells", "block labels",
    "block roots", "root indices", "root headers", "root references", "mid indices",
    "mid headers", "mid references", "leaf indices", "leaves" };
  return stream < StreamCount ? names[stream] : "unknown";
}

Encoded encode(const Volume& v)
{
  if (v.form != DagForm::Pooled)
    throw std::logic_error("dagstreams::encode writes the pooled form (svdag::pooled)");
  Encoded out;
  Streams& s = out.streams;
  const ScalarType type = v.scalarType;

  uint64_t previous = keyOf(type, scalarMin(type));
  for (size_t l = 0; l < v.labels.size(); ++l)
  {
    const uint64_t key = keyOf(type, v.labels[l].value);
    putVarint(s[LabelValues], key - previous - (l > 0 ? 1 : 0));
    previous = key;
  }

  const std::vector<uint64_t> rootStarts = nodeStarts(v.roots, v.rootCount, v.widths.midRefBits);
  const std::vector<uint64_t> midStarts = nodeStarts(v.mids, v.midCount, v.widths.leafRefBits);
  Renumbering roots(v.rootCount), mids(v.midCount), leaves(v.leaves.size());
  uint32_t previousCell = 0;
  for (uint64_t i = 0; i < v.blockCount; ++i)
  {
    const Block b = v.block(i);
    putVarint(s[BlockCells], b.cell - previousCell);
    previousCell = b.cell;
    putVarint(s[BlockLabels], b.label);
    const size_t old = ordinalAt(rootStarts, layout::refTarget(b.root));
    s[BlockRoots].push_back(
      uint8_t((b.root & ComplementFlag) | roots.refer(old, SharedNodeFlag, s[RootIndices])));
  }

  // Each pool in its new order, and the largest reference into it once renumbered (the last
  // node's start; for leaves, the largest reference).
  uint64_t rootBits = 0, lastRootStart = 0, midBits = 0, lastMidStart = 0, leafRefMax = 0;
  for (uint64_t n = 0; n < roots.oldIndex.size(); ++n)
  {
    const uint64_t start = rootStarts[size_t(roots.oldIndex[size_t(n)])];
    lastRootStart = rootBits;
    rootBits += Volume::nodeBits(v.roots, start, v.widths.midRefBits);
    const uint32_t header = Volume::nodeHeader(v.roots, start);
    s[RootHeaders].push_back(uint8_t(layout::nodeMixedMask(header)));
    s[RootHeaders].push_back(uint8_t(layout::nodeFullMask(header)));
    for (uint32_t k = 0; k < popcount8(layout::nodeMixedMask(header)); ++k)
    {
      const uint32_t ref = Volume::nodeChildRef(v.roots, start, k, v.widths.midRefBits);
      const size_t old = ordinalAt(midStarts, layout::refTarget(ref));
      s[RootRefs].push_back(
        uint8_t((ref & ComplementFlag) | mids.refer(old, SharedNodeFlag, s[MidIndices])));
    }
  }
  for (uint64_t n = 0; n < mids.oldIndex.size(); ++n)
  {
    const uint64_t start = midStarts[size_t(mids.oldIndex[size_t(n)])];
    const uint32_t header = Volume::nodeHeader(v.mids, start);
    s[MidHeaders].push_back(uint8_t(layout::nodeMixedMask(header)));
    s[MidHeaders].push_back(uint8_t(layout::nodeFullMask(header)));
    for (uint32_t k = 0; k < popcount8(layout::nodeMixedMask(header)); ++k)
    {
      const uint32_t ref = Volume::nodeChildRef(v.mids, start, k, v.widths.leafRefBits);
      const uint8_t shared =
        leaves.refer(layout::leafRefIndex(ref), SharedLeafFlag, s[LeafIndices]);
      s[MidRefs].push_back(uint8_t((ref & 0x7Fu) | shared));
      leafRefMax = std::max<uint64_t>(leafRefMax,
        layout::leafRef(uint32_t(leaves.newIndex[layout::leafRefIndex(ref)]),
          layout::leafRefSymmetry(ref), ref & 1u));
    }
    lastMidStart = midBits;
    midBits += Volume::nodeBits(v.mids, start, v.widths.leafRefBits);
  }
  for (uint64_t old : leaves.oldIndex)
  {
    const size_t at = s[Leaves].size();
    s[Leaves].resize(at + 8);
    bits::storeLE(s[Leaves].data() + at, v.leaves[size_t(old)], 8);
  }

  Shape& shape = out.shape;
  Volume& f = shape.frame;
  f.geometry = v.geometry;
  f.scalarType = v.scalarType;
  f.background = v.background;
  f.blockCount = v.blockCount;
  f.rootCount = roots.oldIndex.size();
  f.midCount = mids.oldIndex.size();
  f.widths = v.widths;
  f.widths.rootRefBits = std::max(f.widths.rootRefBits, bits::bitWidth((lastRootStart << 1) | 1u));
  f.widths.midRefBits = std::max(f.widths.midRefBits, bits::bitWidth((lastMidStart << 1) | 1u));
  f.widths.leafRefBits = std::max(f.widths.leafRefBits, bits::bitWidth(leafRefMax));
  shape.labelCount = v.labels.size();
  shape.leafCount = leaves.oldIndex.size();
  return out;
}

uint64_t maxStreamBytes(uint32_t stream, const Shape& shape)
{
  const Volume& f = shape.frame;
  constexpr uint64_t MaxVarint = 10;
  // Saturating: the header's counts are whatever a file says.
  auto times = [](uint64_t a, uint64_t count) {
    uint64_t product;
    return __builtin_mul_overflow(a, count, &product) ? UINT64_MAX : product;
  };
  switch (stream)
  {
    case LabelValues: return times(MaxVarint, shape.labelCount);
    case BlockCells:
    case BlockLabels: return times(MaxVarint, f.blockCount);
    case BlockRoots: return f.blockCount;
    case RootIndices: return times(MaxVarint, f.blockCount);
    case RootHeaders: return times(2, f.rootCount);
    case RootRefs: return times(8, f.rootCount);
    case MidIndices: return times(8 * MaxVarint, f.rootCount);
    case MidHeaders: return times(2, f.midCount);
    case MidRefs: return times(8, f.midCount);
    case LeafIndices: return times(8 * MaxVarint, f.midCount);
    case Leaves: return times(8, shape.leafCount);
    default: return 0;
  }
}

Volume decode(const Streams& s, const Shape& shape, PooledGraph* graph)
{
  Volume v = shape.frame; // labels, blocks and pools filled in below
  const ScalarType type = v.scalarType;

  { // labels: values only (counts and bounds are derived)
    Reader r(s[LabelValues], LabelValues);
    const uint64_t lowest = keyOf(type, scalarMin(type)), highest = keyOf(type, scalarMax(type));
    uint64_t key = lowest;
    v.labels.reserve(size_t(std::min<uint64_t>(shape.labelCount, s[LabelValues].size()))); // a byte each at least
    for (uint64_t l = 0; l < shape.labelCount; ++l)
    {
      const uint64_t distance = r.varint();
      if (distance > highest - key || (l > 0 && distance == highest - key))
        fail("label value outside the range of " + std::string(scalarName(type)));
      key += distance + (l > 0 ? 1 : 0);
      LabelInfo info;
      info.value = patternOf(type, key);
      v.labels.push_back(info);
    }
    r.finish();
  }

  { // leaves
    Reader r(s[Leaves], Leaves);
    v.leaves.reserve(size_t(std::min<uint64_t>(shape.leafCount, s[Leaves].size() / 8)));
    for (uint64_t l = 0; l < shape.leafCount; ++l)
      v.leaves.push_back(r.u64le());
    r.finish();
  }

  DecodedPool leaves, mids, roots;
  leaves.starts.resize(v.leaves.size()); // leaves are numbered, not placed
  { // mids: headers, then each mixed child's leaf reference
    v.mids = readHeaders(s[MidHeaders], MidHeaders, v.midCount, v.widths.leafRefBits, mids, "mid");
    Reader refs(s[MidRefs], MidRefs), indices(s[LeafIndices], LeafIndices);
    readReferences(v.mids, mids, v.widths.leafRefBits, refs, "a leaf reference",
      [&](uint8_t flags) {
        const uint32_t symmetry = (flags >> 1) & 0x3Fu;
        if (symmetry >= layout::LEAF_SYMMETRY_COUNT)
          fail("leaf reference with an unknown symmetry");
        const uint64_t leaf = leaves.take((flags & SharedLeafFlag) != 0, indices, "leaf");
        const uint64_t ref =
          (leaf << (layout::LEAF_SYMMETRY_BITS + 1)) | (symmetry << 1) | (flags & ComplementFlag);
        return Reference{ ref, ref };
      },
      graph ? &graph->mids : nullptr, graph ? &graph->leafRefs : nullptr);
    indices.finish();
    leaves.checkAllReferenced("leaf");
  }
  { // roots
    v.roots = readHeaders(s[RootHeaders], RootHeaders, v.rootCount, v.widths.midRefBits, roots, "root");
    Reader refs(s[RootRefs], RootRefs), indices(s[MidIndices], MidIndices);
    readReferences(v.roots, roots, v.widths.midRefBits, refs, "a mid reference",
      [&](uint8_t flags) { return mids.nodeReference(flags, indices, "mid"); },
      graph ? &graph->roots : nullptr, graph ? &graph->midRefs : nullptr);
    indices.finish();
    mids.checkAllReferenced("mid");
  }
  { // blocks, their bounds left zero
    const FieldWidths& w = v.widths;
    const uint64_t cells = v.geometry.cellCount();
    const uint64_t recordBits = w.blockBits();
    Reader cellsIn(s[BlockCells], BlockCells), labels(s[BlockLabels], BlockLabels),
      refs(s[BlockRoots], BlockRoots), indices(s[RootIndices], RootIndices);
    if (s[BlockRoots].size() != v.blockCount)
      fail("block roots stream does not hold the block count");
    if (graph)
      graph->blockRoots.reserve(size_t(v.blockCount)); // a stream byte each
    const uint64_t totalBits = v.blockCount * recordBits; // one stream byte a block: no overflow
    v.blocks.assign(size_t(totalBits / 32 + (totalBits % 32 ? 1 : 0) + 1), 0u);
    uint64_t cell = 0;
    for (uint64_t i = 0; i < v.blockCount; ++i)
    {
      const uint64_t step = cellsIn.varint();
      if (step >= cells - cell) // cell < cells after the first block
        fail("block cell outside the grid");
      cell += step;
      const uint64_t label = labels.varint();
      if (label >= v.labels.size())
        fail("block label index out of range");
      const Reference rootRef = roots.nodeReference(refs.byte(), indices, "root");
      const uint64_t base = i * recordBits;
      writeField(v.blocks, base, w.cellBits, cell, "a block's cell");
      writeField(v.blocks, base + layout::blockLabelOffset(w.cellBits), w.labelBits, label,
        "a block's label");
      writeField(v.blocks, base + layout::blockRootOffset(w.cellBits, w.labelBits), w.rootRefBits,
        rootRef.field, "a root reference");
      if (graph)
        graph->blockRoots.push_back(uint32_t(rootRef.node));
    }
    cellsIn.finish();
    labels.finish();
    refs.finish();
    indices.finish();
    roots.checkAllReferenced("root");
  }
  return v;
}

} // namespace dagstreams
} // namespace svdag
