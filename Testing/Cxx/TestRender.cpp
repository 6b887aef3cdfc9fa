// The VTK-free renderer core: camera framing and ray basis, the index-to-world matrix, device
// selection errors, and one rendered frame against the CPU ray caster (svdag::RayCaster, the same
// traversal code) on a small built volume. Needs a Vulkan device with ray tracing (lavapipe).
#include <svdag/Builder.h>
#include <svdag/RayCaster.h>
#include <svdag_render/Camera.h>
#include <svdag_render/Renderer.h>
#include <svdag_render/Scene.h>

#include <gtest/gtest.h>

#include <cmath>
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

TEST(RenderFrame, VoxelHitsMatchTheCpuRayCaster)
{
  const svdag::Geometry g = tiltedGeometry();
  const auto volume = randomVolume(g, 99);
  svdag::render::Renderer renderer;
  renderer.setVolume(volume);
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
