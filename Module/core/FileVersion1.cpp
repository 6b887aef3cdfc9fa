#include "FileVersion1.h"

#include "Bits.h"

#include <algorithm>
#include <stdexcept>
#include <string>
#include <vector>

namespace svdag
{
namespace file
{
namespace
{
using bits::bitWidth;
using bits::readBits;
using bits::writeBits;

[[noreturn]] void fail(const std::string& what)
{
  throw std::runtime_error("format 1.0: " + what);
}

struct Rewritten
{
  std::vector<uint32_t> stream;             // padded by one zero word
  std::vector<uint64_t> oldOffsets, offsets; // per node, ascending
};

// One node stream, node by node, its references passed through mapRef at the new width.
template <typename MapRef>
Rewritten rewrite(const std::vector<uint32_t>& stream, uint64_t count, uint32_t oldBits,
  uint32_t newBits, const char* what, const MapRef& mapRef)
{
  const uint64_t total = stream.empty() ? 0 : uint64_t(stream.size() - 1) * 32;
  Rewritten r;
  uint64_t at = 0, out = 0;
  for (uint64_t n = 0; n < count; ++n)
  {
    if (at + layout::NODE_HEADER_BITS > total)
      fail(std::string(what) + " stream shorter than its node count");
    const uint32_t k = layout::bitCount(layout::nodeMixedMask(Volume::nodeHeader(stream, at)));
    if (at + layout::NODE_HEADER_BITS + uint64_t(k) * oldBits > total)
      fail(std::string(what) + " node runs past the end of its stream");
    r.oldOffsets.push_back(at);
    r.offsets.push_back(out);
    at += layout::NODE_HEADER_BITS + uint64_t(k) * oldBits;
    out += layout::NODE_HEADER_BITS + uint64_t(k) * newBits;
  }
  if (total - at >= 32)
    fail(std::string(what) + " stream longer than its nodes");
  if (out > 0xFFFFFFFFull)
    fail(std::string(what) + " stream exceeds 2^32 bits in today's layout");
  r.stream.assign(size_t((out + 31) / 32 + 1), 0u);
  for (uint64_t n = 0; n < count; ++n)
  {
    const uint32_t header = Volume::nodeHeader(stream, r.oldOffsets[n]);
    writeBits(r.stream, r.offsets[n], layout::NODE_HEADER_BITS, header);
    const uint32_t k = layout::bitCount(layout::nodeMixedMask(header));
    for (uint32_t c = 0; c < k; ++c)
      writeBits(r.stream, r.offsets[n] + layout::NODE_HEADER_BITS + uint64_t(c) * newBits, newBits,
        mapRef(Volume::nodeChildRef(stream, r.oldOffsets[n], c, oldBits)));
  }
  return r;
}

// The reference (offset << 1 | complement) to a node of `pool` at its new offset.
uint32_t moved(const Rewritten& pool, uint32_t ref, const char* what)
{
  const auto it = std::lower_bound(pool.oldOffsets.begin(), pool.oldOffsets.end(), uint64_t(ref >> 1));
  if (it == pool.oldOffsets.end() || *it != (ref >> 1))
    fail(std::string("a reference into the ") + what + " stream is not at a node start");
  return uint32_t((pool.offsets[size_t(it - pool.oldOffsets.begin())] << 1) | (ref & 1u));
}

uint32_t referenceWidth(const Rewritten& pool, const char* what)
{
  const uint32_t bits = bitWidth(pool.offsets.empty() ? 0 : pool.offsets.back()) + 1;
  if (bits > 32)
    fail(std::string(what) + " references need more than 32 bits in today's layout");
  return bits;
}
} // namespace

void upgradeVersion1(Volume& v)
{
  FieldWidths w = v.widths;
  const uint32_t leafBits = w.leafRefBits + layout::LEAF_SYMMETRY_BITS;
  if (leafBits > 32)
    fail("leaf references need more than 32 bits in today's layout");
  Rewritten mids = rewrite(v.mids, v.midCount, w.leafRefBits, leafBits, "mid",
    [](uint32_t ref) { return layout::leafRef(ref >> 1, 0u, ref & 1u); });
  const uint32_t midBits = referenceWidth(mids, "mid");
  Rewritten roots = rewrite(v.roots, v.rootCount, w.midRefBits, midBits, "root",
    [&](uint32_t ref) { return moved(mids, ref, "mid"); });
  const uint32_t rootBits = referenceWidth(roots, "root");

  // Block records: the same fields, the root reference moved and as wide as it now needs.
  const uint64_t oldRecord = w.blockBits();
  if (v.blocks.empty() || (v.blockCount * oldRecord + 31) / 32 > v.blocks.size() - 1)
    fail("blocks section shorter than its records");
  FieldWidths now = w;
  now.leafRefBits = leafBits;
  now.midRefBits = midBits;
  now.rootRefBits = rootBits;
  const uint64_t record = now.blockBits();
  std::vector<uint32_t> blocks(size_t((v.blockCount * record + 31) / 32 + 1), 0u);
  const uint32_t fieldsBits = layout::blockRootOffset(w.cellBits, w.labelBits);
  for (uint64_t i = 0; i < v.blockCount; ++i)
  {
    // Cell, bounds and label fields are copied as they are (at most 32 bits at a time).
    for (uint32_t b = 0; b < fieldsBits; b += 32)
    {
      const uint32_t width = std::min(32u, fieldsBits - b);
      writeBits(blocks, i * record + b, width, readBits(v.blocks, i * oldRecord + b, width));
    }
    const uint32_t root = readBits(v.blocks, i * oldRecord + fieldsBits, w.rootRefBits);
    writeBits(blocks, i * record + fieldsBits, rootBits, moved(roots, root, "root"));
  }
  v.mids = std::move(mids.stream);
  v.roots = std::move(roots.stream);
  v.blocks = std::move(blocks);
  v.widths = now;
}

} // namespace file
} // namespace svdag
