// Random access (RandomAccess.h) and label statistics (LabelStatistics.h) against brute force
// on the raw labels the volume was built from.
#include "ThreadedFor.h"
#include "svdag/Builder.h"
#include "svdag/Decoder.h"
#include "svdag/LabelStatistics.h"
#include "svdag/RandomAccess.h"

#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <random>
#include <stdexcept>

using svdag::Box;
using svdag::ScalarType;

namespace
{
struct Fixture
{
  svdag::Geometry g;
  std::vector<uint16_t> labels; // x fastest
  svdag::Volume v;
  uint16_t at(int x, int y, int z) const
  {
    return labels[size_t(x) + size_t(g.dims[0]) * (size_t(y) + size_t(g.dims[1]) * size_t(z))];
  }
};

Fixture makeVolume(int nx, int ny, int nz, unsigned seed)
{
  Fixture f;
  f.g.dims = { { nx, ny, nz } };
  f.labels.resize(size_t(nx) * ny * nz);
  std::mt19937 rng(seed);
  for (int z = 0; z < nz; ++z)
    for (int y = 0; y < ny; ++y)
      for (int x = 0; x < nx; ++x)
      {
        uint16_t l = uint16_t((x / 6 + 2 * (y / 5) + 3 * (z / 9)) % 6);
        if (rng() % 20 == 0)
          l = uint16_t(rng() % 6);
        f.labels[size_t(x) + size_t(nx) * (size_t(y) + size_t(ny) * size_t(z))] = l;
      }
  f.v = svdag::Builder::build(f.g, ScalarType::UInt16, f.labels.data());
  return f;
}
} // namespace

TEST(RandomAccess, BoxesSlicesAndMasksMatchTheRawLabels)
{
  const Fixture f = makeVolume(37, 21, 50, 1);
  std::mt19937 rng(5);
  for (int trial = 0; trial < 40; ++trial)
  {
    Box b;
    for (int a = 0; a < 3; ++a)
    {
      const int n = f.g.dims[a];
      const int lo = int(rng() % unsigned(n));
      b[2 * a] = lo;
      b[2 * a + 1] = lo + int(rng() % unsigned(n - lo));
    }
    const auto parallel = trial % 2 ? threadedFor(3) : svdag::ParallelFor(svdag::sequentialFor);
    const std::vector<uint8_t> bytes = svdag::decodeBox(f.v, b, parallel);
    const uint16_t* got = reinterpret_cast<const uint16_t*>(bytes.data());
    std::vector<uint8_t> mask(svdag::boxVoxels(b));
    const uint32_t label = uint32_t(trial % f.v.labels.size());
    svdag::decodeMask(f.v, label, b, mask.data(), parallel);
    size_t i = 0;
    for (int z = b[4]; z <= b[5]; ++z)
      for (int y = b[2]; y <= b[3]; ++y)
        for (int x = b[0]; x <= b[1]; ++x, ++i)
        {
          ASSERT_EQ(got[i], f.at(x, y, z)) << x << " " << y << " " << z;
          ASSERT_EQ(mask[i], f.at(x, y, z) == f.v.labels[label].value ? 1 : 0);
        }
  }
  // Slices are one-voxel boxes.
  EXPECT_EQ(svdag::sliceBox(f.v, 1, 20), (Box{ { 0, 36, 20, 20, 0, 49 } }));
}

TEST(RandomAccess, AxisPlaneResamplingIsTheSlice)
{
  const Fixture f = makeVolume(33, 18, 20, 2);
  svdag::PlaneSampling p;
  p.origin = { { 0, 0, 7 } };
  p.nu = 33;
  p.nv = 18;
  std::vector<uint16_t> out(size_t(p.nu) * p.nv);
  svdag::resamplePlane(f.v, p, out.data(), threadedFor(2));
  for (int y = 0; y < 18; ++y)
    for (int x = 0; x < 33; ++x)
      ASSERT_EQ(out[size_t(x) + 33 * size_t(y)], f.at(x, y, 7));
  // Shifted by just under half a voxel: still the same voxels; outside: the background.
  p.origin = { { 0.49, -0.49, 7.4 } };
  svdag::resamplePlane(f.v, p, out.data());
  EXPECT_EQ(out[5 + 33 * 4], f.at(5, 4, 7));
  p.origin = { { 0, 0, -0.6 } };
  svdag::resamplePlane(f.v, p, out.data());
  for (uint16_t value : out)
    ASSERT_EQ(value, 0);
}

