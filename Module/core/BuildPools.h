// Compact storage for the Builder's deduplicated pools (private to Builder.cpp).
//
// The builder's state must stay close to the size of its output (the issue asks for at most one
// slab plus 1.5x the output plus a constant), so the pools avoid the usual slack:
// - GrowArray grows by 1/16 through realloc (large blocks are remapped by the C library, not
//   copied, so small steps stay cheap);
// - IdTable packs its slots to the bits the ids need and keeps them 55-80% full;
// - PackedNodePool keeps nodes bit-packed with the narrowest reference width their children's
//   pool needs so far, and widens the stream in place when that pool crosses a power of two;
//   PackedRecords does the same for the pending block records.
#pragma once

#include "Bits.h"
#include "svdag/Layout.h"

#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <algorithm>
#include <array>
#include <new>
#include <stdexcept>
#include <type_traits>
#include <vector>

namespace svdag
{
namespace build
{

using bits::bitWidth;
using bits::mix64;

// A growable array of trivially copyable values with 1/16 growth slack at most.
template <class T>
class GrowArray
{
  static_assert(std::is_trivially_copyable<T>::value, "GrowArray holds plain values");

public:
  GrowArray() = default;
  GrowArray(const GrowArray&) = delete;
  GrowArray& operator=(const GrowArray&) = delete;
  ~GrowArray() { std::free(items); }

  size_t size() const { return count; }
  bool empty() const { return count == 0; }
  T* data() { return items; }
  const T* data() const { return items; }
  T& operator[](size_t i) { return items[i]; }
  const T& operator[](size_t i) const { return items[i]; }
  T& back() { return items[count - 1]; }

