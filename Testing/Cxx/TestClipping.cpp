// Clipping planes in the CPU ray caster (svdag::RayCaster::setClipPlanes, Clipping.h) against an
// independent brute force: the ray's interval is clipped by the planes here, in double, and every
// solid voxel of the raw label array is slab-tested inside it. Voxel LOD, random volumes, rays and
// planes (a plane's function need not be normalised in index space).
#include "svdag/Builder.h"
#include "svdag/RayCaster.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <stdexcept>
#include <vector>

namespace
{
using Plane = std::array<double, 4>;

struct Reference
{
  bool hit = false;
  double t = 0;
  bool onCut = false; // the nearest voxel is entered at the clipped tmin, moved by a plane
  int plane = -1;
  std::vector<uint32_t> labels; // labels of voxels entered at t (ties)
};

Reference bruteForce(const std::vector<uint32_t>& labels, int n, const svdag::Ray& ray,
  const std::vector<Plane>& planes)
{
  Reference ref;
  double t0 = ray.tmin, t1 = ray.tmax;
  int enter = -1;
  for (size_t i = 0; i < planes.size(); ++i)
  {
    const Plane& p = planes[i];
    double f = p[3], d = 0;
    for (int a = 0; a < 3; ++a)
    {
      f += p[size_t(a)] * ray.origin[size_t(a)];
      d += p[size_t(a)] * ray.direction[size_t(a)];
    }
    if (d == 0)
    {
      if (f < 0)
        return ref;
      continue;
    }
    const double t = -f / d;
    if (d > 0 && t > t0)
    {
      t0 = t;
      enter = int(i);
    }
    if (d < 0)
      t1 = std::min(t1, t);
  }
  if (!(t0 < t1))
    return ref;
  const double tol = 1e-7;
  double best = std::numeric_limits<double>::infinity();
  for (int z = 0; z < n; ++z)
    for (int y = 0; y < n; ++y)
      for (int x = 0; x < n; ++x)
      {
        const uint32_t l = labels[size_t(x + n * (y + n * z))];
        if (l == 0)
          continue;
        double a0 = t0, a1 = t1;
        const int v[3] = { x, y, z };
        for (int a = 0; a < 3; ++a)
        {
          const double lo = (v[a] - ray.origin[size_t(a)]) / ray.direction[size_t(a)];
          const double hi = (v[a] + 1 - ray.origin[size_t(a)]) / ray.direction[size_t(a)];
          a0 = std::max(a0, std::min(lo, hi));
          a1 = std::min(a1, std::max(lo, hi));
        }
        if (a1 - a0 <= tol)
          continue;
        if (a0 < best - tol)
        {
          best = a0;
          ref.labels.clear();
        }
        if (std::fabs(a0 - best) <= tol)
          ref.labels.push_back(l);
      }
  if (std::isinf(best))
    return ref;
  ref.hit = true;
  ref.t = best;
  ref.onCut = enter >= 0 && std::fabs(best - t0) <= tol;
  ref.plane = enter;
  return ref;
}

TEST(Clipping, RayCasterMatchesBruteForce)
{
  std::mt19937 rng(2024);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::normal_distribution<double> gauss;
  const int n = 20;
  std::vector<uint32_t> labels(size_t(n * n * n));
  for (auto& l : labels)
    l = unit(rng) < 0.3 ? 1 + uint32_t(unit(rng) * 5) : 0;
  svdag::Geometry g;
  g.dims = { { n, n, n } };
  const svdag::Volume volume =
    svdag::Builder::build(g, svdag::ScalarType::UInt32, labels.data(), svdag::BuildOptions());
  svdag::RayCaster caster(volume);

  int hits = 0, cuts = 0;
  for (int trial = 0; trial < 40; ++trial)
  {
    std::vector<Plane> planes(size_t(1 + trial % 3));
    for (auto& p : planes)
    {
      double len = 0;
      for (int a = 0; a < 3; ++a)
      {
        p[size_t(a)] = gauss(rng) * (a + 1); // not unit length
        len += p[size_t(a)] * p[size_t(a)];
      }
      // Through a point near the center, keeping it most of the time.
      p[3] = 0;
      for (int a = 0; a < 3; ++a)
        p[3] -= p[size_t(a)] * (n / 2.0 + 4 * gauss(rng));
    }
    caster.setClipPlanes(planes);
    for (int i = 0; i < 60; ++i)
    {
      svdag::Ray ray;
      for (int a = 0; a < 3; ++a)
      {
        ray.origin[size_t(a)] = n / 2.0 + 30 * gauss(rng);
        ray.direction[size_t(a)] = n / 2.0 + 6 * gauss(rng) - ray.origin[size_t(a)];
      }
      const svdag::RayHit hit = caster.cast(ray, svdag::Lod::Voxel);
      const Reference ref = bruteForce(labels, n, ray, planes);
      ASSERT_EQ(hit.hit, ref.hit) << "trial " << trial << " ray " << i;
      if (!ref.hit)
        continue;
      ++hits;
      EXPECT_NEAR(hit.t, ref.t, 1e-5 * (1 + ref.t));
      const uint32_t value = volume.labels[hit.label].value;
      EXPECT_NE(std::find(ref.labels.begin(), ref.labels.end(), value), ref.labels.end());
      if (ref.onCut)
      {
        ++cuts;
        EXPECT_EQ(hit.clipPlane, ref.plane);
        EXPECT_EQ(hit.normal, (std::array<int32_t, 3>{ { 0, 0, 0 } }));
      }
      else
        EXPECT_EQ(hit.clipPlane, -1);
    }
  }
  EXPECT_GT(hits, 300);
  EXPECT_GT(cuts, 50);
}

TEST(Clipping, RejectsBadPlanes)
{
  svdag::Geometry g;
  g.dims = { { 4, 4, 4 } };
  std::vector<uint8_t> labels(64, 1);
  const svdag::Volume volume =
    svdag::Builder::build(g, svdag::ScalarType::UInt8, labels.data(), svdag::BuildOptions());
  svdag::RayCaster caster(volume);
  EXPECT_THROW(caster.setClipPlanes(std::vector<Plane>(13, Plane{ { 0, 0, 1, 0 } })),
    std::invalid_argument);
  EXPECT_THROW(caster.setClipPlanes({ Plane{ { std::nan(""), 0, 1, 0 } } }), std::invalid_argument);
  // A plane keeping nothing of the volume: every ray misses.
  caster.setClipPlanes({ Plane{ { 1, 0, 0, -10 } } });
  svdag::Ray ray;
  ray.origin = { { -5, 2, 2 } };
  ray.direction = { { 1, 0, 0 } };
  EXPECT_FALSE(caster.cast(ray, svdag::Lod::Voxel).hit);
  // No planes: the solid volume is entered at x = 0.
  caster.setClipPlanes({});
  EXPECT_NEAR(caster.cast(ray, svdag::Lod::Voxel).t, 5.0, 1e-9);
  // Keep x >= 2.5: the cut face inside the solid, at t = 7.5.
  caster.setClipPlanes({ Plane{ { 2, 0, 0, -5 } } });
  const svdag::RayHit cut = caster.cast(ray, svdag::Lod::Voxel);
  EXPECT_TRUE(cut.hit);
  EXPECT_NEAR(cut.t, 7.5, 1e-9);
  EXPECT_EQ(cut.clipPlane, 0);
}
} // namespace
