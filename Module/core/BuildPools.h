// Compact storage for the Builder's deduplicated pools (private to Builder.cpp).
//
// The builder's state must stay close to the size of its output (the issue asks for at most one
// slab plus 1.5x the output plus a constant), so the pools avoid the usual slack:
// - GrowArray grows by 1/4 through realloc (large blocks are remapped, not copied);
// - IdTable sizes its slots freely (not a power of two) and keeps them 55-80% full;
// - PackedNodePool keeps nodes bit-packed with the narrowest reference width their children's
//   pool needs so far, and widens the stream in place when that pool crosses a power of two.
#pragma once

#include "svdag/Layout.h"

#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <algorithm>
#include <new>
#include <stdexcept>
#include <type_traits>
#include <vector>

namespace svdag
{
namespace build
{

inline uint32_t bitWidth(uint64_t v)
{
  return v ? uint32_t(64 - __builtin_clzll(v)) : 0u;
}

inline uint64_t mix64(uint64_t x)
{
  x ^= x >> 30;
  x *= 0xbf58476d1ce4e5b9ULL;
  x ^= x >> 27;
  x *= 0x94d049bb133111ebULL;
  x ^= x >> 31;
  return x;
}

// A growable array of trivially copyable values with 25% growth slack at most.
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
    size_t next = capacity + capacity / 4;
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

// Open-addressing hash set of 32-bit ids whose keys live elsewhere (in a pool). Keys are compared
// exactly through the pool, so a hash collision never merges two different nodes. The slot count
// is not a power of two: a hash maps to a slot by multiply-shift, so the table can grow by 1.45x
// and stay between 55% and 80% full, where linear probing is still short.
class IdTable
{
public:
  template <class Hash, class Equal, class Insert>
  uint32_t intern(uint64_t hash, const Equal& equalsId, const Insert& insert, const Hash& hashOfId)
  {
    if ((count + 1) * 5 > slots.size() * 4)
      grow(hashOfId);
    const size_t n = slots.size();
    for (size_t i = home(hash, n);; i = (i + 1 == n) ? 0 : i + 1)
    {
      const uint32_t id = slots[i];
      if (id == Empty)
      {
        const uint32_t added = insert();
        slots[i] = added;
        ++count;
        return added;
      }
      if (equalsId(id))
        return id;
    }
  }
  void clear() { slots.release(); count = 0; }

private:
  static constexpr uint32_t Empty = 0xFFFFFFFFu;
  static size_t home(uint64_t hash, size_t n)
  {
    return size_t((unsigned __int128)hash * n >> 64);
  }
  template <class Hash>
  void grow(const Hash& hashOfId)
  {
    const size_t n = std::max<size_t>(1024, (count + 1) * 20 / 11); // 55% full after growing
    GrowArray<uint32_t> old;
    old.resize(n);
    std::memset(old.data(), 0xFF, n * sizeof(uint32_t));
    slots.swap(old);
    for (size_t k = 0; k < old.size(); ++k)
    {
      const uint32_t id = old[k];
      if (id == Empty)
        continue;
      size_t i = home(hashOfId(id), n);
      while (slots[i] != Empty)
        i = (i + 1 == n) ? 0 : i + 1;
      slots[i] = id;
    }
  }
  GrowArray<uint32_t> slots;
  size_t count = 0;
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

// A deduplicated pool of nodes [header:16][ref x popcount(mixed)], kept in the layout's bit-packed
// form with child references (childId << 1 | complement) refBits() wide. Ids are first-seen order.
// The reference width follows the child pool: widenTo() re-packs the stream in place, back to
// front, so a pool of leaf-referencing nodes is already its final stream when building ends.
class PackedNodePool
{
public:
  // Returns the id of the node (header, refs), inserting it if new. Every ref must fit refBits().
  uint32_t intern(uint32_t header, const uint32_t* refs)
  {
    const uint32_t n = layout::bitCount(layout::nodeMixedMask(header));
    return table.intern(
      hashOf(header, refs, n),
      [&](uint32_t id) { return equals(id, header, refs, n); },
      [&]() { return append(header, refs, n); },
      [&](uint32_t id) {
        uint32_t stored[8];
        const uint32_t h = read(id, stored);
        return hashOf(h, stored, layout::bitCount(layout::nodeMixedMask(h)));
      });
  }

