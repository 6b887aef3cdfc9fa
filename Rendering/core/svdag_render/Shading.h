/* Materials, BSDF sampling, multiple importance sampling and environment-light sampling of the
 * path tracer, shared by the GLSL shaders and the C++ tests (common subset of GLSL 4.60 and C++17
 * with GLM, like Module/core/svdag/Layout.h).
 *
 * BSDF model per label: a Lambertian diffuse lobe and a GGX microfacet specular lobe (metallic /
 * dielectric via Schlick's Fresnel with F0 = mix(0.08 * specular, baseColor, metallic)), plus an
 * optional smooth dielectric transmission lobe (delta, exact Fresnel, index of refraction `ior`).
 * Transmission is a thin-walled dielectric: Fresnel splits the light at the surface, and what is
 * transmitted passes straight through (no bending), because the traversal cannot follow a ray
 * through the interior of a label (a transmitted ray skips the solid it starts in and continues to
 * the next surface it enters).
 * The non-delta lobes are sampled as one mixture, so eval() and pdf() describe the same density that
 * sample() draws from (required for MIS). Directions are world-space unit vectors; `n` is the
 * shading normal facing the incoming side, wo points away from the surface (towards the viewer).
 *
 * The environment is a constant radiance or an equirectangular map (longitude along u from +x
 * towards +y, latitude v from +z (v = 0) down to -z (v = 1)), importance-sampled through a marginal
 * CDF over rows and a conditional CDF per row, built on the host (see EnvironmentMap.h). Buffer
 * access goes through macros the includer defines: SVDAG_ENV_MARGINAL(i), SVDAG_ENV_CONDITIONAL(i),
 * SVDAG_ENV_TEXEL(i) (vec3 radiance).
 */
#ifndef SVDAG_RENDER_SHADING_H
#define SVDAG_RENDER_SHADING_H

#include "svdag_render/Material.h"

