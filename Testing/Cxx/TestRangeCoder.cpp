// The range coder of the .svdag 3.0 file (RangeCoder.h): what the Encoder writes, the Decoder
// reads back, for bits of every skew and for direct bits, and a shortened stream fails.
#include "RangeCoder.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

namespace
{
using svdag::coding::BitModel;

struct Symbol
{
  bool direct;
  uint32_t model; // or the number of direct bits
  uint32_t value;
};

// Bits from models of very different skews, interleaved with direct fields of 0..32 bits.
std::vector<Symbol> symbols(size_t n, uint64_t seed)
{
  std::mt19937_64 rng(seed);
  const double skews[] = { 0.5, 0.9, 0.99, 0.999, 0.0001, 0.3 };
  std::vector<Symbol> out;
  for (size_t i = 0; i < n; ++i)
  {
    if (rng() % 17 == 0)
    {
      const uint32_t count = uint32_t(rng() % 33);
      out.push_back({ true, count, count == 0 ? 0u : uint32_t(rng()) & (0xFFFFFFFFu >> (32 - count)) });
      continue;
    }
    const uint32_t m = uint32_t(rng() % 6);
    const uint32_t one = std::uniform_real_distribution<double>(0, 1)(rng) < skews[m] ? 0u : 1u;
    out.push_back({ false, m, one });
  }
  return out;
}

template <class Coder>
std::vector<uint32_t> run(Coder& coder, const std::vector<Symbol>& input)
{
  BitModel models[6];
  std::vector<uint32_t> out;
  for (const Symbol& s : input)
    out.push_back(s.direct ? coder.direct(s.value, s.model) : coder.bit(models[s.model], s.value));
  return out;
}
} // namespace

TEST(RangeCoder, DecodesWhatItEncodes)
{
  for (uint64_t seed : { 1, 2, 3 })
  {
    const std::vector<Symbol> input = symbols(200000, seed);
    svdag::coding::Encoder encoder;
    run(encoder, input);
    const std::vector<uint8_t> bytes = encoder.finish();
    svdag::coding::Decoder decoder(bytes.data(), bytes.size());
    const std::vector<uint32_t> decoded = run(decoder, input);
    for (size_t i = 0; i < input.size(); ++i)
      ASSERT_EQ(decoded[i], input[i].value) << "symbol " << i;
    EXPECT_LE(decoder.consumed(), bytes.size());
  }
}

// Skewed bits cost what their entropy says, within 10%: the models adapt (the fast one's
// estimate wanders on a stationary source, the price of following changes quickly).
TEST(RangeCoder, SkewedBitsCostTheirEntropy)
{
  for (double p : { 0.5, 0.9, 0.99 })
  {
    std::mt19937_64 rng(7);
    svdag::coding::Encoder encoder;
    BitModel model;
    const size_t n = 400000;
    for (size_t i = 0; i < n; ++i)
      encoder.bit(model, std::uniform_real_distribution<double>(0, 1)(rng) < p ? 0u : 1u);
    const double bits = 8.0 * double(encoder.finish().size());
    const double entropy = n * -(p * std::log2(p) + (1 - p) * std::log2(1 - p));
    EXPECT_LT(bits, entropy * 1.10 + 64) << "p = " << p;
    EXPECT_GT(bits, entropy * 0.97) << "p = " << p;
  }
}

TEST(RangeCoder, ShortenedOrForeignStreamsFail)
{
  const std::vector<Symbol> input = symbols(50000, 4);
  svdag::coding::Encoder encoder;
  run(encoder, input);
  const std::vector<uint8_t> bytes = encoder.finish();
  // Cut well short, the decoder runs past the end and says so.
  svdag::coding::Decoder shortened(bytes.data(), bytes.size() / 2);
  EXPECT_THROW(run(shortened, input), svdag::coding::CorruptStream);
  EXPECT_THROW(svdag::coding::Decoder(bytes.data(), 4), svdag::coding::CorruptStream);
  std::vector<uint8_t> foreign = bytes;
  foreign[0] = 1; // every stream starts with a zero byte
  EXPECT_THROW(svdag::coding::Decoder(foreign.data(), foreign.size()), svdag::coding::CorruptStream);
}