TEST(RandomAccess, LabelStatisticsMatchBruteForce)
{
  const Fixture f = makeVolume(35, 19, 41, 3);
  std::map<uint64_t, svdag::LabelStatistics> expected;
  const auto& d = f.g.dims;
  for (int z = 0; z < d[2]; ++z)
    for (int y = 0; y < d[1]; ++y)
      for (int x = 0; x < d[0]; ++x)
      {
        const uint16_t l = f.at(x, y, z);
        if (l == 0)
          continue;
        auto& s = expected[l];
        ++s.voxels;
        s.indexSum[0] += uint64_t(x);
        s.indexSum[1] += uint64_t(y);
        s.indexSum[2] += uint64_t(z);
        const int n[6][3] = { { -1, 0, 0 }, { 1, 0, 0 }, { 0, -1, 0 }, { 0, 1, 0 }, { 0, 0, -1 },
          { 0, 0, 1 } };
        bool open = false;
        for (const auto& o : n)
        {
          const int a = x + o[0], b = y + o[1], c = z + o[2];
          open = open || a < 0 || b < 0 || c < 0 || a >= d[0] || b >= d[1] || c >= d[2] ||
            f.at(a, b, c) != l;
        }
        s.surfaceVoxels += open ? 1 : 0;
      }
  for (const auto& parallel : { svdag::ParallelFor(svdag::sequentialFor), threadedFor(3) })
  {
    const auto stats = svdag::labelStatistics(f.v, parallel);
    ASSERT_EQ(stats.size(), expected.size());
    for (size_t i = 0; i < stats.size(); ++i)
    {
      const auto& e = expected.at(f.v.labels[i].value);
      EXPECT_EQ(stats[i].voxels, e.voxels);
      EXPECT_EQ(stats[i].voxels, f.v.labels[i].voxels);
      EXPECT_EQ(stats[i].indexSum, e.indexSum);
      EXPECT_EQ(stats[i].surfaceVoxels, e.surfaceVoxels);
    }
  }
}

TEST(RandomAccess, RejectsBadRequests)
{
  const Fixture f = makeVolume(20, 20, 20, 4);
  std::vector<uint8_t> out(8000 * 2);
  EXPECT_THROW(svdag::decodeBox(f.v, Box{ { 3, 2, 0, 0, 0, 0 } }, out.data()), std::invalid_argument);
  EXPECT_THROW(svdag::decodeBox(f.v, Box{ { 0, 20, 0, 0, 0, 0 } }, out.data()), std::out_of_range);
  EXPECT_THROW(svdag::decodeBox(f.v, Box{ { -1, 2, 0, 0, 0, 0 } }, out.data()), std::out_of_range);
  EXPECT_THROW(svdag::sliceBox(f.v, 3, 0), std::invalid_argument);
  EXPECT_THROW(svdag::sliceBox(f.v, 0, 20), std::out_of_range);
  EXPECT_THROW(svdag::decodeMask(f.v, 99, svdag::volumeBox(f.v), out.data()), std::out_of_range);
  svdag::PlaneSampling p;
  p.nu = -1;
  EXPECT_THROW(svdag::checkPlaneSampling(f.v, p), std::invalid_argument);
  p.nu = 1 << 30;
  p.nv = 1 << 30;
  EXPECT_THROW(svdag::checkPlaneSampling(f.v, p), std::length_error);
  p.nu = p.nv = 1;
  p.origin[0] = NAN;
  EXPECT_THROW(svdag::checkPlaneSampling(f.v, p), std::invalid_argument);
}