  size_t size() const { return starts.size(); }
  uint32_t refBits() const { return width; }
  uint64_t bits() const { return totalBits; }
  // Bit offset of each node in the stream, by id.
  const GrowArray<uint32_t>& offsets() const { return starts; }
  // Reads node `id`: returns its header and writes its child references into refs[0..7].
  uint32_t read(uint32_t id, uint32_t* refs) const
  {
    const uint64_t at = starts[id];
    const uint32_t header = readField(words.data(), at, layout::NODE_HEADER_BITS);
    const uint32_t n = layout::bitCount(layout::nodeMixedMask(header));
    for (uint32_t r = 0; r < n; ++r)
      refs[r] = readField(words.data(), at + layout::NODE_HEADER_BITS + uint64_t(r) * width, width);
    return header;
  }

  // Re-packs every node with `newBits`-wide references (newBits >= refBits()), in place.
  void widenTo(uint32_t newBits)
  {
    if (newBits <= width)
      return;
    const uint64_t nodes = starts.size();
    const uint64_t refCount = width ? (totalBits - layout::NODE_HEADER_BITS * nodes) / width : 0;
    const uint64_t newTotal = layout::NODE_HEADER_BITS * nodes + refCount * newBits;
    checkOffset(newTotal);
    words.resize(size_t((newTotal + 31) / 32 + 1));
    // A node only moves towards the end, past the old end of every node before it, so going
    // back to front never overwrites a node that is still to be read.
    for (uint64_t id = nodes; id-- > 0;)
    {
      uint32_t refs[8];
      const uint32_t header = read(uint32_t(id), refs);
      const uint64_t old = starts[id];
      const uint64_t refsBefore = width ? (old - layout::NODE_HEADER_BITS * id) / width : 0;
      const uint64_t at = layout::NODE_HEADER_BITS * id + refsBefore * newBits;
      const uint32_t oldWidth = width;
      width = newBits;
      write(at, header, refs);
      width = oldWidth;
      starts[id] = uint32_t(at);
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
    starts.release();
    totalBits = 0;
  }

private:
  static uint64_t hashOf(uint32_t header, const uint32_t* refs, uint32_t n)
  {
    uint64_t h = mix64(header);
    for (uint32_t r = 0; r < n; ++r)
      h = mix64(h ^ refs[r]);
    return h;
  }
  bool equals(uint32_t id, uint32_t header, const uint32_t* refs, uint32_t n) const
  {
    const uint64_t at = starts[id];
    if (readField(words.data(), at, layout::NODE_HEADER_BITS) != header)
      return false;
    for (uint32_t r = 0; r < n; ++r)
    {
      if (readField(words.data(), at + layout::NODE_HEADER_BITS + uint64_t(r) * width, width) != refs[r])
        return false;
    }
    return true;
  }
  void write(uint64_t at, uint32_t header, const uint32_t* refs)
  {
    writeField(words.data(), at, layout::NODE_HEADER_BITS, header);
    const uint32_t n = layout::bitCount(layout::nodeMixedMask(header));
    for (uint32_t r = 0; r < n; ++r)
      writeField(words.data(), at + layout::NODE_HEADER_BITS + uint64_t(r) * width, width, refs[r]);
  }
  uint32_t append(uint32_t header, const uint32_t* refs, uint32_t n)
  {
    if (starts.size() >= 0xFFFFFFFEu)
      throw std::length_error("SVDAG too large: a node pool exceeds 2^32 nodes");
    const uint64_t end = totalBits + layout::NODE_HEADER_BITS + uint64_t(n) * width;
    checkOffset(end);
    words.resize(size_t((end + 31) / 32 + 1));
    write(totalBits, header, refs);
    starts.push_back(uint32_t(totalBits));
    totalBits = end;
    return uint32_t(starts.size() - 1);
  }
  // Node offsets are stored in 32 bits; the layout's references cannot address more anyway.
  static void checkOffset(uint64_t bitsUsed)
  {
    if (bitsUsed > 0xFFFFFFFFull)
      throw std::length_error("SVDAG too large: a node stream exceeds 2^32 bits");
  }
  IdTable table;
  GrowArray<uint32_t> words; // bit stream, padded by at least one zero word
  GrowArray<uint32_t> starts;
  uint64_t totalBits = 0;
  uint32_t width = 1;
};

} // namespace build
} // namespace svdag