  void push_back(const T& value)
  {
    reserveFor(count + 1);
    items[count++] = value;
  }
  // Grows with zero-filled values or shrinks (keeping the capacity).
  void resize(size_t n)
  {
    reserveFor(n);
    if (n > count)
      std::memset(static_cast<void*>(items + count), 0, (n - count) * sizeof(T));
    count = n;
  }
  void swap(GrowArray& other)
  {
    std::swap(items, other.items);
    std::swap(count, other.count);
    std::swap(capacity, other.capacity);
  }
  void release()
  {
    std::free(items);
    items = nullptr;
    count = capacity = 0;
  }
  // Moves the values into a std::vector (one copy) and frees this array.
  std::vector<T> takeVector()
  {
    std::vector<T> out(items, items + count);
    release();
    return out;
  }

private:
  void reserveFor(size_t n)
  {
    if (n <= capacity)
      return;
    size_t next = capacity + capacity / 16;
    if (next < n)
      next = n;
    if (next < 256)
      next = 256;
    void* grown = std::realloc(items, next * sizeof(T));
    if (!grown)
      throw std::bad_alloc();
    items = static_cast<T*>(grown);
    capacity = next;
  }
  T* items = nullptr;
  size_t count = 0;
  size_t capacity = 0;
};

// Reads/writes a field of `width` (0..32) bits at a bit offset of a word stream padded by one
// word. writeField replaces the field's bits (the stream is rewritten in place when widening).
inline uint32_t readField(const uint32_t* words, uint64_t offset, uint32_t width)
{
  if (width == 0)
    return 0;
  const uint64_t w = offset >> 5;
  const uint32_t shift = uint32_t(offset & 31);
  uint64_t pair = words[w] >> shift;
  if (shift + width > 32)
    pair |= uint64_t(words[w + 1]) << (32 - shift);
  return uint32_t(pair) & layout::lowMask(width);
}
inline void writeField(uint32_t* words, uint64_t offset, uint32_t width, uint32_t value)
{
  if (width == 0)
    return;
  const uint64_t w = offset >> 5;
  const uint32_t shift = uint32_t(offset & 31);
  const uint64_t mask = uint64_t(layout::lowMask(width)) << shift;
  const uint64_t bits = (uint64_t(value) << shift) & mask;
  words[w] = uint32_t((words[w] & ~uint32_t(mask)) | uint32_t(bits));
  if (shift + width > 32)
    words[w + 1] = uint32_t((words[w + 1] & ~uint32_t(mask >> 32)) | uint32_t(bits >> 32));
}

// Children per node from an 8-bit mask. Inline arithmetic: without -mpopcnt the compiler's
// popcount builtin is a library call, and node sizes are computed on every lookup.
inline uint32_t popcount8(uint32_t mask)
{
  mask = mask - ((mask >> 1) & 0x55u);
  mask = (mask & 0x33u) + ((mask >> 2) & 0x33u);
  return (mask + (mask >> 4)) & 0x0Fu;
}

// Open-addressing hash set of dense ids (0, 1, 2, ... in insertion order) whose keys live
// elsewhere (in a pool). Keys are compared exactly through the pool, so a hash collision never
// merges two different nodes. The tables are a large share of the builder's state, so:
// - a slot holds id + 1 (0 = empty) in just the bits the ids need until the next growth, beside
//   TagBits of the key's hash, so that most probes of other keys never read the pool (worth
//   it where comparing a key is costly: bit-packed nodes, not 64-bit leaf masks);
// - the slot count is not a power of two: a hash maps to a slot by multiply-shift, so the table
//   grows by 1.45x and stays between 55% and 80% full, where linear probing is still short;
// - growing frees the old slots first and re-inserts ids 0..count-1 from the pool, which walks
//   the pool in order (cheap) and needs no second table alive.
template <uint32_t TagBits>
class IdTable
{
public:
  // hashAll(place) must call place(id, hash) for every id inserted so far.
  template <class Equal, class Insert, class HashAll>
  uint32_t intern(uint64_t hash, const Equal& equalsId, const Insert& insert, const HashAll& hashAll)
  {
    if ((count + 1) * 5 > slotCount * 4)
      rebuild(std::max<size_t>(1024, (count + 1) * 20 / 11), hashAll);
    const uint64_t tag = hash & TagMask;
    for (size_t i = home(hash);; i = next(i))
    {
      const uint64_t stored = slot(i);
      if (stored == 0)
      {
        const uint32_t added = insert();
        if (added != count)
          throw std::logic_error("IdTable: ids must be dense and in insertion order");
        ++count;
        setSlot(i, added, hash);
        return added;
      }
      if ((stored & TagMask) == tag && equalsId(uint32_t((stored >> TagBits) - 1)))
        return uint32_t((stored >> TagBits) - 1);
    }
  }
  void clear()
  {
    words.release();
    slotCount = count = 0;
  }

private:
  size_t home(uint64_t hash) const { return size_t((unsigned __int128)hash * slotCount >> 64); }
  size_t next(size_t i) const { return i + 1 == slotCount ? 0 : i + 1; }
  static constexpr uint64_t TagMask = (uint64_t(1) << TagBits) - 1;
  // A slot is ((id + 1) << TagBits | tag), at most 32 + TagBits bits: read as two fields.
  uint64_t slot(size_t i) const
  {
    const uint64_t at = uint64_t(i) * slotBits;
    if (slotBits <= 32)
      return readField(words.data(), at, slotBits);
    return readField(words.data(), at, TagBits) |
      (uint64_t(readField(words.data(), at + TagBits, slotBits - TagBits)) << TagBits);
  }
  void setSlot(size_t i, uint32_t id, uint64_t hash)
  {
    const uint64_t at = uint64_t(i) * slotBits;
    if (TagBits > 0)
      writeField(words.data(), at, TagBits, uint32_t(hash & TagMask));
    writeField(words.data(), at + TagBits, slotBits - TagBits, id + 1);
  }

  template <class HashAll>
  void rebuild(size_t n, const HashAll& hashAll)
  {
    // Ids stay below 80% of n until the next growth; id + 1 must fit a slot.
    const uint32_t bits = TagBits + std::min<uint32_t>(32, bitWidth(uint64_t(n) * 4 / 5 + 2));
    words.release();
    words.resize(size_t((uint64_t(n) * bits + 31) / 32 + 1));
    slotCount = n;
    slotBits = bits;
    hashAll([&](uint32_t id, uint64_t hash) {
      size_t i = home(hash);
      while (slot(i) != 0)
        i = next(i);
      setSlot(i, id, hash);
    });
  }
  GrowArray<uint32_t> words; // slotCount fields of slotBits, padded by one word
  size_t slotCount = 0;
  size_t count = 0;
  uint32_t slotBits = TagBits + 1;
};

// A deduplicated pool of nodes [header:16][ref x popcount(mixed)], kept in the layout's bit-packed
// form with child references (childId << 1 | complement) refBits() wide. Ids are first-seen order.
// The reference width follows the child pool: widenTo() re-packs the stream in place, back to
// front, so a pool of leaf-referencing nodes is already its final stream when building ends.
// Only every AnchorStride-th node's bit offset is stored; a node is found from its group's anchor
// by skipping the headers before it (a 32-bit offset per node would be a third of the stream).
class PackedNodePool
{
public:
  static constexpr uint32_t AnchorStride = 4;

