// The path-tracing integrator (Rendering/core/svdag_render/PathTracer.h) on analytic scenes traced
// on the CPU: white furnace, a sunlit plane against its closed form, NEE and plain estimators
// converging to the same answer, determinism and finiteness.
#include "svdag_render/EnvironmentMap.h"

#include <glm/glm.hpp>
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

namespace
{
// Spheres (center, radius) and an optional ground plane z = 0 (solid below).
struct Scene
{
  std::vector<glm::vec4> spheres;
  bool ground = false;
};
thread_local const Scene* scene = nullptr;
} // namespace

#define SVDAG_ENV_MARGINAL(i) 0.0f
#define SVDAG_ENV_CONDITIONAL(i) 0.0f
#define SVDAG_ENV_TEXEL(i) glm::vec3(0.0f)
#define SVDAG_FEATURE_NEE true
#define SVDAG_FEATURE_ENV_MAP false
#define SVDAG_FEATURE_SUN true
#define SVDAG_FEATURE_EMISSION true
#define SVDAG_FEATURE_TRANSMISSION true
#define SVDAG_FEATURE_PREVIEW false
// traceScene already reports only entries (a ray inside a sphere leaves it without a hit), which
// is what the renderer's entry-only trace (skipStart) does after a transmission event.
#define SVDAG_TRACE(hit, origin, direction, tmax, skipStart, anyHit)                              \
  hit = traceScene(origin, direction, tmax)
#define SVDAG_MATERIAL(label) (materials[(label)])

#include "svdag_render/Shading.h"

namespace svdag
{
namespace shading
{
PathHit traceScene(glm::vec3 o, glm::vec3 d, float tmax);
extern thread_local std::vector<Material> materials;
} // namespace shading
} // namespace svdag

#include "svdag_render/PathTracer.h"

namespace svdag
{
namespace shading
{
thread_local std::vector<Material> materials;

PathHit traceScene(glm::vec3 o, glm::vec3 d, float tmax)
{
  PathHit h;
  h.hit = false;
  h.inside = false;
  h.t = tmax;
  h.label = 0;
  h.normal = glm::vec3(0, 0, 1);
  for (size_t i = 0; i < scene->spheres.size(); ++i)
  {
    const glm::vec3 c(scene->spheres[i]);
    const float r = scene->spheres[i].w;
    const glm::vec3 oc = o - c;
    const float b = glm::dot(oc, d);
    const float disc = b * b - (glm::dot(oc, oc) - r * r);
    if (disc < 0)
      continue;
    const float t = -b - std::sqrt(disc);
    if (t > 0 && t < h.t)
    {
      h.hit = true;
      h.t = t;
      h.label = uint32_t(i);
      h.normal = glm::normalize(o + t * d - c);
    }
  }
  if (scene->ground && d.z < 0 && o.z > 0)
  {
    const float t = -o.z / d.z;
    if (t < h.t)
    {
      h.hit = true;
      h.t = t;
      h.label = uint32_t(scene->spheres.size());
      h.normal = glm::vec3(0, 0, 1);
    }
  }
  h.shading = h.normal; // no smooth shading in these analytic scenes
  h.lift = 0.0f;
  return h;
}
} // namespace shading
} // namespace svdag

