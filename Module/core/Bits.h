// Bit helpers of the core's implementation files (private; not installed): field widths, the
// hash mixer of the pools, and reading and writing bit-packed fields of a word stream.
#pragma once

#include "svdag/Layout.h"

#include <cstddef>
#include <cstdint>
#include <vector>

#ifndef SVDAG_WORD
#define SVDAG_WORD(stream, i) (stream)[(i)]
#endif

namespace svdag
{
namespace bits
{
// Bits needed to write v (0 for 0).
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

// The `width` (0..32) bits at `offset` of a stream padded by one zero word (Layout.h).
inline uint32_t readBits(const std::vector<uint32_t>& stream, uint64_t offset, uint32_t width)
{
  uint32_t result;
  SVDAG_READ_BITS(result, stream, offset, width);
  return result;
}

// Bit counts without a library call (the core is built for any x86-64, without POPCNT, where
// __builtin_popcount calls libgcc).
inline uint32_t popcount64(uint64_t x)
{
  x = x - ((x >> 1) & 0x5555555555555555ull);
  x = (x & 0x3333333333333333ull) + ((x >> 2) & 0x3333333333333333ull);
  x = (x + (x >> 4)) & 0x0F0F0F0F0F0F0F0Full;
  return uint32_t((x * 0x0101010101010101ull) >> 56);
}
inline uint32_t popcount8(uint32_t x)
{
  x = x - ((x >> 1) & 0x55u);
  x = (x & 0x33u) + ((x >> 2) & 0x33u);
  return (x + (x >> 4)) & 0x0Fu;
}

// Unsigned LEB128 numbers (the .svdag 4.0 file's): 7 bits a byte, the lowest first, the high bit
// set on every byte but the last.
inline void putVarint(std::vector<uint8_t>& out, uint64_t v)
{
  for (; v >= 0x80u; v >>= 7)
    out.push_back(uint8_t(v | 0x80u));
  out.push_back(uint8_t(v));
}
// Reads one from [at, end) and moves `at` past it; false (at unchanged) when it runs past `end`
// or holds more than 64 bits.
inline bool getVarint(const uint8_t*& at, const uint8_t* end, uint64_t& v)
{
  uint64_t value = 0;
  for (const uint8_t* p = at; p != end; ++p)
  {
    const uint32_t shift = uint32_t(7 * (p - at));
    if (shift > 63 || (shift == 63 && (*p & 0x7Fu) > 1u))
      return false;
    value |= uint64_t(*p & 0x7Fu) << shift;
    if (!(*p & 0x80u))
    {
      at = p + 1;
      v = value;
      return true;
    }
  }
  return false;
}

// Little-endian fields of a byte buffer, whatever the host's byte order (compilers turn these
// into plain loads and stores on little-endian hosts): the .svdag file's and its coded volume's.
inline void storeLE(uint8_t* at, uint64_t v, int n)
{
  for (int i = 0; i < n; ++i)
    at[i] = uint8_t(v >> (8 * i));
}
inline uint64_t loadLE(const uint8_t* at, int n)
{
  uint64_t v = 0;
  for (int i = 0; i < n; ++i)
    v |= uint64_t(at[i]) << (8 * i);
  return v;
}

// ORs `value` (at most `width` bits, 0..32) into a zero-filled field of a stream that has a word
// past the field's last one. It writes the word after the field's first word either way (zero
// bits where the field ends before it): whether a field straddles two words changes from field
// to field, a branch a load would mispredict at every other field. So no other thread may write
// that word meanwhile.
inline void writeBits(std::vector<uint32_t>& stream, uint64_t offset, uint32_t width, uint32_t value)
{
  if (width == 0)
    return;
  const uint64_t word = offset >> 5;
  const uint64_t wide = uint64_t(value) << (offset & 31);
  stream[size_t(word)] |= uint32_t(wide);
  stream[size_t(word + 1)] |= uint32_t(wide >> 32);
}
// Sets a field (whatever it held) to `value` (at most `width` bits, 0..32), as writeBits.
inline void replaceBits(
  std::vector<uint32_t>& stream, uint64_t offset, uint32_t width, uint32_t value)
{
  const uint64_t word = offset >> 5;
  const uint32_t shift = uint32_t(offset & 31);
  const uint64_t mask = uint64_t(layout::lowMask(width)) << shift;
  uint64_t pair = stream[size_t(word)] | (uint64_t(stream[size_t(word + 1)]) << 32);
  pair = (pair & ~mask) | (uint64_t(value) << shift);
  stream[size_t(word)] = uint32_t(pair);
  stream[size_t(word + 1)] = uint32_t(pair >> 32);
}
} // namespace bits
} // namespace svdag
