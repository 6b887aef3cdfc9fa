// The renderer at the driver's real BLAS limit: a generated volume (BigVolume.h) with more
// visible blocks than one BLAS holds (maxPrimitiveCount, 16,777,215 on lavapipe, not lowered), so
// the Scene cuts its primitives into two BLAS, rendered and compared pixel by pixel with the CPU
// ray caster (labels exactly, depths within a relative 1e-4 as in TestRender).
//
// Which blocks land in which BLAS follows from the documented order alone (Scene.h: a recursive
// longest-axis median split of the box centers, cut into runs of maxPrimitiveCount): region A,
// exactly maxPrimitiveCount blocks, fills a 256-cell-wide box; region B, a few thousand blocks,
// lies past it along x, further away than A is wide. Every range of the split that holds blocks of
// both regions is then longest along x and puts B's blocks after A's, so B is the last run: the
// second BLAS (up to the order inside one unsplit pair of primitives at the boundary, which can
// swap one block of each). Blocks have one of five shapes and one of seven labels, hashed from the
// cell, so that a wrong primitive -> block mapping shows as a wrong label or depth.
//
// Three 64 x 64 views: B close up (second BLAS), A's end face close up (first BLAS), and through
// B onto A (rays that pass both BLAS: the nearest hit must win across instances).
#include "BigVolume.h"
#include "svdag/Compact.h"

#include <svdag/Decoder.h>
#include <svdag/RayCaster.h>
#include <svdag_render/Camera.h>
#include <svdag_render/Context.h>
#include <svdag_render/Renderer.h>

#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <memory>
#include <set>
#include <string>

namespace
{
using Vec = std::array<double, 3>;
using bigvolume::availableMemory;
using bigvolume::Clock;
using bigvolume::secondsSince;

// Cells: region A is x < ASide, every y and z below ASide (the first cells in cell order left
// empty beyond the A count); region B is x in [BFirst, BFirst + BSide), y and z in
// [BLow, BLow + BSide).
constexpr int32_t ASide = 256;
constexpr int32_t BSide = 16;
constexpr int32_t BLow = 120;
constexpr uint32_t LabelCount = 7;

struct Layout
{
  uint64_t aBlocks = 0;
  int32_t aLayers = 0; // z extent of A, in cells
  int32_t bFirst = 0;
  std::array<int32_t, 3> cells{ {} };
};

Layout layoutFor(uint64_t aBlocks)
{
  Layout l;
  l.aBlocks = aBlocks;
  l.aLayers = int32_t((aBlocks + uint64_t(ASide) * ASide - 1) / (uint64_t(ASide) * ASide));
  // B starts further along x than A's y and z extents (plus a margin for the boxes' offsets in
  // their cells), so ranges with blocks of both split along x.
  l.bFirst = ASide + std::max(ASide, l.aLayers) + 4;
  l.cells = { { l.bFirst + BSide, ASide, std::max(l.aLayers, BLow + BSide) } };
  return l;
}

bigvolume::CellBlock cellBlock(const Layout& l, int32_t x, int32_t y, int32_t z)
{
  const uint64_t i =
    uint64_t(x) + uint64_t(l.cells[0]) * (uint64_t(y) + uint64_t(l.cells[1]) * uint64_t(z));
  const bigvolume::CellBlock hashed = bigvolume::hashedBlock(i, LabelCount);
  if (x < ASide)
  {
    // A's cells in their own order (x, then y, then z), the first ones empty.
    const uint64_t inA =
      uint64_t(x) + uint64_t(ASide) * (uint64_t(y) + uint64_t(ASide) * uint64_t(z));
    const uint64_t aCells = uint64_t(ASide) * ASide * uint64_t(l.aLayers);
    return z < l.aLayers && inA >= aCells - l.aBlocks ? hashed : bigvolume::CellBlock();
  }
  const bool inB = x >= l.bFirst && y >= BLow && y < BLow + BSide && z >= BLow && z < BLow + BSide;
  return inB ? hashed : bigvolume::CellBlock();
}

struct ViewResult
{
  size_t pixels = 0, hits = 0, labelMismatches = 0;
  size_t hitsA = 0, hitsB = 0;
  std::set<uint64_t> blocksA, blocksB;
  double maxDepthError = 0; // relative: |depth - t| / (1 + t)
};

// Renders one view and compares every pixel with the CPU ray caster; index space is world + 0.5
// (the default geometry: unit spacing, zero origin, identity direction).
ViewResult compareView(svdag::render::Renderer& renderer, const svdag::Volume& volume,
  const Layout& layout, const Vec& eye, const Vec& target, double viewAngle)
{
  const uint32_t w = 64, h = 64;
  svdag::render::Camera camera;
  for (int a = 0; a < 3; ++a)
  {
    camera.position[a] = eye[a] - 0.5;
    camera.focalPoint[a] = target[a] - 0.5;
  }
  camera.viewUp = { { 0, 0, 1 } };
  camera.viewAngle = viewAngle;
  renderer.setCamera(camera);
  const svdag::render::Image& image = renderer.render();
  EXPECT_EQ(image.label.size(), size_t(w) * h);

  const auto b = svdag::render::rayBasis(camera, w, h);
  svdag::RayCaster caster(volume);
  ViewResult r;
  for (uint32_t y = 0; y < h; ++y)
  {
    for (uint32_t x = 0; x < w; ++x)
    {
      const double u = 2 * (x + 0.5) / w - 1, v = 2 * (y + 0.5) / h - 1;
      Vec d;
      for (int a = 0; a < 3; ++a)
        d[a] = b.forward[a] + u * b.right[a] + v * b.up[a];
      const double len = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
      svdag::Ray ray;
      for (int a = 0; a < 3; ++a)
      {
        ray.origin[a] = eye[a];
        ray.direction[a] = d[a] / len; // t is the world distance
      }
      const svdag::RayHit hit = caster.cast(ray, svdag::Lod::Voxel);
      const size_t i = x + size_t(w) * y;
      ++r.pixels;
      const uint32_t expected = hit.hit ? hit.label + 1 : 0;
      if (image.label[i] != expected)
      {
        ++r.labelMismatches;
        if (r.labelMismatches <= 5)
          ADD_FAILURE() << "pixel (" << x << ", " << y << "): label " << image.label[i]
                        << ", the CPU ray caster's " << expected << " (block " << hit.block << ")";
        continue;
      }
      if (!hit.hit)
        continue;
      ++r.hits;
      r.maxDepthError =
        std::max(r.maxDepthError, std::abs(double(image.depth[i]) - hit.t) / (1 + hit.t));
      const int32_t cellX = int32_t(volume.block(hit.block).cell % uint32_t(layout.cells[0]));
      if (cellX >= layout.bFirst)
      {
        ++r.hitsB;
        r.blocksB.insert(hit.block);
      }
      else
      {
        ++r.hitsA;
        r.blocksA.insert(hit.block);
      }
    }
  }
  return r;
}
} // namespace

