// Adaptive binary arithmetic coding for the .svdag 3.0 file's coded volume (private to the core;
// not installed).
//
// A range coder over 32-bit ranges with byte output and carry propagation, driven by adaptive bit
// models: each model estimates the probability of a 0 twice, adapting quickly (1/16 per bit) and
// slowly (1/128 per bit), and codes with their mean, which follows both short runs and stable
// statistics. The coding procedure is written once for both directions: it calls
// `coder.bit(model, value)`, which the Encoder writes and returns and the Decoder ignores and
// replaces with the decoded bit, so the two can never disagree about the sequence of models.
#pragma once

#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <vector>

namespace svdag
{
namespace coding
{

// Thrown by the Decoder for a stream that cannot have been written by the Encoder.
struct CorruptStream : std::runtime_error
{
  using std::runtime_error::runtime_error;
};

class BitModel
{
public:
  // Probability of a 0 in 1/65536 units, within [71, 65465] by the update rules below, so that
  // either bit keeps a non-empty share of any range the coder holds.
  uint32_t zeroProbability() const { return (uint32_t(Fast) + uint32_t(Slow)) >> 1; }
  // Without branches: decoded bits are hard to predict.
  void update(uint32_t bit)
  {
    const uint32_t fast = Fast, slow = Slow;
    Fast = uint16_t(bit ? fast - (fast >> 4) : fast + ((65536u - fast) >> 4));
    Slow = uint16_t(bit ? slow - (slow >> 7) : slow + ((65536u - slow) >> 7));
  }

private:
  uint16_t Fast = 32768, Slow = 32768;
};

constexpr uint32_t TopOfRange = 1u << 24; // below it, the range takes in another byte

class Encoder
{
public:
  uint32_t bit(BitModel& model, uint32_t value)
  {
    const uint32_t bound = (Range >> 16) * model.zeroProbability();
    if (value)
    {
      Low += bound;
      Range -= bound;
    }
    else
      Range = bound;
    model.update(value);
    normalize();
    return value;
  }
  // The low `count` (0..32) bits of value, most significant first, each with probability 1/2.
  uint32_t direct(uint32_t value, uint32_t count)
  {
    for (uint32_t i = count; i-- > 0;)
    {
      Range >>= 1;
      if ((value >> i) & 1u)
        Low += Range;
      normalize();
    }
    return value;
  }
  // Flushes the state; the bytes are complete afterwards.
  std::vector<uint8_t> finish()
  {
    for (int i = 0; i < 5; ++i)
      shiftLow();
    return std::move(Bytes);
  }

private:
  void normalize()
  {
    while (Range < TopOfRange)
    {
      Range <<= 8;
      shiftLow();
    }
  }
  // Moves the top byte of Low out. A byte of 0xFF may still change by a carry, so runs of them
  // wait (Pending) until a byte below 0xFF or a carry settles them.
  void shiftLow()
  {
    if (uint32_t(Low) < 0xFF000000u || (Low >> 32) != 0)
    {
      const uint8_t carry = uint8_t(Low >> 32);
      uint8_t held = Held;
      do
      {
        Bytes.push_back(uint8_t(held + carry));
        held = 0xFF;
      } while (--Pending != 0);
      Held = uint8_t(Low >> 24);
    }
    ++Pending;
    Low = (Low & 0x00FFFFFFu) << 8;
  }

  uint64_t Low = 0;
  uint32_t Range = 0xFFFFFFFFu;
  uint8_t Held = 0;
  uint64_t Pending = 1;
  std::vector<uint8_t> Bytes;
};

class Decoder
{
public:
  // Throws CorruptStream if the stream does not start as the Encoder starts every stream.
  Decoder(const uint8_t* data, size_t size)
    : Data(data)
    , Size(size)
  {
    if (size < 5 || data[0] != 0)
      throw CorruptStream("the coded volume does not start with a range coder's first byte");
    for (int i = 0; i < 5; ++i)
      Code = (Code << 8) | next();
    if (Code == 0xFFFFFFFFu)
      throw CorruptStream("the coded volume starts outside the coder's range");
  }
  uint32_t bit(BitModel& model, uint32_t /*ignored*/)
  {
    const uint32_t bound = (Range >> 16) * model.zeroProbability();
    const uint32_t value = Code >= bound ? 1u : 0u;
    const uint32_t ones = 0u - value;
    Code -= bound & ones;
    Range = (bound & ~ones) | ((Range - bound) & ones);
    model.update(value);
    normalize();
    return value;
  }
  uint32_t direct(uint32_t /*ignored*/, uint32_t count)
  {
    uint32_t value = 0;
    for (uint32_t i = 0; i < count; ++i)
    {
      Range >>= 1;
      const uint32_t b = Code >= Range ? 1u : 0u;
      Code -= Range & (0u - b);
      value = (value << 1) | b;
      normalize();
    }
    return value;
  }
  // Bytes taken from the stream so far (the Encoder's flush is read up to its last 4 bytes).
  size_t consumed() const { return Position; }

private:
  void normalize()
  {
    while (Range < TopOfRange)
    {
      Range <<= 8;
      Code = (Code << 8) | next();
    }
  }
  // Past the end the stream reads as zeros, as the Encoder's flush would continue; a stream that
  // needs more than the flush's worth of them is truncated. This also bounds the work any input
  // can cause: no model is surer than 65465/65536, so every coded bit costs at least 1/640 of a
  // bit of input.
  uint32_t next()
  {
    if (Position < Size)
      return Data[Position++];
    if (++Overrun > 4)
      throw CorruptStream("the coded volume is truncated (its coder ran past the end)");
    return 0;
  }

  const uint8_t* Data;
  size_t Size;
  size_t Position = 0;
  uint32_t Overrun = 0;
  uint32_t Code = 0;
  uint32_t Range = 0xFFFFFFFFu;
};

} // namespace coding
} // namespace svdag