  // Returns the id of the node (header, refs), inserting it if new. Every ref must fit refBits().
  uint32_t intern(uint32_t header, const uint32_t* refs)
  {
    const uint32_t n = popcount8(layout::nodeMixedMask(header));
    return table.intern(
      hashOf(header, refs, n),
      [&](uint32_t id) { return equals(id, header, refs, n); },
      [&]() { return append(header, refs, n); },
      [&](const auto& place) {
        uint64_t at = 0;
        for (uint32_t id = 0; id < nodes; ++id)
        {
          uint32_t stored[8];
          const uint32_t h = readAt(at, width, stored);
          const uint32_t count = popcount8(layout::nodeMixedMask(h));
          place(id, hashOf(h, stored, count));
          at += layout::NODE_HEADER_BITS + uint64_t(count) * width;
        }
      });
  }

  size_t size() const { return nodes; }
  uint32_t refBits() const { return width; }
  // Bit offset of node `id` in the stream.
  uint64_t offset(uint32_t id) const
  {
    uint64_t at = anchors[id / AnchorStride];
    for (uint32_t k = id - id % AnchorStride; k < id; ++k)
      at += nodeBits(readField(words.data(), at, layout::NODE_HEADER_BITS), width);
    return at;
  }
  // Reads node `id`: returns its header and writes its child references into refs[0..7].
  uint32_t read(uint32_t id, uint32_t* refs) const { return readAt(offset(id), width, refs); }

  // Re-packs every node with `newBits`-wide references (newBits >= refBits()), in place.
  void widenTo(uint32_t newBits)
  {
    if (newBits <= width)
      return;
    const uint64_t refCount = (totalBits - layout::NODE_HEADER_BITS * nodes) / width;
    const uint64_t newTotal = layout::NODE_HEADER_BITS * nodes + refCount * newBits;
    checkOffset(newTotal);
    words.resize(size_t((newTotal + 31) / 32 + 1));
    // A node only moves towards the end, past the old end of every node before it, so going
    // back to front never overwrites a node that is still to be read.
    for (size_t group = anchors.size(); group-- > 0;)
    {
      const uint64_t first = uint64_t(group) * AnchorStride;
      const uint32_t inGroup = uint32_t(std::min<uint64_t>(AnchorStride, nodes - first));
      uint64_t old[AnchorStride];
      old[0] = anchors[group];
      for (uint32_t k = 1; k < inGroup; ++k)
        old[k] = old[k - 1] + nodeBits(readField(words.data(), old[k - 1], layout::NODE_HEADER_BITS), width);
      for (uint32_t k = inGroup; k-- > 0;)
      {
        uint32_t refs[8];
        const uint32_t header = readAt(old[k], width, refs);
        const uint64_t id = first + k;
        const uint64_t refsBefore = (old[k] - layout::NODE_HEADER_BITS * id) / width;
        const uint64_t at = layout::NODE_HEADER_BITS * id + refsBefore * newBits;
        writeAt(at, newBits, header, refs);
        if (k == 0)
          anchors[group] = uint32_t(at);
      }
    }
    width = newBits;
    totalBits = newTotal;
  }

