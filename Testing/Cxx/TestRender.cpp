// The VTK-free renderer core: camera framing and ray basis, the index-to-world matrix, device
// selection errors, and rendered frames against the CPU ray caster (svdag::RayCaster, the same
// traversal code) on small built volumes, through both backends (the ray tracing pipeline and
// the compute cell-grid walk). Needs a Vulkan device with ray tracing (lavapipe).
#include <svdag/Builder.h>
#include <svdag/RayCaster.h>
#include <svdag_render/Camera.h>
#include <svdag_render/FrameBudget.h>
#include <svdag_render/Renderer.h>
#include <svdag_render/Scene.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <iostream>
#include <cstdlib>
#include <random>
#include <stdexcept>
#include <string>

namespace
{
using Vec = std::array<double, 3>;

double dot(const Vec& a, const Vec& b)
{
  return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

svdag::Geometry tiltedGeometry()
{
  svdag::Geometry g;
  g.dims = { { 37, 21, 19 } };
  g.spacing = { { 0.5, 1.25, 2.0 } };
  g.origin = { { -10, 4, 7 } };
  const double c = std::cos(0.3), s = std::sin(0.3);
  g.direction = { { c, -s, 0, s, c, 0, 0, 0, 1 } }; // a rotation about z
  return g;
}

std::shared_ptr<const svdag::Volume> randomVolume(const svdag::Geometry& g, uint32_t seed)
{
  std::mt19937 rng(seed);
  std::vector<uint16_t> labels(g.voxelCount());
  for (auto& l : labels)
    l = (rng() % 5 == 0) ? uint16_t(1 + rng() % 6) : 0;
  return std::make_shared<const svdag::Volume>(
    svdag::Builder::build(g, svdag::ScalarType::UInt16, labels.data()));
}

// Restores an environment variable when the test ends.
struct ScopedEnv
{
  std::string name;
  ScopedEnv(const char* n, const char* value)
    : name(n)
  {
    setenv(n, value, 1);
  }
  ~ScopedEnv() { unsetenv(name.c_str()); }
};
} // namespace

TEST(RenderCamera, RayBasisIsOrthogonalAndScaled)
{
  svdag::render::Camera c;
  c.position = { { 1, 2, 3 } };
  c.focalPoint = { { 4, -2, 3 } };
  c.viewUp = { { 0, 0.2, 1 } };
  c.viewAngle = 40;
  const auto b = svdag::render::rayBasis(c, 80, 40);
  const double h = std::tan(20 * M_PI / 180);
  EXPECT_NEAR(std::sqrt(dot(b.forward, b.forward)), 1, 1e-12);
  EXPECT_NEAR(std::sqrt(dot(b.up, b.up)), h, 1e-12);
  EXPECT_NEAR(std::sqrt(dot(b.right, b.right)), 2 * h, 1e-12); // aspect 2
  EXPECT_NEAR(dot(b.forward, b.up), 0, 1e-12);
  EXPECT_NEAR(dot(b.forward, b.right), 0, 1e-12);
  EXPECT_NEAR(dot(b.up, b.right), 0, 1e-12);
  EXPECT_GT(b.up[2], 0); // up follows the view up
}

TEST(RenderCamera, DegenerateCamerasThrow)
{
  svdag::render::Camera c;
  c.focalPoint = c.position;
  EXPECT_THROW(svdag::render::rayBasis(c, 4, 4), std::invalid_argument);
  c = svdag::render::Camera();
  c.viewUp = { { 0, 0, 2 } }; // parallel to the view direction
  EXPECT_THROW(svdag::render::rayBasis(c, 4, 4), std::invalid_argument);
  c = svdag::render::Camera();
  c.viewAngle = 180;
  EXPECT_THROW(svdag::render::rayBasis(c, 4, 4), std::invalid_argument);
  c = svdag::render::Camera();
  c.position[0] = NAN;
  EXPECT_THROW(svdag::render::rayBasis(c, 4, 4), std::invalid_argument);
  EXPECT_THROW(svdag::render::rayBasis(svdag::render::Camera(), 0, 4), std::invalid_argument);
}

TEST(RenderCamera, IndexToWorldPutsVoxelCentersOnVTKPoints)
{
  const svdag::Geometry g = tiltedGeometry();
  const auto m = svdag::render::indexToWorld(g);
  // Index-space p = i + 0.5 is the center of voxel i, the VTK point origin + D diag(s) i.
  const double i[3] = { 3, 7, 11 };
  for (int r = 0; r < 3; ++r)
  {
    double world = m[4 * r + 3], vtk = g.origin[r];
    for (int c = 0; c < 3; ++c)
    {
      world += m[4 * r + c] * (i[c] + 0.5);
      vtk += g.direction[3 * r + c] * g.spacing[c] * i[c];
    }
    EXPECT_NEAR(world, vtk, 1e-12);
  }
}

TEST(RenderCamera, FrameVolumeSeesEveryCorner)
{
  const svdag::Geometry g = tiltedGeometry();
  const auto bounds = svdag::render::worldBounds(g);
  for (double azimuth : { 0.0, 35.0, -120.0 })
  {
    for (double elevation : { 0.0, 50.0, -89.0 })
    {
      const auto camera = svdag::render::frameVolume(g, azimuth, elevation, 1.0, 30.0);
      const auto b = svdag::render::rayBasis(camera, 64, 48);
      for (int corner = 0; corner < 8; ++corner)
      {
        const Vec p = { bounds[(corner & 1) ? 1 : 0], bounds[(corner & 2) ? 3 : 2],
          bounds[(corner & 4) ? 5 : 4] };
        const Vec d = { p[0] - camera.position[0], p[1] - camera.position[1],
          p[2] - camera.position[2] };
        const double depth = dot(d, b.forward);
        ASSERT_GT(depth, 0);
        // Image-plane coordinates u, v in [-1, 1] for points in view.
        EXPECT_LE(std::abs(dot(d, b.right) / dot(b.right, b.right) / depth), 1.0);
        EXPECT_LE(std::abs(dot(d, b.up) / dot(b.up, b.up) / depth), 1.0);
      }
    }
  }
  EXPECT_THROW(svdag::render::frameVolume(g, 0, 0, 0), std::invalid_argument);
}

TEST(RenderDevice, ForcedMissingDeviceNamesTheDevices)
{
  ScopedEnv env("SVDAG_VK_DEVICE", "no-such-device-xyz");
  try
  {
    svdag::render::Renderer renderer;
    FAIL() << "a renderer was created on a device that does not exist";
  }
  catch (const std::runtime_error& e)
  {
    const std::string message = e.what();
    EXPECT_NE(message.find("SVDAG_VK_DEVICE='no-such-device-xyz'"), std::string::npos) << message;
    EXPECT_NE(message.find("devices found"), std::string::npos) << message;
  }
}

// Both backends, each test once per backend.
class RenderBackend : public ::testing::TestWithParam<svdag::render::Backend>
{
};
INSTANTIATE_TEST_SUITE_P(Backends, RenderBackend,
  ::testing::Values(svdag::render::Backend::RayTracing, svdag::render::Backend::Compute),
  [](const ::testing::TestParamInfo<svdag::render::Backend>& info) {
    return std::string(info.param == svdag::render::Backend::RayTracing ? "RayTracing" : "Compute");
  });

TEST_P(RenderBackend, VoxelHitsMatchTheCpuRayCaster)
{
  const svdag::Geometry g = tiltedGeometry();
  const auto volume = randomVolume(g, 99);
  svdag::render::Renderer renderer;
  renderer.setBackend(GetParam());
  renderer.setVolume(volume);
  EXPECT_EQ(renderer.backend(), GetParam());
  renderer.setImageSize(32, 24);
  renderer.setLod(svdag::render::Lod::Voxel);
  renderer.setCamera(svdag::render::frameVolume(g, 25, -15, 1.5));
  const svdag::render::Image& image = renderer.render();
  ASSERT_EQ(image.label.size(), 32u * 24u);

  // The same rays (GpuLayout.h's pixel-center convention) in index space for the CPU caster.
  const auto b = svdag::render::rayBasis(renderer.camera(), 32, 24);
  const auto m = svdag::render::indexToWorld(g);
  // Inverse of the 3x3 part: a rotation times diag(spacing) -> diag(1/s) * R^T.
  auto toIndex = [&](const Vec& w, bool point) {
    Vec v = w;
    if (point)
      for (int r = 0; r < 3; ++r)
        v[r] -= m[4 * r + 3];
    Vec p;
    for (int c = 0; c < 3; ++c)
      p[c] = (g.direction[c] * v[0] + g.direction[3 + c] * v[1] + g.direction[6 + c] * v[2]) /
        g.spacing[c];
    return p;
  };
  svdag::RayCaster caster(*volume);
  size_t agree = 0, hits = 0;
  for (uint32_t y = 0; y < 24; ++y)
  {
    for (uint32_t x = 0; x < 32; ++x)
    {
      const double u = 2 * (x + 0.5) / 32 - 1, v = 2 * (y + 0.5) / 24 - 1;
      Vec d;
      for (int a = 0; a < 3; ++a)
        d[a] = b.forward[a] + u * b.right[a] + v * b.up[a];
      const double len = std::sqrt(dot(d, d));
      for (auto& c : d)
        c /= len;
      svdag::Ray ray;
      ray.origin = toIndex(renderer.camera().position, true);
      ray.direction = toIndex(d, false); // t stays the world distance
      const svdag::RayHit hit = caster.cast(ray, svdag::Lod::Voxel);
      const size_t i = x + 32 * y;
      const uint32_t expected = hit.hit ? hit.label + 1 : 0;
      if (image.label[i] == expected)
      {
        ++agree;
        if (hit.hit)
        {
          ++hits;
          EXPECT_NEAR(image.depth[i], hit.t, 1e-4 * (1 + hit.t));
        }
      }
    }
  }
  EXPECT_GE(agree, size_t(0.999 * 32 * 24));
  EXPECT_GT(hits, 32u * 24u / 5); // the view sees the volume
}

// Ray limits (an opaque surface in front, as the VTK mapper passes the depth buffer) end camera
// rays: a pixel limited before its hit shows background, one limited after it is unchanged; the
// error estimate is positive once two samples are accumulated, with limits as without.
TEST(RenderFrame, RayLimitsEndCameraRays)
{
  const svdag::Geometry g = tiltedGeometry();
  const auto volume = randomVolume(g, 7);
  svdag::render::Renderer renderer;
  renderer.setVolume(volume);
  renderer.setImageSize(32, 24);
  renderer.setCamera(svdag::render::frameVolume(g, 25, -15, 1.5));
  const svdag::render::Image reference = renderer.render();
  renderer.render();
  EXPECT_EQ(renderer.errorEstimate() > 0, true);
  std::vector<float> limits(32 * 24);
  size_t hits = 0;
  for (size_t i = 0; i < limits.size(); ++i)
  {
    const bool before = i % 2 == 0;
    hits += reference.label[i] != 0;
    limits[i] = reference.label[i] == 0 ? 1e30f
                                        : (before ? 0.5f * reference.depth[i] : 2.0f * reference.depth[i]);
  }
  ASSERT_GT(hits, 50u);
  renderer.setRayLimits(limits);
  renderer.resetAccumulation();
  const svdag::render::Image& limited = renderer.render();
  for (size_t i = 0; i < limits.size(); ++i)
  {
    if (reference.label[i] != 0 && i % 2 == 0)
      EXPECT_EQ(limited.label[i], 0u) << i;
    else
      EXPECT_EQ(limited.label[i], reference.label[i]) << i;
  }
  renderer.render();
  EXPECT_GT(renderer.errorEstimate(), 0.0);
  std::vector<float> wrongSize(5, 1.0f);
  renderer.setRayLimits(wrongSize);
  EXPECT_THROW(renderer.render(), std::invalid_argument);
}

namespace
{
// A row-major OpenGL-style world-to-clip matrix of a pinhole camera (VTK's perspective
// projection) with near and far planes at distances n and f, for a width x height image.
std::array<double, 16> worldToClip(const svdag::render::Camera& c, uint32_t width, uint32_t height,
  double n, double f)
{
  const auto b = svdag::render::rayBasis(c, width, height);
  const double h = std::tan(c.viewAngle * 3.14159265358979323846 / 360);
  const double aspect = double(width) / height;
  Vec right = b.right, up = b.up;
  for (int a = 0; a < 3; ++a)
  {
    right[a] /= h * aspect;
    up[a] /= h;
  }
  const Vec back = { -b.forward[0], -b.forward[1], -b.forward[2] };
  // View: rows right, up, back; translation -R.p etc.
  std::array<double, 16> view{};
  const Vec* rows[3] = { &right, &up, &back };
  for (int r = 0; r < 3; ++r)
  {
    for (int k = 0; k < 3; ++k)
      view[4 * r + k] = (*rows[r])[k];
    view[4 * r + 3] = -dot(*rows[r], c.position);
  }
  view[15] = 1;
  std::array<double, 16> proj{};
  proj[0] = 1 / (h * aspect);
  proj[5] = 1 / h;
  proj[10] = -(f + n) / (f - n);
  proj[11] = -2 * f * n / (f - n);
  proj[14] = -1;
  std::array<double, 16> m{};
  for (int r = 0; r < 4; ++r)
    for (int k = 0; k < 4; ++k)
      for (int j = 0; j < 4; ++j)
        m[4 * r + k] += proj[4 * r + j] * view[4 * j + k];
  return m;
}

std::array<double, 16> inverse4(const std::array<double, 16>& m)
{
  // Gauss-Jordan with partial pivoting.
  std::array<double, 32> a{};
  for (int r = 0; r < 4; ++r)
  {
    for (int k = 0; k < 4; ++k)
      a[8 * r + k] = m[4 * r + k];
    a[8 * r + 4 + r] = 1;
  }
  for (int col = 0; col < 4; ++col)
  {
    int pivot = col;
    for (int r = col + 1; r < 4; ++r)
      if (std::abs(a[8 * r + col]) > std::abs(a[8 * pivot + col]))
        pivot = r;
    for (int k = 0; k < 8; ++k)
      std::swap(a[8 * col + k], a[8 * pivot + k]);
    const double p = a[8 * col + col];
    for (int k = 0; k < 8; ++k)
      a[8 * col + k] /= p;
    for (int r = 0; r < 4; ++r)
    {
      if (r == col)
        continue;
      const double factor = a[8 * r + col];
      for (int k = 0; k < 8; ++k)
        a[8 * r + k] -= factor * a[8 * col + k];
    }
  }
  std::array<double, 16> out{};
  for (int r = 0; r < 4; ++r)
    for (int k = 0; k < 4; ++k)
      out[4 * r + k] = a[8 * r + 4 + k];
  return out;
}
} // namespace

// Rays from a projection matrix (the VTK mapper's path) equal the pinhole camera's: the same
// directions, origins on the near plane, and so the same labels, depths shifted by the near
// distance along each ray, and a path-traced image of the same mean.
TEST(RenderFrame, ProjectionRaysMatchThePinholeCamera)
{
  const svdag::Geometry g = tiltedGeometry();
  const auto volume = randomVolume(g, 11);
  const auto camera = svdag::render::frameVolume(g, 25, -15, 1.5);
  const uint32_t w = 40, h = 30;
  svdag::render::Renderer pinhole;
  pinhole.setVolume(volume);
  pinhole.setImageSize(w, h);
  pinhole.setCamera(camera);
  for (int i = 0; i < 7; ++i)
    pinhole.render();
  const svdag::render::Image a = pinhole.image();

  // Near and far planes hugging the volume, as vtkRenderer::ResetCameraClippingRange sets them.
  const auto bounds = svdag::render::worldBounds(g);
  const Vec center = { (bounds[0] + bounds[1]) / 2, (bounds[2] + bounds[3]) / 2,
    (bounds[4] + bounds[5]) / 2 };
  const Vec toCenter = { center[0] - camera.position[0], center[1] - camera.position[1],
    center[2] - camera.position[2] };
  const double radius = std::sqrt(std::pow(bounds[1] - bounds[0], 2) +
    std::pow(bounds[3] - bounds[2], 2) + std::pow(bounds[5] - bounds[4], 2)) / 2;
  const double n = std::sqrt(dot(toCenter, toCenter)) - 1.01 * radius;
  const double f = std::sqrt(dot(toCenter, toCenter)) + 1.01 * radius;
  ASSERT_GT(n, 0);
  const auto rays = svdag::render::viewRaysFromClipToWorld(inverse4(worldToClip(camera, w, h, n, f)));
  EXPECT_TRUE(rays.bounded);
  svdag::render::Renderer projected;
  projected.setVolume(volume);
  projected.setImageSize(w, h);
  projected.setViewRays(rays);
  for (int i = 0; i < 7; ++i)
    projected.render();
  const svdag::render::Image& b = projected.image();
  size_t same = 0, hits = 0;
  double meanA = 0, meanB = 0;
  size_t blackA = 0, blackB = 0;
  for (size_t i = 0; i < size_t(w) * h; ++i)
  {
    same += a.label[i] == b.label[i];
    if (a.label[i] != 0 && a.label[i] == b.label[i])
    {
      ++hits;
      // The near plane is at distance n along the view axis: along the ray, n / cos.
      EXPECT_LT(b.depth[i], a.depth[i]);
      EXPECT_GT(b.depth[i], a.depth[i] - 2 * n);
    }
    for (int c = 0; c < 3; ++c)
    {
      meanA += a.hdr[4 * i + c];
      meanB += b.hdr[4 * i + c];
    }
    blackA += a.label[i] != 0 && a.hdr[4 * i] + a.hdr[4 * i + 1] + a.hdr[4 * i + 2] == 0;
    blackB += b.label[i] != 0 && b.hdr[4 * i] + b.hdr[4 * i + 1] + b.hdr[4 * i + 2] == 0;
  }
  EXPECT_GE(same, size_t(0.995 * w * h));
  EXPECT_GT(hits, size_t(w) * h / 5);
  EXPECT_NEAR(meanB, meanA, 0.02 * meanA);
  EXPECT_EQ(blackB, blackA) << "pixels that hit but received no light";
}

// The time budget's choice of LOD and reduction (FrameBudget.h), from recorded costs.
TEST(FrameBudget, ChoosesTheFirstLevelThatFits)
{
  using svdag::render::FrameBudget;
  using svdag::render::Lod;
  FrameBudget budget;
  const uint64_t pixels = 512 * 512;
  // Nothing known, or no budget: full quality.
  EXPECT_EQ(budget.choose(Lod::Voxel, pixels, 0.1).reduction, 1u);
  EXPECT_EQ(budget.choose(Lod::Voxel, pixels, 0.0).lod, Lod::Voxel);
  // Voxel LOD: 1 us per pixel, 10 ms overhead -> 272 ms at full size.
  budget.record(Lod::Voxel, pixels, 1e-6 * pixels, 0.010);
  EXPECT_NEAR(budget.predict({ Lod::Voxel, 1 }, pixels), 0.010 + 1e-6 * pixels, 1e-9);
  EXPECT_EQ(budget.choose(Lod::Voxel, pixels, 1.0).reduction, 1u);
  // 100 ms: leaf (0.8x, 220 ms) and block (0.6x, 167 ms) at full size do not fit; voxel at
  // reduction 2 does (10 + 65.5 ms).
  const auto level = budget.choose(Lod::Voxel, pixels, 0.1);
  EXPECT_EQ(level.lod, Lod::Voxel);
  EXPECT_EQ(level.reduction, 2u);
  EXPECT_LE(budget.predict(level, pixels), 0.1);
  // Nothing fits: the coarsest level.
  const auto coarsest = budget.choose(Lod::Voxel, pixels, 1e-6);
  EXPECT_EQ(coarsest.lod, Lod::Block);
  EXPECT_EQ(coarsest.reduction, FrameBudget::MaximumReduction);
  // Never finer than asked.
  EXPECT_EQ(budget.choose(Lod::Leaf, pixels, 10.0).lod, Lod::Leaf);
}

TEST(FrameBudget, ProvisionalFramesCountOnlyUntilMeasured)
{
  using svdag::render::FrameBudget;
  using svdag::render::Lod;
  FrameBudget budget;
  // A warm-up frame (shader compilation) 10x too slow is used while nothing else is known ...
  budget.record(Lod::Voxel, 1000, 0.010, 0.0, true);
  EXPECT_NEAR(budget.predict({ Lod::Voxel, 1 }, 1000), 0.010, 1e-12);
  // ... then replaced, not averaged, by the first real measurement; later ones are averaged.
  budget.record(Lod::Voxel, 1000, 0.001, 0.0);
  EXPECT_NEAR(budget.predict({ Lod::Voxel, 1 }, 1000), 0.001, 1e-12);
  budget.record(Lod::Voxel, 1000, 0.010, 0.0, true);
  EXPECT_NEAR(budget.predict({ Lod::Voxel, 1 }, 1000), 0.001, 1e-12);
  budget.record(Lod::Voxel, 1000, 0.003, 0.0);
  EXPECT_NEAR(budget.predict({ Lod::Voxel, 1 }, 1000), 0.002, 1e-12);
}

// The block stream in chunks of 16 words (records straddle chunk ends, up to the 4 words of
// overlap) renders exactly as in one chunk: every output, bit for bit.
TEST_P(RenderBackend, ChunkedBlockStreamRendersTheSameImage)
{
  svdag::Geometry g = tiltedGeometry();
  g.dims = { { 96, 80, 64 } };
  const auto volume = randomVolume(g, 5);
  auto renderOnce = [&](uint32_t shift, size_t& chunks) {
    svdag::render::Renderer renderer;
    renderer.setBackend(GetParam());
    renderer.setBlockChunkShift(shift);
    renderer.setVolume(volume);
    chunks = renderer.blockChunkCount();
    renderer.setImageSize(48, 40);
    renderer.setLod(svdag::render::Lod::Voxel);
    renderer.setCamera(svdag::render::frameVolume(g, 35, -20, 1.2));
    return renderer.render();
  };
  size_t one = 0, many = 0;
  const svdag::render::Image whole = renderOnce(svdag::render::Scene::MaxBlockChunkShift, one);
  const svdag::render::Image chunked = renderOnce(4, many);
  EXPECT_EQ(one, 1u);
  EXPECT_GE(many, (volume->blocks.size() - 1) / 16);
  EXPECT_GT(many, 30u);
  EXPECT_EQ(whole.label, chunked.label);
  EXPECT_EQ(whole.depth, chunked.depth);
  EXPECT_EQ(whole.normal, chunked.normal);
  EXPECT_EQ(whole.color, chunked.color);
  size_t hits = 0;
  for (uint32_t l : whole.label)
    hits += l != 0;
  EXPECT_GT(hits, whole.label.size() / 3);
}

// What does not fit the device memory the renderer may use fails before it is allocated, with
// the bytes needed and available; the renderer stays usable with more room.
TEST(RenderDevice, AVolumeThatDoesNotFitNamesTheBytes)
{
  svdag::Geometry g = tiltedGeometry();
  g.dims = { { 96, 80, 64 } };
  const auto volume = randomVolume(g, 5);
  const svdag::MemoryUsage usage = volume->memory();
  svdag::render::Renderer renderer;
  svdag::render::RenderSettings settings = renderer.settings();
  settings.deviceMemoryLimit = usage.blocks + usage.dag() / 2; // less than the streams
  renderer.setSettings(settings);
  try
  {
    renderer.setVolume(volume);
    FAIL() << "the volume fit in fewer bytes than its streams";
  }
  catch (const svdag::render::DeviceMemoryError& e)
  {
    const std::string message = e.what();
    EXPECT_NE(message.find("The volume's streams (blocks and DAG) needs "), std::string::npos)
      << message;
    // The bytes needed are at least the streams' bytes, the ones available at most the limit.
    const auto needs = std::stoull(message.substr(message.find("needs ") + 6));
    const auto available = std::stoull(message.substr(message.find("but ") + 4));
    EXPECT_GE(needs, usage.blocks + usage.dag());
    EXPECT_LE(available, settings.deviceMemoryLimit);
    EXPECT_NE(message.find("a limit of " + std::to_string(settings.deviceMemoryLimit) + " bytes"),
      std::string::npos) << message;
  }
  settings.deviceMemoryLimit = 0;
  renderer.setSettings(settings);
  renderer.setVolume(volume);
  const uint64_t held = renderer.deviceBytes(); // streams, BVH, materials
  EXPECT_GT(held, usage.blocks + usage.dag());
  // One byte less than the volume holds once set up: its last buffer is refused.
  settings.deviceMemoryLimit = held - 1;
  renderer.setSettings(settings);
  EXPECT_THROW(renderer.setVolume(volume), svdag::render::DeviceMemoryError);
  EXPECT_LE(renderer.deviceBytes(), held - 1);
  settings.deviceMemoryLimit = 0;
  renderer.setSettings(settings);
  renderer.setVolume(volume);
  EXPECT_EQ(renderer.deviceBytes(), held);
  renderer.setImageSize(16, 16);
  renderer.setCamera(svdag::render::frameVolume(g, 35, -20, 1.2));
  EXPECT_EQ(renderer.render().label.size(), 256u);
}

namespace
{
size_t hitCount(const svdag::render::Image& image)
{
  size_t hits = 0;
  for (uint32_t l : image.label)
    hits += l != 0;
  return hits;
}
} // namespace

// The two backends trace the same scene: at every LOD, with smooth shading, a clipping plane and
// hidden labels. Voxel LOD: labels agree on 99.9% of the pixels (float rounding may pick another
// of two voxels touching at a ray's entry), depth and normals where they do, and so does the
// path-traced color (the same integrator with the same random numbers). Block, leaf and auto LOD:
// boxes of different labels overlap inside a cell and a ray entering several at the same
// distance may show any of them (RayCaster.h), so there hit or miss and depth agree.
TEST(RenderBackends, TraceTheSameImage)
{
  svdag::Geometry g = tiltedGeometry();
  g.dims = { { 70, 45, 40 } };
  const auto volume = randomVolume(g, 21);
  auto frame = [&](svdag::render::Backend backend, svdag::render::Lod lod,
                 svdag::render::Shading shading, bool clipped, bool hidden) {
    svdag::render::Renderer renderer;
    svdag::render::RenderSettings settings;
    settings.backend = backend;
    settings.lod = lod;
    settings.shading = shading;
    settings.maximumBounces = 2;
    settings.samplesPerPixel = 2;
    settings.sun.on = true;
    if (clipped)
    {
      svdag::render::ClipPlane plane;
      const auto bounds = svdag::render::worldBounds(g);
      plane.origin = { { 0.5 * (bounds[0] + bounds[1]), 0.5 * (bounds[2] + bounds[3]),
        0.5 * (bounds[4] + bounds[5]) } };
      plane.normal = { { 0.3, -1.0, 0.2 } };
      settings.clipPlanes.push_back(plane);
    }
    renderer.setSettings(settings);
    renderer.setVolume(volume);
    if (hidden)
      renderer.setHiddenLabels({ 1, 3 });
    renderer.setImageSize(40, 30);
    renderer.setCamera(svdag::render::frameVolume(g, 35, -20, 1.3));
    renderer.render();
    EXPECT_EQ(renderer.backend(), backend);
    return renderer.render();
  };
  using svdag::render::Lod;
  using svdag::render::Shading;
  struct Case
  {
    Lod lod;
    Shading shading;
    bool clipped, hidden;
  };
  for (const Case c : { Case{ Lod::Voxel, Shading::Voxel, false, false },
         Case{ Lod::Voxel, Shading::Smooth, true, false }, Case{ Lod::Leaf, Shading::Voxel, false, true },
         Case{ Lod::Block, Shading::Voxel, true, true }, Case{ Lod::Auto, Shading::Voxel, false, false } })
  {
    const auto rt = frame(svdag::render::Backend::RayTracing, c.lod, c.shading, c.clipped, c.hidden);
    const auto compute = frame(svdag::render::Backend::Compute, c.lod, c.shading, c.clipped, c.hidden);
    const std::string what = std::string("LOD ") + svdag::render::lodName(c.lod) + ", " +
      svdag::render::shadingName(c.shading) + (c.clipped ? ", clipped" : "") +
      (c.hidden ? ", labels 1 and 3 hidden" : "");
    const bool exact = c.lod == Lod::Voxel;
    size_t same = 0, colorSame = 0;
    for (size_t i = 0; i < rt.label.size(); ++i)
    {
      if (c.hidden && compute.label[i] != 0)
        EXPECT_TRUE(compute.label[i] != 2 && compute.label[i] != 4) << what;
      if (exact ? rt.label[i] != compute.label[i] : (rt.label[i] != 0) != (compute.label[i] != 0))
        continue;
      ++same;
      if (rt.label[i] == 0)
        continue;
      EXPECT_NEAR(rt.depth[i], compute.depth[i], 1e-4 * (1 + rt.depth[i])) << what << ", pixel " << i;
      if (!exact)
        continue;
      for (int a = 0; a < 3; ++a)
        EXPECT_NEAR(rt.normal[3 * i + a], compute.normal[3 * i + a], 2e-3) << what << ", pixel " << i;
      bool close = true;
      for (int a = 0; a < 4; ++a)
        close = close && std::abs(rt.hdr[4 * i + a] - compute.hdr[4 * i + a]) <= 1e-3f * (1 + rt.hdr[4 * i + a]);
      colorSame += close;
    }
    EXPECT_GE(same, size_t(0.999 * rt.label.size())) << what;
    // Bounce and shadow rays may graze an edge one backend counts and the other not: a few
    // paths differ.
    if (exact)
      EXPECT_GE(colorSame, size_t(0.97 * hitCount(rt))) << what;
    EXPECT_GT(hitCount(rt), rt.label.size() / 4) << what;
  }
}

// The compute backend holds no BVH: hiding labels writes bits (no rebuild, yet the accumulation
// restarts and the labels vanish), its acceleration bytes are the cell grid (4 bytes a cell + 1)
// and the hidden bits; switching backends rebuilds and restarts.
TEST(RenderBackends, ComputeHoldsNoBvh)
{
  const svdag::Geometry g = tiltedGeometry();
  const auto volume = randomVolume(g, 3);
  svdag::render::Renderer renderer;
  renderer.setBackend(svdag::render::Backend::Compute);
  renderer.setVolume(volume);
  renderer.setImageSize(32, 24);
  renderer.setCamera(svdag::render::frameVolume(g, 25, -15, 1.5));
  const svdag::render::Image before = renderer.render();
  EXPECT_EQ(renderer.blasBytes(), 0u);
  EXPECT_EQ(renderer.tlasBytes(), 0u);
  EXPECT_EQ(renderer.bvhBuilds(), 0u);
  const auto cells = g.cellCounts();
  const uint64_t gridBytes = (uint64_t(cells[0]) * cells[1] * cells[2] + 1) * 4 +
    4 * ((volume->labels.size() + 31) / 32);
  const svdag::render::DeviceBytes bytes = renderer.deviceBytesByPart();
  EXPECT_EQ(bytes.acceleration, gridBytes);
  EXPECT_EQ(bytes.encoding, uint64_t(volume->blocks.size() * 4 + 8) +
      volume->roots.size() * 4 + volume->mids.size() * 4 + std::max<size_t>(volume->leaves.size(), 1) * 8);
  // The outputs, sums and ray limits (20 words a pixel), and the denoiser's working images (on
  // by default: two RGBA and two guide records, 16 words) and edge coverage records (24 words).
  ASSERT_TRUE(renderer.denoise());
  EXPECT_EQ(bytes.images, uint64_t(32 * 24) * ((1 + 1 + 6 + 4 + 1 + 1 + 4 + 1 + 1) + 16 + 24) * 4);
  EXPECT_EQ(bytes.total, renderer.deviceBytes());
  EXPECT_GE(bytes.total, bytes.encoding + bytes.acceleration + bytes.materials + bytes.images);

  renderer.render();
  EXPECT_EQ(renderer.accumulatedSamples(), 2u);
  renderer.setHiddenLabels({ 0 });
  const svdag::render::Image& hidden = renderer.render();
  EXPECT_EQ(renderer.accumulatedSamples(), 1u);
  EXPECT_EQ(renderer.bvhBuilds(), 0u);
  size_t had = 0;
  for (size_t i = 0; i < hidden.label.size(); ++i)
  {
    had += before.label[i] == 1;
    EXPECT_NE(hidden.label[i], 1u) << i;
  }
  EXPECT_GT(had, 0u);

  renderer.setBackend(svdag::render::Backend::RayTracing);
  const svdag::render::Image& rt = renderer.render();
  EXPECT_EQ(renderer.accumulatedSamples(), 1u);
  EXPECT_EQ(renderer.bvhBuilds(), 1u);
  EXPECT_GT(renderer.blasBytes(), 0u);
  EXPECT_EQ(renderer.deviceBytesByPart().acceleration,
    renderer.blasBytes() + renderer.tlasBytes() + sizeof(VkAccelerationStructureInstanceKHR) +
      4 * renderer.visibleBlocks());
  size_t same = 0;
  for (size_t i = 0; i < rt.label.size(); ++i)
    same += rt.label[i] == hidden.label[i];
  EXPECT_GE(same, size_t(0.999 * rt.label.size()));
}

// A device without ray tracing (simulated: SVDAG_VK_NO_RAY_TRACING) renders through the compute
// backend; asking for the ray tracing backend there is a clear error that changes nothing.
TEST(RenderBackends, DeviceWithoutRayTracingRendersThroughCompute)
{
  const svdag::Geometry g = tiltedGeometry();
  const auto volume = randomVolume(g, 99);
  svdag::render::Image reference;
  {
    svdag::render::Renderer renderer;
    renderer.setBackend(svdag::render::Backend::Compute);
    renderer.setVolume(volume);
    renderer.setImageSize(32, 24);
    renderer.setCamera(svdag::render::frameVolume(g, 25, -15, 1.5));
    reference = renderer.render();
  }
  ScopedEnv env("SVDAG_VK_NO_RAY_TRACING", "1");
  svdag::render::Renderer renderer;
  EXPECT_FALSE(renderer.hasRayTracing());
  EXPECT_EQ(renderer.backend(), svdag::render::Backend::Compute);
  renderer.setVolume(volume);
  renderer.setImageSize(32, 24);
  renderer.setCamera(svdag::render::frameVolume(g, 25, -15, 1.5));
  EXPECT_EQ(renderer.render().label, reference.label);
  try
  {
    renderer.setBackend(svdag::render::Backend::RayTracing);
    FAIL() << "the rt backend was accepted on a device without ray tracing";
  }
  catch (const std::runtime_error& e)
  {
    const std::string message = e.what();
    EXPECT_NE(message.find("needs a Vulkan device with ray tracing"), std::string::npos) << message;
    EXPECT_NE(message.find("SVDAG_VK_NO_RAY_TRACING"), std::string::npos) << message;
  }
  EXPECT_EQ(renderer.settings().backend, svdag::render::Backend::Auto);
  svdag::render::RenderSettings settings = renderer.settings();
  settings.backend = svdag::render::Backend::RayTracing;
  EXPECT_THROW(renderer.setSettings(settings), std::runtime_error);
  EXPECT_EQ(renderer.render().label, reference.label);
}

// An Accumulating pass leaves the denoiser out (its hdr and color are the raw mean, those of the
// same pass with the denoiser off); finishImage then gives exactly the Shown pass's image, and
// does nothing a second time or after a Shown pass.
TEST(RenderDenoiser, OnlyShownPassesAreFiltered)
{
  // Two large boxes: most pixels are inside one label, where the filter averages.
  svdag::Geometry g;
  g.dims = { { 28, 24, 20 } };
  std::vector<uint8_t> labels(g.voxelCount(), 0);
  for (int z = 2; z < 18; ++z)
    for (int y = 2; y < 22; ++y)
      for (int x = 2; x < 26; ++x)
        labels[x + 28 * (y + 24 * size_t(z))] = x < 14 ? 1 : 2;
  const auto volume = std::make_shared<const svdag::Volume>(
    svdag::Builder::build(g, svdag::ScalarType::UInt8, labels.data()));
  using PassUse = svdag::render::Renderer::PassUse;
  auto make = [&](bool denoise) {
    auto r = std::make_unique<svdag::render::Renderer>();
    r->setBackend(svdag::render::Backend::Compute);
    r->setVolume(volume);
    r->setImageSize(40, 30);
    r->setCamera(svdag::render::frameVolume(g, 25, -15, 1.2));
    r->setMaximumBounces(2);
    r->setDenoise(denoise);
    return r;
  };
  auto raw = make(false), deferred = make(true), shown = make(true);
  for (int pass = 0; pass < 3; ++pass)
  {
    const svdag::render::Image rawImage = raw->render();
    const svdag::render::Image& accumulating = deferred->render(PassUse::Accumulating);
    EXPECT_EQ(accumulating.hdr, rawImage.hdr) << pass;
    EXPECT_EQ(accumulating.color, rawImage.color) << pass;
    const svdag::render::Image shownImage = shown->render(PassUse::Shown);
    EXPECT_NE(shownImage.hdr, rawImage.hdr) << pass; // the filter changed something
    const double traced = deferred->lastFrameMilliseconds();
    const double filtered = deferred->finishImage();
    EXPECT_GT(filtered, 0.0);
    EXPECT_DOUBLE_EQ(deferred->lastFrameMilliseconds(), traced + filtered);
    EXPECT_EQ(deferred->image().hdr, shownImage.hdr) << pass;
    EXPECT_EQ(deferred->image().color, shownImage.color) << pass;
    EXPECT_EQ(deferred->finishImage(), 0.0);
    EXPECT_EQ(shown->finishImage(), 0.0);
    EXPECT_EQ(raw->finishImage(), 0.0);
  }
  EXPECT_EQ(deferred->accumulatedSamples(), 3u);
}

// Guided upsampling: a frame traced at 1/r of the image's size shows every pixel's own label,
// depth and normal (those of the full-resolution frame, exactly), never carries one label's
// color into a pixel of another where a same-label sample is near, and is closer to the
// full-resolution image than the reduced one scaled up by pixel replication.
TEST(RenderUpsampling, GuidesAreExactAndColorsStayWithinTheirLabel)
{
  svdag::Geometry g;
  g.dims = { { 40, 36, 30 } };
  std::vector<uint8_t> labels(g.voxelCount(), 0);
  for (int z = 3; z < 27; ++z)
    for (int y = 3; y < 33; ++y)
      for (int x = 3; x < 37; ++x)
        labels[x + 40 * (y + 36 * size_t(z))] = (x + y / 2) < 24 ? 1 : 2;
  const auto volume = std::make_shared<const svdag::Volume>(
    svdag::Builder::build(g, svdag::ScalarType::UInt8, labels.data()));
  for (const auto backend : { svdag::render::Backend::Compute, svdag::render::Backend::RayTracing })
  {
    auto make = [&](uint32_t reduction) {
      auto r = std::make_unique<svdag::render::Renderer>();
      r->setBackend(backend);
      r->setVolume(volume);
      r->setImageSize(67, 50); // not a multiple of the reduction
      r->setCamera(svdag::render::frameVolume(g, 30, 25, 1.3));
      r->setDenoise(false);
      r->setSeed(3);
      svdag::render::Material red = svdag::render::Renderer::defaultMaterial(0);
      red.baseColorVisibility = { 1, 0, 0, 1 };
      svdag::render::Material blue = red;
      blue.baseColorVisibility = { 0, 0, 1, 1 };
      r->setMaterials({ red, blue });
      r->setTraceReduction(reduction);
      return r;
    };
    auto full = make(1), reduced = make(3), coarse = make(1);
    coarse->setImageSize(23, 17); // the reduced trace's own size
    svdag::render::Image reference;
    for (int pass = 0; pass < 16; ++pass)
      reference = full->render();
    svdag::render::Image up;
    for (int pass = 0; pass < 16; ++pass)
      up = reduced->render();
    EXPECT_EQ(reduced->accumulatedSamples(), 16u);
    ASSERT_EQ(up.width, 67u);
    ASSERT_EQ(up.height, 50u);
    EXPECT_EQ(up.label, reference.label);
    EXPECT_EQ(up.depth, reference.depth);
    EXPECT_EQ(up.normal, reference.normal);
    svdag::render::Image small;
    for (int pass = 0; pass < 16; ++pass)
      small = coarse->render();
    double guided = 0, replicated = 0;
    size_t crossed = 0, foreground = 0;
    for (uint32_t y = 0; y < up.height; ++y)
    {
      for (uint32_t x = 0; x < up.width; ++x)
      {
        const size_t i = x + size_t(up.width) * y;
        const size_t j = std::min(x / 3, small.width - 1) + size_t(small.width) * std::min(y / 3, small.height - 1);
        for (int c = 0; c < 3; ++c)
        {
          guided += std::pow(up.hdr[4 * i + c] - reference.hdr[4 * i + c], 2);
          replicated += std::pow(small.hdr[4 * j + c] - reference.hdr[4 * i + c], 2);
        }
        if (up.label[i] == 0)
          continue;
        ++foreground;
        // Red label 1 shows no blue, blue label 2 no red (direct light of its own color; the
        // other label's color would come only from a bounce, which is dimmer).
        const float own = up.hdr[4 * i + (up.label[i] == 1 ? 0 : 2)];
        const float other = up.hdr[4 * i + (up.label[i] == 1 ? 2 : 0)];
        crossed += other > own;
      }
    }
    EXPECT_GT(foreground, size_t(up.width) * up.height / 4);
    EXPECT_LE(crossed, foreground / 200) << int(backend);
    EXPECT_LT(guided, 0.7 * replicated) << int(backend) << " " << guided << " " << replicated;
    std::cout << "backend " << int(backend) << ": guided SSE " << guided << ", replicated " << replicated
              << ", crossed " << crossed << " of " << foreground << "\n";
    // The guides follow what is visible: a label hidden by its material, then by the hidden set.
    svdag::render::Material invisible = reduced->material(0);
    invisible.baseColorVisibility.a = 0;
    reduced->setMaterial(0, invisible);
    const svdag::render::Image withoutRed = reduced->render();
    EXPECT_EQ(std::count(withoutRed.label.begin(), withoutRed.label.end(), 1u), 0);
    EXPECT_GT(std::count(withoutRed.label.begin(), withoutRed.label.end(), 2u), 0);
    invisible.baseColorVisibility.a = 1;
    reduced->setMaterial(0, invisible);
    reduced->setHiddenLabels({ 1 });
    const svdag::render::Image withoutBlue = reduced->render();
    EXPECT_EQ(std::count(withoutBlue.label.begin(), withoutBlue.label.end(), 2u), 0);
    EXPECT_GT(std::count(withoutBlue.label.begin(), withoutBlue.label.end(), 1u), 0);
  }
}
