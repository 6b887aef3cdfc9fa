// Lossless round trips and structural invariants of the builder, on synthetic volumes.
#include "svdag/Builder.h"

#include <gtest/gtest.h>

#include <random>

namespace
{
template <class T>
std::vector<T> randomLabels(const svdag::Geometry& g, int labels, uint32_t seed)
{
  std::mt19937 rng(seed);
  std::vector<T> v(g.voxelCount());
  std::uniform_int_distribution<int> d(0, labels - 1);
  for (auto& x : v)
    x = T(d(rng));
  return v;
}
} // namespace

TEST(Builder, RandomRoundTrip)
{
  svdag::Geometry g;
  g.dims = { { 37, 21, 19 } };
  auto labels = randomLabels<uint16_t>(g, 5, 1);
  const svdag::Volume v = svdag::Builder::build(g, svdag::ScalarType::UInt16, labels.data());
  v.validate();
  std::vector<uint16_t> out(labels.size());
  svdag::decode(v, out.data());
  EXPECT_EQ(out, labels);
  EXPECT_EQ(v.labels.size(), 4u);
}