#ifdef __cplusplus
#include <cstdint>
#include <glm/glm.hpp>
namespace svdag
{
namespace shading
{
using namespace glm;
typedef uint32_t uint;
#define SHADING_CONST constexpr
#define SHADING_FN inline
#define SHADING_INOUT(T) T&
#define SHADING_OUT(T) T&
#else
#define SHADING_CONST const
#define SHADING_FN
#define SHADING_INOUT(T) inout T
#define SHADING_OUT(T) out T
#endif

SHADING_CONST float PI = 3.14159265358979f;
SHADING_CONST float INV_PI = 0.31830988618379f;
SHADING_CONST float MIN_ROUGHNESS = 0.02f; // below, GGX is numerically a mirror: keep it finite

/* Per-label material (std430, 64 bytes): svdag_render/Material.h, included above the
 * namespace. */

/* ---- random numbers: PCG hash (O'Neill), 32-bit state ---------------------------------------- */
SHADING_FN uint pcgHash(uint v)
{
  uint state = v * 747796405u + 2891336453u;
  uint word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;
  return (word >> 22u) ^ word;
}
SHADING_FN float random01(SHADING_INOUT(uint) state)
{
  state = pcgHash(state);
  return float(state >> 8u) * (1.0f / 16777216.0f); // [0, 1)
}

/* ---- small helpers ---------------------------------------------------------------------------- */
SHADING_FN float luminance(vec3 c) { return dot(c, vec3(0.2126f, 0.7152f, 0.0722f)); }
SHADING_FN float saturate1(float x) { return clamp(x, 0.0f, 1.0f); }
/* Orthonormal basis around a unit normal, without branches on the sign of n.z except one. */
SHADING_FN void basis(vec3 n, SHADING_OUT(vec3) t, SHADING_OUT(vec3) b)
{
  float s = n.z >= 0.0f ? 1.0f : -1.0f;
  float a = -1.0f / (s + n.z);
  float c = n.x * n.y * a;
  t = vec3(1.0f + s * n.x * n.x * a, s * c, -s * n.x);
  b = vec3(c, s + n.y * n.y * a, -n.y);
}
SHADING_FN vec3 toWorld(vec3 v, vec3 n)
{
  vec3 t, b;
  basis(n, t, b);
  return v.x * t + v.y * b + v.z * n;
}
SHADING_FN vec3 toLocal(vec3 v, vec3 n)
{
  vec3 t, b;
  basis(n, t, b);
  return vec3(dot(v, t), dot(v, b), dot(v, n));
}
SHADING_FN float powerHeuristic(float pdfA, float pdfB)
{
  float a = pdfA * pdfA, b = pdfB * pdfB;
  return a + b > 0.0f ? a / (a + b) : 0.0f;
}
/* Replaces NaN and infinite components by zero: no sample may poison an accumulated image. */
SHADING_FN vec3 finiteOrZero(vec3 c)
{
  bvec3 bad = bvec3(isnan(c.x) || isinf(c.x), isnan(c.y) || isinf(c.y), isnan(c.z) || isinf(c.z));
  return vec3(bad.x ? 0.0f : c.x, bad.y ? 0.0f : c.y, bad.z ? 0.0f : c.z);
}

/* ---- GGX microfacet lobe (isotropic, Smith height-correlated masking) ------------------------- */
SHADING_FN float ggxD(float nh, float alpha)
{
  float a2 = alpha * alpha;
  float d = nh * nh * (a2 - 1.0f) + 1.0f;
  return a2 / (PI * d * d);
}
SHADING_FN float ggxLambda(float cosTheta, float alpha)
{
  float c2 = max(cosTheta * cosTheta, 1e-8f);
  float tan2 = max(1.0f - c2, 0.0f) / c2;
  return 0.5f * (sqrt(1.0f + alpha * alpha * tan2) - 1.0f);
}
SHADING_FN float ggxG1(float cosTheta, float alpha) { return 1.0f / (1.0f + ggxLambda(cosTheta, alpha)); }
SHADING_FN float ggxG2(float no, float ni, float alpha)
{
  return 1.0f / (1.0f + ggxLambda(no, alpha) + ggxLambda(ni, alpha));
}
/* Samples a visible normal (Heitz 2018) in the local frame for view direction vLocal (z up). */
SHADING_FN vec3 ggxSampleVisibleNormal(vec3 vLocal, float alpha, float u1, float u2)
{
  vec3 vh = normalize(vec3(alpha * vLocal.x, alpha * vLocal.y, vLocal.z));
  float lensq = vh.x * vh.x + vh.y * vh.y;
  vec3 t1 = lensq > 1e-12f ? vec3(-vh.y, vh.x, 0.0f) / sqrt(lensq) : vec3(1.0f, 0.0f, 0.0f);
  vec3 t2 = cross(vh, t1);
  float r = sqrt(u1);
  float phi = 2.0f * PI * u2;
  float p1 = r * cos(phi);
  float p2 = r * sin(phi);
  float s = 0.5f * (1.0f + vh.z);
  p2 = (1.0f - s) * sqrt(max(0.0f, 1.0f - p1 * p1)) + s * p2;
  vec3 nh = p1 * t1 + p2 * t2 + sqrt(max(0.0f, 1.0f - p1 * p1 - p2 * p2)) * vh;
  return normalize(vec3(alpha * nh.x, alpha * nh.y, max(1e-6f, nh.z)));
}
/* Density of wi (local) when sampling visible normals for wo: D_v(h) / (4 wo.h). */
SHADING_FN float ggxReflectionPdf(vec3 wo, vec3 wi, float alpha)
{
  vec3 h = normalize(wo + wi);
  float oh = dot(wo, h);
  if (wo.z <= 0.0f || wi.z <= 0.0f || oh <= 0.0f)
    return 0.0f;
  return ggxG1(wo.z, alpha) * ggxD(h.z, alpha) / (4.0f * wo.z);
}

/* Schlick's Fresnel; the grazing reflectance fades out for F0 below 2% so that a material with
 * no specular reflectance is exactly Lambertian (and energy-conserving). */
SHADING_FN vec3 schlick(vec3 f0, float cosTheta)
{
  float m = saturate1(1.0f - cosTheta);
  float m5 = m * m * m * m * m;
  float f90 = saturate1(50.0f * max(f0.x, max(f0.y, f0.z)));
  return f0 + (vec3(f90) - f0) * m5;
}
/* Exact unpolarised Fresnel reflectance of a smooth dielectric; eta = n_transmitted / n_incident. */
SHADING_FN float fresnelDielectric(float cosI, float eta)
{
  float sin2T = (1.0f - cosI * cosI) / (eta * eta);
  if (sin2T >= 1.0f)
    return 1.0f; // total internal reflection
  float cosT = sqrt(max(0.0f, 1.0f - sin2T));
  float rs = (cosI - eta * cosT) / (cosI + eta * cosT);
  float rp = (eta * cosI - cosT) / (eta * cosI + cosT);
  return saturate1(0.5f * (rs * rs + rp * rp));
}

/* ---- the material's BSDF ---------------------------------------------------------------------- */
SHADING_FN float materialAlpha(Material m)
{
  float r = clamp(m.params.x, MIN_ROUGHNESS, 1.0f);
  return r * r;
}
SHADING_FN vec3 materialF0(Material m)
{
  vec3 dielectric = vec3(0.08f * clamp(m.extra.x, 0.0f, 1.0f));
  return mix(dielectric, vec3(m.baseColorVisibility), saturate1(m.params.y));
}
/* Probabilities of choosing the transmission (delta) lobe and, otherwise, the specular lobe. */
SHADING_FN float transmissionProbability(Material m)
{
  return saturate1(m.params.z) * (1.0f - saturate1(m.params.y));
}
SHADING_FN float specularProbability(Material m)
{
  float metallic = saturate1(m.params.y);
  float spec = luminance(materialF0(m));
  float diffuse = (1.0f - metallic) * luminance(vec3(m.baseColorVisibility));
  // Never 0 or 1: each strategy keeps covering the other lobe's support, so the mixture stays
  // unbiased for any material.
  return clamp(spec / max(spec + diffuse, 1e-4f), 0.1f, 0.9f);
}

/* f(wo, wi) * |n.wi| of the non-delta lobes, weighted by the probability of not transmitting. */
SHADING_FN vec3 bsdfEval(Material m, vec3 n, vec3 woW, vec3 wiW)
{
  vec3 wo = toLocal(woW, n);
  vec3 wi = toLocal(wiW, n);
  if (wo.z <= 0.0f || wi.z <= 0.0f)
    return vec3(0.0f);
  float keep = 1.0f - transmissionProbability(m);
  float metallic = saturate1(m.params.y);
  float alpha = materialAlpha(m);
  vec3 h = normalize(wo + wi);
  vec3 F = schlick(materialF0(m), saturate1(dot(wi, h)));
  vec3 spec = F * ggxD(h.z, alpha) * ggxG2(wo.z, wi.z, alpha) / (4.0f * wo.z);
  // The diffuse lobe gets what the specular layer does not reflect towards wo (an
  // approximation that keeps the directional albedo at or below one).
  vec3 fo = schlick(materialF0(m), wo.z);
  float diffuseShare = 1.0f - max(fo.x, max(fo.y, fo.z));
  vec3 diffuse = (1.0f - metallic) * diffuseShare * vec3(m.baseColorVisibility) * INV_PI * wi.z;
  return keep * (spec + diffuse);
}
/* Solid-angle density with which bsdfSample draws wi (non-delta part, including its selection). */
SHADING_FN float bsdfPdf(Material m, vec3 n, vec3 woW, vec3 wiW)
{
  vec3 wo = toLocal(woW, n);
  vec3 wi = toLocal(wiW, n);
  if (wo.z <= 0.0f || wi.z <= 0.0f)
    return 0.0f;
  float keep = 1.0f - transmissionProbability(m);
  float ps = specularProbability(m);
  return keep * (ps * ggxReflectionPdf(wo, wi, materialAlpha(m)) + (1.0f - ps) * wi.z * INV_PI);
}

/* Result of sampling: direction, throughput weight f*cos/pdf, pdf (0 for a delta lobe). */
struct BsdfSample
{
  vec3 direction;
  vec3 weight;
  float pdf;
  bool delta;
  bool transmitted;
};

/* Samples the BSDF; `entering` tells whether wo is outside the object (for the dielectric's eta,
 * i.e. only for the Fresnel split). A zero weight means the path ends. */
SHADING_FN BsdfSample bsdfSample(Material m, vec3 n, vec3 woW, bool entering, vec3 u)
{
  BsdfSample s;
  s.direction = n;
  s.weight = vec3(0.0f);
  s.pdf = 0.0f;
  s.delta = false;
  s.transmitted = false;
  vec3 wo = toLocal(woW, n);
  if (wo.z <= 0.0f)
    return s;
  float pt = transmissionProbability(m);
  if (u.x < pt)
  {
    // Thin-walled smooth dielectric: reflect or pass straight through (-wo), split by Fresnel;
    // the lobe choice cancels the pdf.
    float ior = max(m.params.w, 1.0001f);
    float eta = entering ? ior : 1.0f / ior;
    float F = fresnelDielectric(wo.z, eta);
    s.delta = true;
    s.pdf = 0.0f;
    float uf = u.x / max(pt, 1e-6f); // reuse the remainder of u.x, uniform in [0, 1)
    if (uf < F)
    {
      s.direction = toWorld(vec3(-wo.x, -wo.y, wo.z), n);
      s.weight = vec3(1.0f);
    }
    else
    {
      s.direction = -woW;
      s.weight = vec3(m.baseColorVisibility); // tinted transmission; radiance scaling omitted
      s.transmitted = true;
    }
    return s;
  }
  float ps = specularProbability(m);
  float v = (u.x - pt) / max(1.0f - pt, 1e-6f);
  vec3 wi;
  if (v < ps)
  {
    vec3 h = ggxSampleVisibleNormal(wo, materialAlpha(m), u.y, u.z);
    wi = reflect(-wo, h);
  }
  else
  {
    float r = sqrt(u.y);
    float phi = 2.0f * PI * u.z;
    wi = vec3(r * cos(phi), r * sin(phi), sqrt(max(0.0f, 1.0f - u.y)));
  }
  if (wi.z <= 0.0f)
    return s;
  s.direction = toWorld(wi, n);
  s.pdf = bsdfPdf(m, n, woW, s.direction);
  if (s.pdf <= 0.0f)
    return s;
  s.weight = finiteOrZero(bsdfEval(m, n, woW, s.direction) / s.pdf);
  return s;
}

/* ---- equirectangular environment ---------------------------------------------------------------- */
SHADING_FN vec2 envDirectionToUV(vec3 d)
{
  float u = atan(d.y, d.x) * (0.5f * INV_PI);
  u = u < 0.0f ? u + 1.0f : u;
  float v = acos(clamp(d.z, -1.0f, 1.0f)) * INV_PI;
  return vec2(u, v);
}
SHADING_FN vec3 envUVToDirection(vec2 uv)
{
  float phi = 2.0f * PI * uv.x;
  float theta = PI * uv.y;
  float st = sin(theta);
  return vec3(st * cos(phi), st * sin(phi), cos(theta));
}

/* Index of the CDF interval holding u: cdf[first .. first + n] ascending, cdf[first] = 0,
 * cdf[first + n] = 1. Bounded binary search (at most 32 steps). */
#define SHADING_CDF_FIND(result, CDF, first, n, u)                                                 \
  {                                                                                                \
    uint lo_ = 0u, hi_ = (n);                                                                      \
    for (uint it_ = 0u; it_ < 32u && hi_ - lo_ > 1u; ++it_)                                        \
    {                                                                                              \
      uint mid_ = (lo_ + hi_) / 2u;                                                                \
      if (CDF((first) + mid_) <= (u))                                                              \
        lo_ = mid_;                                                                                \
      else                                                                                         \
        hi_ = mid_;                                                                                \
    }                                                                                              \
    result = lo_;                                                                                  \
  }

/* Solid-angle density of direction d under the map's importance distribution. The marginal CDF
 * has height + 1 entries, each row's conditional CDF width + 1 entries (row r starts at
 * r * (width + 1)). */
SHADING_FN float envPdf(vec3 d, uint width, uint height)
{
  if (width == 1u && height == 1u)
    return 0.25f * INV_PI; // a constant environment is sampled uniformly over the sphere
  vec2 uv = envDirectionToUV(d);
  uint col = min(uint(uv.x * float(width)), width - 1u);
  uint row = min(uint(uv.y * float(height)), height - 1u);
  float pRow = SVDAG_ENV_MARGINAL(row + 1u) - SVDAG_ENV_MARGINAL(row);
  uint base = row * (width + 1u);
  float pCol = SVDAG_ENV_CONDITIONAL(base + col + 1u) - SVDAG_ENV_CONDITIONAL(base + col);
  float sinTheta = length(vec2(d.x, d.y)); // precise near the poles, unlike sin(acos(z))
  return pRow * pCol * float(width) * float(height) / (2.0f * PI * PI * max(sinTheta, 1e-6f));
}

/* Draws a direction with density envPdf; returns it and writes its pdf. */
SHADING_FN vec3 envSample(vec2 u, uint width, uint height, SHADING_OUT(float) pdf)
{
  if (width == 1u && height == 1u)
  {
    pdf = 0.25f * INV_PI;
    float z = 1.0f - 2.0f * u.x;
    float r = sqrt(max(0.0f, 1.0f - z * z));
    float phi = 2.0f * PI * u.y;
    return vec3(r * cos(phi), r * sin(phi), z);
  }
  uint row;
  SHADING_CDF_FIND(row, SVDAG_ENV_MARGINAL, 0u, height, u.x);
  float r0 = SVDAG_ENV_MARGINAL(row), r1 = SVDAG_ENV_MARGINAL(row + 1u);
  float fv = r1 > r0 ? saturate1((u.x - r0) / (r1 - r0)) : 0.5f;
  uint base = row * (width + 1u);
  uint col;
  SHADING_CDF_FIND(col, SVDAG_ENV_CONDITIONAL, base, width, u.y);
  float c0 = SVDAG_ENV_CONDITIONAL(base + col), c1 = SVDAG_ENV_CONDITIONAL(base + col + 1u);
  float fu = c1 > c0 ? saturate1((u.y - c0) / (c1 - c0)) : 0.5f;
  // Stay inside the chosen texel so that envPdf finds the same one.
  fu = clamp(fu, 1e-4f, 1.0f - 1e-4f);
  fv = clamp(fv, 1e-4f, 1.0f - 1e-4f);
  vec2 uv = vec2((float(col) + fu) / float(width), (float(row) + fv) / float(height));
  vec3 d = envUVToDirection(uv);
  float sinTheta = length(vec2(d.x, d.y)); // as envPdf computes it from the direction
  pdf = (r1 - r0) * (c1 - c0) * float(width) * float(height) /
    (2.0f * PI * PI * max(sinTheta, 1e-6f));
  return d;
}

/* Radiance of the map in direction d (nearest texel). */
SHADING_FN vec3 envRadiance(vec3 d, uint width, uint height)
{
  vec2 uv = envDirectionToUV(d);
  uint col = min(uint(uv.x * float(width)), width - 1u);
  uint row = min(uint(uv.y * float(height)), height - 1u);
  return SVDAG_ENV_TEXEL(row * width + col);
}

/* ---- interface of the path-tracing integrator (PathTracer.h) ----------------------------------- */
SHADING_CONST uint MAX_BOUNCES_LIMIT = 64u; // hard bound of the path loop
SHADING_CONST uint FLAG_NEE = 1u;

/* Lighting and integrator settings, std430/std140-compatible (64 bytes). */
struct PathTracerParams
{
  vec4 sunDirection;   // xyz: unit direction towards the light (world), w: cos(angular radius)
  vec4 sunRadiance;    // rgb: irradiance at normal incidence (radiance * solid angle), a: 1 = on
  vec4 environment;    // rgb: constant environment radiance, or the map's scale; a: ray epsilon
  uvec4 config;        // x, y: environment map size (1 x 1 = constant), z: max bounces, w: flags
};

/* What a closest-hit query returns. */
struct PathHit
{
  bool hit;
  bool inside; // the ray started inside the solid: t and normal describe where it leaves it
  float t;     // distance along the (unit) direction
  uint label;  // label index
  vec3 normal; // unit geometric normal of the face crossed, world space, pointing out of the solid
  vec3 shading; // unit shading normal for the BSDF (smooth shading; else equal to normal), facing
                // the ray; the geometric normal still offsets the rays that leave the surface
  float lift;   // world distance along `shading` that shadow rays and reflected paths start at,
                // to clear the voxel staircase a smooth normal stands for (SmoothNormal.h); 0 with
                // face normals
};

#ifdef __cplusplus
} // namespace shading
} // namespace svdag
#endif

#endif