  // Lookups end when the pool is complete; reading nodes does not need the table.
  void releaseTable() { table.clear(); }
  // The packed stream (padded by one zero word); the pool's stream is released.
  std::vector<uint32_t> takeStream()
  {
    words.resize(size_t((totalBits + 31) / 32 + 1));
    return words.takeVector();
  }
  void release()
  {
    table.clear();
    words.release();
    anchors.release();
    totalBits = 0;
    nodes = 0;
  }

private:
  static uint64_t nodeBits(uint32_t header, uint32_t refWidth)
  {
    return layout::NODE_HEADER_BITS + uint64_t(popcount8(layout::nodeMixedMask(header))) * refWidth;
  }
  static uint64_t hashOf(uint32_t header, const uint32_t* refs, uint32_t n)
  {
    uint64_t h = mix64(header);
    for (uint32_t r = 0; r < n; ++r)
      h = mix64(h ^ refs[r]);
    return h;
  }
  uint32_t readAt(uint64_t at, uint32_t refWidth, uint32_t* refs) const
  {
    const uint32_t header = readField(words.data(), at, layout::NODE_HEADER_BITS);
    const uint32_t n = popcount8(layout::nodeMixedMask(header));
    for (uint32_t r = 0; r < n; ++r)
      refs[r] = readField(words.data(), at + layout::NODE_HEADER_BITS + uint64_t(r) * refWidth, refWidth);
    return header;
  }
  bool equals(uint32_t id, uint32_t header, const uint32_t* refs, uint32_t n) const
  {
    const uint64_t at = offset(id);
    if (readField(words.data(), at, layout::NODE_HEADER_BITS) != header)
      return false;
    for (uint32_t r = 0; r < n; ++r)
    {
      if (readField(words.data(), at + layout::NODE_HEADER_BITS + uint64_t(r) * width, width) != refs[r])
        return false;
    }
    return true;
  }
  void writeAt(uint64_t at, uint32_t refWidth, uint32_t header, const uint32_t* refs)
  {
    writeField(words.data(), at, layout::NODE_HEADER_BITS, header);
    const uint32_t n = popcount8(layout::nodeMixedMask(header));
    for (uint32_t r = 0; r < n; ++r)
      writeField(words.data(), at + layout::NODE_HEADER_BITS + uint64_t(r) * refWidth, refWidth, refs[r]);
  }
  uint32_t append(uint32_t header, const uint32_t* refs, uint32_t n)
  {
    if (nodes >= 0xFFFFFFFEu)
      throw std::length_error("SVDAG too large: a node pool exceeds 2^32 nodes");
    const uint64_t end = totalBits + layout::NODE_HEADER_BITS + uint64_t(n) * width;
    checkOffset(end);
    words.resize(size_t((end + 31) / 32 + 1));
    writeAt(totalBits, width, header, refs);
    if (nodes % AnchorStride == 0)
      anchors.push_back(uint32_t(totalBits));
    totalBits = end;
    return uint32_t(nodes++);
  }
  // Node offsets are stored in 32 bits; the layout's references cannot address more anyway.
  static void checkOffset(uint64_t bitsUsed)
  {
    if (bitsUsed > 0xFFFFFFFFull)
      throw std::length_error("SVDAG too large: a node stream exceeds 2^32 bits");
  }
  IdTable<4> table;
  GrowArray<uint32_t> words;   // bit stream, padded by at least one zero word
  GrowArray<uint32_t> anchors; // bit offset of nodes 0, AnchorStride, 2 AnchorStride, ...
  uint64_t totalBits = 0;
  uint64_t nodes = 0;
  uint32_t width = 1;
};

// Fixed-width records of FieldCount bit fields, bit-packed back to back. A field's width can
// grow (widenTo re-packs every record in place, back to front, like PackedNodePool).
template <uint32_t FieldCount>
class PackedRecords
{
public:
  using Record = std::array<uint32_t, FieldCount>;

  size_t size() const { return count; }
  void push_back(const Record& r)
  {
    const uint64_t at = uint64_t(count) * recordBits;
    words.resize(size_t((at + recordBits + 31) / 32 + 1));
    writeAt(at, widths, r);
    ++count;
  }
  Record operator[](size_t i) const { return readAt(uint64_t(i) * recordBits, widths); }

  // Makes field f at least `bits` wide (0..32), re-packing the records if it grows.
  void widenTo(uint32_t f, uint32_t bits)
  {
    if (bits <= widths[f])
      return;
    Record newWidths = widths;
    newWidths[f] = bits;
    const uint32_t newRecordBits = sum(newWidths);
    words.resize(size_t((uint64_t(count) * newRecordBits + 31) / 32 + 1));
    // Record i moves from i * recordBits to i * newRecordBits, past the old end of record i - 1.
    for (size_t i = count; i-- > 0;)
      writeAt(uint64_t(i) * newRecordBits, newWidths, readAt(uint64_t(i) * recordBits, widths));
    widths = newWidths;
    recordBits = newRecordBits;
  }
  void release()
  {
    words.release();
    count = 0;
  }

private:
  static uint32_t sum(const Record& w)
  {
    uint32_t total = 0;
    for (uint32_t x : w)
      total += x;
    return total;
  }
  Record readAt(uint64_t at, const Record& w) const
  {
    Record r;
    for (uint32_t f = 0; f < FieldCount; at += w[f], ++f)
      r[f] = readField(words.data(), at, w[f]);
    return r;
  }
  void writeAt(uint64_t at, const Record& w, const Record& r)
  {
    for (uint32_t f = 0; f < FieldCount; at += w[f], ++f)
      writeField(words.data(), at, w[f], r[f]);
  }
  GrowArray<uint32_t> words; // padded by one word
  Record widths{};
  uint32_t recordBits = 0;
  size_t count = 0;
};

} // namespace build
} // namespace svdag
