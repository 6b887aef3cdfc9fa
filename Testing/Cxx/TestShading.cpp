// The path tracer's shading code (Rendering/core/svdag_render/Shading.h), run on the CPU: energy
// conservation, sampling densities that match their pdfs, environment importance sampling, and no
// NaN or Inf on extreme materials.
#include "svdag_render/EnvironmentMap.h"

#define SVDAG_ENV_MARGINAL(i) 0.0f
#define SVDAG_ENV_CONDITIONAL(i) 0.0f
#define SVDAG_ENV_TEXEL(i) glm::vec3(0.0f)
#include "svdag_render/Shading.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace
{
using namespace svdag::shading;

Material material(glm::vec3 color, float roughness, float metallic, float transmission = 0,
  float ior = 1.5f, float specular = 0.5f)
{
  Material m;
  m.baseColorVisibility = glm::vec4(color, 1.0f);
  m.emission = glm::vec4(0.0f);
  m.params = glm::vec4(roughness, metallic, transmission, ior);
  m.extra = glm::vec4(specular, 0, 0, 0);
  return m;
}

glm::vec3 direction(float cosTheta, float phi)
{
  const float s = std::sqrt(std::max(0.0f, 1 - cosTheta * cosTheta));
  return { s * std::cos(phi), s * std::sin(phi), cosTheta };
}

// Mean throughput weight over many samples: the directional albedo of the material.
glm::vec3 albedo(const Material& m, const glm::vec3& n, const glm::vec3& wo, int samples)
{
  std::mt19937 rng(1);
  std::uniform_real_distribution<float> u(0, 1);
  glm::dvec3 sum(0);
  for (int i = 0; i < samples; ++i)
  {
    const BsdfSample s = bsdfSample(m, n, wo, true, glm::vec3(u(rng), u(rng), u(rng)));
    sum += glm::dvec3(s.weight);
  }
  return glm::vec3(sum / double(samples));
}

TEST(Shading, WhiteLambertIsEnergyConserving)
{
  // specular = 0: no Fresnel layer at all, a perfect white diffuser reflects everything.
  const Material m = material(glm::vec3(1), 1.0f, 0.0f, 0.0f, 1.5f, 0.0f);
  const glm::vec3 n(0, 0, 1);
  for (float c : { 1.0f, 0.7f, 0.3f, 0.05f })
  {
    const glm::vec3 a = albedo(m, n, direction(c, 0.3f), 200000);
    EXPECT_NEAR(a.x, 1.0f, 0.01f) << "cos(wo) = " << c;
  }
}

TEST(Shading, AlbedoNeverExceedsOne)
{
  const glm::vec3 n = glm::normalize(glm::vec3(0.3f, -0.5f, 0.8f));
  for (float roughness : { 0.0f, 0.1f, 0.5f, 1.0f })
    for (float metallic : { 0.0f, 0.5f, 1.0f })
      for (float c : { 0.95f, 0.5f, 0.15f })
      {
        const Material m = material(glm::vec3(1.0f), roughness, metallic);
        const glm::vec3 wo = direction(c, 1.0f);
        // wo is given in n's frame: rotate into world.
        const glm::vec3 woW = toWorld(wo, n);
        const glm::vec3 a = albedo(m, n, woW, 40000);
        EXPECT_LE(a.x, 1.02f) << "roughness " << roughness << " metallic " << metallic << " cos " << c;
        EXPECT_GT(a.x, 0.3f);
      }
}

TEST(Shading, SampledDensityMatchesPdf)
{
  // E[g(wi) / pdf(wi)] over sampled wi equals the integral of g when pdf is the true density:
  // with g = cos(theta) over the hemisphere the integral is pi (the mixture covers the whole
  // hemisphere, the diffuse strategy never has probability 0).
  const glm::vec3 n(0, 0, 1);
  std::mt19937 rng(2);
  std::uniform_real_distribution<float> u(0, 1);
  for (float roughness : { 0.05f, 0.3f, 1.0f })
    for (float metallic : { 0.0f, 1.0f })
    {
      const Material m = material(glm::vec3(0.8f, 0.6f, 0.4f), roughness, metallic);
      const glm::vec3 wo = direction(0.6f, 0.2f);
      double sum = 0;
      const int samples = 300000;
      for (int i = 0; i < samples; ++i)
      {
        const BsdfSample s = bsdfSample(m, n, wo, true, glm::vec3(u(rng), u(rng), u(rng)));
        if (s.pdf > 0)
        {
          EXPECT_NEAR(s.pdf, bsdfPdf(m, n, wo, s.direction), 1e-3f * s.pdf);
          sum += double(s.direction.z) / double(s.pdf);
        }
      }
      EXPECT_NEAR(sum / samples, M_PI, 0.03 * M_PI) << "roughness " << roughness << " metallic " << metallic;
    }
}

TEST(Shading, DielectricSplitsEnergyByFresnel)
{
  const glm::vec3 n(0, 0, 1);
  const Material glass = material(glm::vec3(1), 0.0f, 0.0f, 1.0f, 1.5f);
  for (float c : { 1.0f, 0.5f, 0.1f })
  {
    const glm::vec3 a = albedo(glass, n, direction(c, 0.0f), 20000);
    EXPECT_NEAR(a.x, 1.0f, 1e-5f) << "clear glass must neither gain nor lose energy";
  }
  // Leaving a dense medium beyond the critical angle reflects everything.
  const BsdfSample s = bsdfSample(glass, n, direction(0.2f, 0.0f), false, glm::vec3(0.5f, 0.5f, 0.5f));
  EXPECT_FALSE(s.transmitted);
  EXPECT_NEAR(fresnelDielectric(0.2f, 1.0f / 1.5f), 1.0f, 1e-6f);
  EXPECT_NEAR(fresnelDielectric(1.0f, 1.5f), 0.04f, 1e-3f);
}

TEST(Shading, ThinWalledTransmissionPassesStraightThrough)
{
  // Thin-walled dielectric: the transmitted share (1 - Fresnel) continues along -wo unbent, the
  // rest is the mirror direction; no other direction occurs.
  const glm::vec3 n(0, 0, 1);
  const Material glass = material(glm::vec3(0.5f, 1.0f, 0.25f), 0.0f, 0.0f, 1.0f, 1.5f);
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> u(0, 1);
  for (float c : { 1.0f, 0.6f, 0.2f })
  {
    const glm::vec3 wo = direction(c, 0.3f);
    const int samples = 20000;
    int transmitted = 0;
    for (int i = 0; i < samples; ++i)
    {
      const BsdfSample s = bsdfSample(glass, n, wo, true, glm::vec3(u(rng), u(rng), u(rng)));
      ASSERT_TRUE(s.delta);
      if (s.transmitted)
      {
        ++transmitted;
        ASSERT_NEAR(glm::length(s.direction + wo), 0.0f, 1e-5f) << "bent at cos " << c;
        ASSERT_EQ(s.weight, glm::vec3(0.5f, 1.0f, 0.25f)); // tinted by the base color
      }
      else
      {
        const glm::vec3 mirror(-wo.x, -wo.y, wo.z);
        ASSERT_NEAR(glm::length(s.direction - mirror), 0.0f, 1e-5f);
      }
    }
    const float expected = 1.0f - fresnelDielectric(c, 1.5f);
    EXPECT_NEAR(float(transmitted) / samples, expected, 0.015f) << "cos " << c;
  }
}

TEST(Shading, ExtremeMaterialsStayFinite)
{
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> u(0, 1);
  const float values[] = { 0.0f, 1e-7f, 0.5f, 1.0f };
  const glm::vec3 n(0, 0, 1);
  const glm::vec3 wos[] = { direction(1.0f, 0), direction(1e-6f, 0), direction(-0.5f, 0),
    direction(0.0f, 1), glm::vec3(0, 0, 1) };
  for (float r : values)
    for (float metal : values)
      for (float t : values)
        for (float ior : { 1.0f, 1.0001f, 4.0f })
          for (const glm::vec3& wo : wos)
            for (int i = 0; i < 50; ++i)
            {
              const Material m = material(glm::vec3(1, 0, 1e-9f), r, metal, t, ior, r);
              const BsdfSample s = bsdfSample(m, n, wo, i % 2 == 0, glm::vec3(u(rng), u(rng), u(rng)));
              for (int c = 0; c < 3; ++c)
              {
                ASSERT_TRUE(std::isfinite(s.weight[c]));
                ASSERT_TRUE(std::isfinite(s.direction[c]));
              }
              ASSERT_TRUE(std::isfinite(s.pdf));
              const glm::vec3 f = bsdfEval(m, n, wo, s.direction);
              ASSERT_TRUE(std::isfinite(f.x) && std::isfinite(bsdfPdf(m, n, wo, s.direction)));
            }
  EXPECT_EQ(finiteOrZero(glm::vec3(NAN, INFINITY, 2.0f)), glm::vec3(0, 0, 2));
}

TEST(Shading, PowerHeuristicWeightsSumToOne)
{
  for (float a : { 0.0f, 0.1f, 1.0f, 1e6f })
    for (float b : { 0.1f, 3.0f, 1e-6f })
      EXPECT_NEAR(powerHeuristic(a, b) + powerHeuristic(b, a), 1.0f, 1e-6f);
  EXPECT_EQ(powerHeuristic(0, 0), 0.0f);
}

TEST(EnvironmentMap, ImportanceSamplingIsUnbiased)
{
  // A map with a very bright texel: sampling must find it and estimate the integral exactly.
  const uint32_t w = 32, h = 16;
  std::vector<glm::vec3> texels(w * h);
  std::mt19937 rng(4);
  std::uniform_real_distribution<float> u(0, 1);
  for (auto& t : texels)
    t = glm::vec3(u(rng), u(rng), u(rng)) * 0.2f;
  texels[5 * w + 7] = glm::vec3(500.0f, 400.0f, 300.0f);
  texels[0] = glm::vec3(0.0f); // a black texel keeps a non-zero density
  const auto map = svdag::render::EnvironmentMap::fromTexels(w, h, texels);

  // Exact integral of the piecewise-constant map over the sphere.
  double exact = 0;
  for (uint32_t r = 0; r < h; ++r)
  {
    const double solidAngle = (2 * M_PI / w) * (std::cos(M_PI * r / h) - std::cos(M_PI * (r + 1) / h));
    for (uint32_t c = 0; c < w; ++c)
      exact += solidAngle * texels[r * w + c].x;
  }
  double estimate = 0, pdfIntegral = 0;
  const int samples = 400000;
  for (int i = 0; i < samples; ++i)
  {
    float pdf = 0;
    const glm::vec3 d = map.sample(glm::vec2(u(rng), u(rng)), pdf);
    ASSERT_GT(pdf, 0.0f);
    ASSERT_NEAR(pdf, map.pdf(d), 1e-3f * pdf);
    estimate += map.radiance(d).x / pdf;
    // pdf integrates to one: uniform directions.
    const float z = 2 * u(rng) - 1, phi = 2 * float(M_PI) * u(rng);
    const float s = std::sqrt(std::max(0.0f, 1 - z * z));
    pdfIntegral += map.pdf(glm::vec3(s * std::cos(phi), s * std::sin(phi), z)) * 4 * M_PI;
  }
  EXPECT_NEAR(estimate / samples, exact, 0.01 * exact);
  EXPECT_NEAR(pdfIntegral / samples, 1.0, 0.02);
}

TEST(EnvironmentMap, ConstantAndBadInput)
{
  const auto map = svdag::render::EnvironmentMap::constant(glm::vec3(0.5f, 1.0f, 2.0f));
  float pdf = 0;
  const glm::vec3 d = map.sample(glm::vec2(0.3f, 0.8f), pdf);
  EXPECT_FLOAT_EQ(pdf, 1.0f / (4.0f * float(M_PI)));
  EXPECT_FLOAT_EQ(map.pdf(d), pdf);
  EXPECT_NEAR(glm::length(d), 1.0f, 1e-6f);
  EXPECT_EQ(map.radiance(d), glm::vec3(0.5f, 1.0f, 2.0f));
  EXPECT_THROW(svdag::render::EnvironmentMap::fromTexels(2, 1, { glm::vec3(1), glm::vec3(NAN) }),
    std::runtime_error);
  EXPECT_THROW(svdag::render::EnvironmentMap::fromEXR("/nonexistent.exr"), std::runtime_error);
}
} // namespace