TEST(RenderLimits, TwoBlasAtTheDriversPrimitiveLimitMatchTheCpuRayCaster)
{
  const auto start = Clock::now();
  auto t = start;
  auto phase = [&](const char* what) {
    std::printf("[ phase    ] %-30s %7.1f s\n", what, secondsSince(t));
    std::fflush(stdout);
    t = Clock::now();
  };
  uint64_t limit = 0;
  {
    svdag::render::Context context;
    limit = context.limits().maxPrimitiveCount;
    std::printf("[ info     ] %s: maxPrimitiveCount %llu\n", context.deviceName().c_str(),
      static_cast<unsigned long long>(limit));
  }
  if (limit > (uint64_t(1) << 25))
    GTEST_SKIP() << "the device's maxPrimitiveCount is " << limit
                 << ": more blocks than this test builds (it targets lavapipe's 16,777,215)";
  // The Scene's boxes, the AABBs and their upload, the BLAS (lavapipe: in host memory, about
  // 88 bytes per AABB) and the build's scratch: the test peaks at about 220 bytes per block.
  const uint64_t memoryNeeded = 300 * (limit + 4096) + (uint64_t(1) << 30);
  if (availableMemory() < memoryNeeded)
    GTEST_SKIP() << "needs " << svdag::formatBytes(memoryNeeded) << " of available memory, "
                 << "/proc/meminfo's MemAvailable says " << svdag::formatBytes(availableMemory());
  phase("device limits");

  const Layout layout = layoutFor(limit);
  // Made pooled, rendered compact (Compact.h).
  auto volume = std::make_shared<const svdag::Volume>(svdag::compacted(bigvolume::bigVolume(
    layout.cells, LabelCount, [&](int32_t x, int32_t y, int32_t z) { return cellBlock(layout, x, y, z); })));
  const uint64_t bBlocks = uint64_t(BSide) * BSide * BSide;
  ASSERT_EQ(volume->blockCount, limit + bBlocks);
  phase("generate");
  ASSERT_NO_THROW(volume->validate());
  phase("validate");

  svdag::render::Renderer renderer;
  renderer.setBackend(svdag::render::Backend::RayTracing); // the BLAS split is this backend's
  renderer.setImageSize(64, 64);
  renderer.setLod(svdag::render::Lod::Voxel);
  renderer.setSamplesPerPixel(1);
  renderer.setMaximumBounces(0);
  renderer.setVolume(volume);
  phase("setVolume (upload + BVH)");
  std::printf("[ info     ] %zu BLAS, %s of BLAS, %llu visible blocks\n", renderer.blasCount(),
    svdag::formatBytes(renderer.blasBytes()).c_str(),
    static_cast<unsigned long long>(renderer.visibleBlocks()));
  ASSERT_EQ(renderer.visibleBlocks(), limit + bBlocks);
  ASSERT_EQ(renderer.blasCount(), 2u);

  // Index-space points: B spans x [16 bFirst, 16 (bFirst + 16)), y and z [1920, 2176); A ends
  // at x = 4096. Eye offsets are not round, so that no pixel ray runs along a voxel face.
  const double bx = 16.0 * layout.bFirst, bCenter = 16.0 * (BLow + BSide / 2);
  const double aEnd = 16.0 * ASide;
  struct View
  {
    const char* name;
    Vec eye, target;
    double angle;
  };
  const View views[] = {
    { "B close up", { bx - 437.3, bCenter + 291.7, bCenter + 352.9 },
      { bx + 128, bCenter, bCenter }, 40 },
    { "A's end face", { aEnd + 611.3, bCenter - 203.9, bCenter + 307.1 },
      { aEnd - 100, bCenter, bCenter }, 35 },
    { "through B onto A", { bx + 256 + 563.7, bCenter + 61.3, bCenter + 97.9 },
      { aEnd, bCenter, bCenter }, 30 },
  };
  ViewResult total;
  for (const View& view : views)
  {
    SCOPED_TRACE(view.name);
    const ViewResult r = compareView(renderer, *volume, layout, view.eye, view.target, view.angle);
    std::printf("[ view     ] %-18s %4zu hits (%4zu on %3zu blocks of A, "
                "%4zu on %3zu blocks of B), "
                "%zu label mismatches, relative depth error <= %.2g\n",
      view.name, r.hits, r.hitsA, r.blocksA.size(), r.hitsB, r.blocksB.size(), r.labelMismatches,
      r.maxDepthError);
    EXPECT_EQ(r.labelMismatches, 0u);
    EXPECT_LE(r.maxDepthError, 1e-4); // as TestRender: float rays, grazing faces
    total.hitsA += r.hitsA;
    total.hitsB += r.hitsB;
    total.blocksA.insert(r.blocksA.begin(), r.blocksA.end());
    total.blocksB.insert(r.blocksB.begin(), r.blocksB.end());
  }
  phase("render and compare 3 views");
  // Both BLAS are seen on many blocks (a boundary swap moves at most one block of each region).
  EXPECT_GE(total.blocksA.size(), 100u);
  EXPECT_GE(total.blocksB.size(), 100u);
  EXPECT_GE(total.hitsA, 1000u);
  EXPECT_GE(total.hitsB, 1000u);

  // The compute backend on the same 16.78 M blocks (its cell grid: one uint32 per cell), the same
  // views against the CPU ray caster; it frees the BVH.
  renderer.setBackend(svdag::render::Backend::Compute);
  EXPECT_EQ(renderer.blasCount(), 0u);
  for (const View& view : views)
  {
    SCOPED_TRACE(std::string("compute: ") + view.name);
    const ViewResult r = compareView(renderer, *volume, layout, view.eye, view.target, view.angle);
    EXPECT_EQ(r.labelMismatches, 0u);
    EXPECT_LE(r.maxDepthError, 1e-4);
    EXPECT_GE(r.hits, 100u);
  }
  phase("compute backend, 3 views");
  std::printf("[ total    ] %.1f s\n", secondsSince(start));
}