namespace
{
using namespace svdag::shading;

Material diffuse(glm::vec3 albedo)
{
  Material m;
  m.baseColorVisibility = glm::vec4(albedo, 1);
  m.emission = glm::vec4(0);
  m.params = glm::vec4(1.0f, 0.0f, 0.0f, 1.5f);
  m.extra = glm::vec4(0); // no specular layer: exactly Lambertian
  return m;
}

PathTracerParams params(glm::vec3 environment, uint32_t bounces, bool nee)
{
  PathTracerParams p;
  p.sunDirection = glm::vec4(0, 0, 1, 1);
  p.sunRadiance = glm::vec4(0);
  p.environment = glm::vec4(environment, 1e-4f);
  p.config = glm::uvec4(1, 1, bounces, nee ? FLAG_NEE : 0u);
  return p;
}

// Mean radiance over many paths from `origin` towards `target` (one fixed direction).
glm::dvec3 meanRadiance(const PathTracerParams& p, glm::vec3 origin, glm::vec3 target, int paths)
{
  glm::dvec3 sum(0);
  const glm::vec3 d = glm::normalize(target - origin);
  for (int i = 0; i < paths; ++i)
  {
    uint32_t rng = pcgHash(uint32_t(i) * 9781u + 17u);
    sum += glm::dvec3(tracePath(p, origin, d, 1e30f, rng));
  }
  return sum / double(paths);
}

TEST(PathTracer, WhiteFurnace)
{
  // Two touching white spheres on a white ground plane: inter-reflections everywhere, and every
  // path still ends in the uniform environment, so the answer is its radiance, exactly.
  Scene s;
  s.spheres = { glm::vec4(0, 0, 1, 1), glm::vec4(1.9f, 0, 1, 1) };
  s.ground = false;
  scene = &s;
  materials = { diffuse(glm::vec3(1)), diffuse(glm::vec3(1)) };
  for (bool nee : { true, false })
  {
    const PathTracerParams p = params(glm::vec3(0.7f), 64, nee);
    for (const glm::vec3& target : { glm::vec3(0, 0, 1), glm::vec3(0.95f, 0, 1), glm::vec3(1.9f, 0.3f, 1.5f) })
    {
      const glm::dvec3 L = meanRadiance(p, glm::vec3(0.5f, -6, 1.2f), target, 40000);
      EXPECT_NEAR(L.x, 0.7, 0.007) << (nee ? "NEE" : "plain") << " towards " << target.x;
    }
  }
}

TEST(PathTracer, SunlitPlaneMatchesClosedForm)
{
  // Lambertian ground of albedo 0.5 under a sun of irradiance 3 at 60 degrees from the zenith and
  // a black sky: L = albedo / pi * E * cos(60 deg).
  Scene s;
  s.ground = true;
  scene = &s;
  materials = { diffuse(glm::vec3(0.5f)) };
  const glm::vec3 sun = glm::normalize(glm::vec3(std::sin(glm::radians(60.0f)), 0, 0.5f));
  const double expected = 0.5 / M_PI * 3.0 * 0.5;
  // Delta sun: only next-event estimation finds it, and gets it exactly.
  PathTracerParams p = params(glm::vec3(0), 4, true);
  p.sunDirection = glm::vec4(sun, 1.0f);
  p.sunRadiance = glm::vec4(3, 3, 3, 1);
  EXPECT_NEAR(meanRadiance(p, glm::vec3(0, -3, 2), glm::vec3(0, 0, 0), 2000).x, expected, 1e-5);
  // A disk sun of 5 degrees: NEE and plain path tracing converge to the same value.
  p.sunDirection.w = std::cos(glm::radians(5.0f));
  const double withNee = meanRadiance(p, glm::vec3(0, -3, 2), glm::vec3(0, 0, 0), 20000).x;
  p.config.w = 0;
  const double plain = meanRadiance(p, glm::vec3(0, -3, 2), glm::vec3(0, 0, 0), 400000).x;
  EXPECT_NEAR(withNee, expected, 0.01 * expected);
  EXPECT_NEAR(plain, expected, 0.05 * expected);
}

TEST(PathTracer, DeterministicAndFiniteOnExtremeMaterials)
{
  Scene s;
  s.spheres = { glm::vec4(0, 0, 1, 1) };
  s.ground = true;
  scene = &s;
  Material wild = diffuse(glm::vec3(1e30f, 0, 1));
  wild.emission = glm::vec4(1e38f, 0, 0, 0);
  wild.params = glm::vec4(0.0f, 1.0f, 1.0f, 1.0f);
  Material glass = diffuse(glm::vec3(1));
  glass.params = glm::vec4(0.0f, 0.0f, 1.0f, 1.5f);
  materials = { wild, glass };
  PathTracerParams p = params(glm::vec3(1e20f), 64, true);
  p.sunRadiance = glm::vec4(1e30f, 1e30f, 1e30f, 1);
  for (int i = 0; i < 2000; ++i)
  {
    uint32_t a = uint32_t(i), b = uint32_t(i);
    const glm::vec3 d = glm::normalize(glm::vec3(std::sin(i * 0.37f), std::cos(i * 0.11f), -0.5f));
    const glm::vec3 la = tracePath(p, glm::vec3(0, -4, 3), d, 1e30f, a);
    const glm::vec3 lb = tracePath(p, glm::vec3(0, -4, 3), d, 1e30f, b);
    ASSERT_EQ(la, lb) << "same seed, same result";
    for (int c = 0; c < 3; ++c)
      ASSERT_TRUE(std::isfinite(la[c]));
  }
}
} // namespace
