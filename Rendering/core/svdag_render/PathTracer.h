/* The path-tracing integrator, shared by the ray generation shader and a CPU reference (common
 * subset of GLSL 4.60 and C++17 with GLM, like Shading.h).
 *
 * Unidirectional path tracing with next-event estimation: at every non-delta scattering event the
 * environment (importance-sampled) and the directional light are sampled with a shadow ray; BSDF
 * sampling continues the path, and an escaping path adds the environment and the sun weighted by
 * the power heuristic against the light-sampling densities. The sun is a disk of a given angular
 * radius (radius 0: a delta light that only light sampling can find). Emissive voxels add their
 * emission where a path hits them. Russian roulette from the third bounce. With NEE disabled the
 * estimator is the plain "light only where a path escapes" one (the paper authors' estimator),
 * kept for the error-versus-time comparison.
 *
 * The last scattering event (the one whose continuation would end the path) with NEE, a constant
 * environment and nothing emissive: its continuation could only collect the environment and the
 * sun where it escapes. So the environment is sampled there by the BSDF alone (for a constant
 * environment the better of the two strategies) with an occlusion ray instead of a closest-hit
 * one, the sun by light sampling alone (weight 1), and no environment shadow ray is traced: one
 * ray fewer per path, the same expectation. A delta (transmission) sample still continues.
 *
 * Its interface types (PathTracerParams, PathHit) are in Shading.h, so that the includer can
 * define its trace functions before including this file. The includer defines:
 *   SVDAG_TRACE(hit, origin, direction, tmax, skipStart, anyHit)  fills a PathHit for the nearest
 *       surface; with skipStart the ray starts just inside a solid (after a transmission event) or
 *       lifted above a smooth-shaded hit, possibly inside a voxel of a touching label, and must
 *       skip the solid it starts in and report the next surface it ENTERS (the renderer's
 *       entry-only hit group, Traversal.h "Entry only"); where a trace never reports a hit from
 *       inside anyway, it may ignore skipStart. With anyHit (shadow rays) only hit.hit counts:
 *       whether anything is hit, so the trace may stop at the first hit it finds
 *   SVDAG_MATERIAL(labelIndex)  the Material of a label
 *   and the environment macros of Shading.h.
 * Feature switches (specialization constants on the GPU, so a scene that does not use a feature
 * does not pay for it): SVDAG_FEATURE_NEE, SVDAG_FEATURE_ENV_MAP, SVDAG_FEATURE_SUN,
 * SVDAG_FEATURE_EMISSION, SVDAG_FEATURE_TRANSMISSION (booleans), and SVDAG_FEATURE_PREVIEW: no
 * path at all, the camera ray's first hit shaded by its base color under a headlight (what a
 * window shows while the full pipeline compiles; the rest of the integrator is compiled out).
 */
#ifndef SVDAG_RENDER_PATHTRACER_H
#define SVDAG_RENDER_PATHTRACER_H

#include "svdag_render/Shading.h"

// SVDAG_TRACE is expanded at one place only: an includer may inline its trace (the compute
// backend inlines the whole grid walk), so every further site would be another copy of it.

#ifdef __cplusplus
namespace svdag
{
namespace shading
{
#endif

SHADING_FN vec3 environmentRadiance(PathTracerParams p, vec3 d)
{
  if (SVDAG_FEATURE_ENV_MAP)
    return vec3(p.environment) * envRadiance(d, p.config.x, p.config.y);
  return vec3(p.environment);
}

SHADING_FN float environmentPdf(PathTracerParams p, vec3 d)
{
  if (SVDAG_FEATURE_ENV_MAP)
    return envPdf(d, p.config.x, p.config.y);
  return 0.25f * INV_PI;
}

SHADING_FN vec3 environmentSample(PathTracerParams p, vec2 u, SHADING_OUT(float) pdf)
{
  if (SVDAG_FEATURE_ENV_MAP)
    return envSample(u, p.config.x, p.config.y, pdf);
  return envSample(u, 1u, 1u, pdf);
}

/* Solid angle of the sun disk; 0 for a delta light. */
SHADING_FN float sunSolidAngle(PathTracerParams p)
{
  float cosMax = clamp(p.sunDirection.w, -1.0f, 1.0f);
  return cosMax >= 0.9999999f ? 0.0f : 2.0f * PI * (1.0f - cosMax);
}

/* Radiance of the sun seen along d (zero outside the disk or for a delta sun). */
SHADING_FN vec3 sunRadianceAlong(PathTracerParams p, vec3 d)
{
  float omega = sunSolidAngle(p);
  if (!(SVDAG_FEATURE_SUN) || p.sunRadiance.a <= 0.0f || omega <= 0.0f ||
    dot(d, vec3(p.sunDirection)) < p.sunDirection.w)
    return vec3(0.0f);
  return vec3(p.sunRadiance) / omega;
}

/* Uniform direction in the sun's cone; pdf = 1 / solid angle (0 for a delta sun). */
SHADING_FN vec3 sunSample(PathTracerParams p, vec2 u, SHADING_OUT(float) pdf)
{
  float omega = sunSolidAngle(p);
  vec3 axis = normalize(vec3(p.sunDirection));
  if (omega <= 0.0f)
  {
    pdf = 0.0f;
    return axis;
  }
  float z = 1.0f - u.x * (1.0f - p.sunDirection.w);
  float r = sqrt(max(0.0f, 1.0f - z * z));
  float phi = 2.0f * PI * u.y;
  pdf = 1.0f / omega;
  return normalize(toWorld(vec3(r * cos(phi), r * sin(phi), z), axis));
}

/* Radiance arriving along a camera ray that may hit the volume up to `cameraTmax` (an opaque
 * surface drawn before the volume, or a far plane: beyond it the ray counts as a miss); `rng`
 * advances. Never NaN or Inf. */
SHADING_FN vec3 tracePath(
  PathTracerParams p, vec3 origin, vec3 direction, float cameraTmax, SHADING_INOUT(uint) rng)
{
  vec3 radiance = vec3(0.0f);
  vec3 throughput = vec3(1.0f);
  float previousPdf = 0.0f;
  bool previousDelta = true; // the camera "samples" its ray with a delta distribution
  bool nee = SVDAG_FEATURE_NEE && (p.config.w & FLAG_NEE) != 0u;
  uint maxBounces = min(p.config.z, MAX_BOUNCES_LIMIT);
  float epsilon = p.environment.w;
  // The path's next segment.
  vec3 o = origin;
  vec3 d = direction;
  float tmax = cameraTmax;
  // The segment starts through the surface it has just crossed, or above a smooth-shaded hit.
  bool skipStart = false;
  // The last event's shadow rays (at most two: the environment's or the last event's, and the
  // sun's), with what each adds where nothing is in the way; `traced` of them are done.
  vec3 shadowOrigin = vec3(0.0f);
  bool shadowLifted = false;
  vec3 shadowDirection[2];
  vec3 shadowRadiance[2];
  shadowDirection[0] = shadowDirection[1] = vec3(0.0f);
  shadowRadiance[0] = shadowRadiance[1] = vec3(0.0f);
  uint shadows = 0u;
  uint traced = 0u;
  bool ends = false; // no segment follows the last event's shadow rays
  uint bounce = 0u;
  // One trace for every ray of the path, as Volcanite does: each iteration traces the last
  // event's next shadow ray or, when none is left, the path's next segment. The samples of an
  // event are drawn before its shadow rays are traced (environment, sun, BSDF, roulette: the
  // order of rng), which depend on nothing drawn after them.
  for (;;)
  {
    bool shadowRay = traced < shadows;
    if (!shadowRay && ends)
      break;
    vec3 rayOrigin = o;
    vec3 rayDirection = d;
    float rayTmax = tmax;
    bool raySkipStart = skipStart;
    if (shadowRay)
    {
      rayOrigin = shadowOrigin;
      rayDirection = shadowDirection[traced];
      rayTmax = 1e30f;
      raySkipStart = shadowLifted;
    }
    PathHit h;
    SVDAG_TRACE(h, rayOrigin, rayDirection, rayTmax, raySkipStart, shadowRay);
    if (shadowRay)
    {
      if (!h.hit)
        radiance += shadowRadiance[traced];
      ++traced;
      continue;
    }
    shadows = 0u;
    traced = 0u;
    if (!h.hit)
    {
      bool weighted = nee && !previousDelta;
      float wEnv = weighted ? powerHeuristic(previousPdf, environmentPdf(p, d)) : 1.0f;
      float omega = sunSolidAngle(p);
      float wSun = (weighted && omega > 0.0f) ? powerHeuristic(previousPdf, 1.0f / omega) : 1.0f;
      radiance += throughput * (wEnv * environmentRadiance(p, d) + wSun * sunRadianceAlong(p, d));
      break;
    }
    Material m = SVDAG_MATERIAL(h.label);
    if (SVDAG_FEATURE_PREVIEW)
    {
      float facing = h.inside ? 1.0f : abs(dot(h.shading, d));
      radiance = vec3(m.baseColorVisibility) * (0.3f + 0.7f * facing);
      break;
    }
    if (SVDAG_FEATURE_EMISSION && !h.inside)
      radiance += throughput * vec3(m.emission);
    if (bounce == maxBounces)
      break;
    // Shade on the side the ray comes from.
    vec3 n = h.inside ? -h.normal : h.normal;
    if (dot(n, d) > 0.0f)
      n = -n;
    // The BSDF sees the shading normal. Shadow rays and reflected paths of a smooth-shaded hit
    // start above the staircase (shadowOrigin below); with face normals a path continuing below
    // the geometric surface n ends (its ray would start into the solid).
    vec3 ns = h.inside ? n : h.shading;
    if (!(dot(ns, d) < 0.0f))
      ns = n;
    vec3 wo = -d;
    vec3 position = o + h.t * d;
    vec3 above = position + epsilon * n;
    // Shadow rays and reflected paths of a smooth-shaded hit start h.lift further along the
    // shading normal: the voxel staircase next to the hit would otherwise shadow the smooth
    // surface it stands for (dark dots in every step's corner, stripes near the terminator).
    bool lifted = !h.inside && h.lift > 0.0f;
    shadowLifted = lifted;
    shadowOrigin = lifted ? above + h.lift * ns : above;

    // The last scattering event with a constant environment and nothing emissive (see above).
    bool lastEvent = nee && bounce + 1u == maxBounces && !(SVDAG_FEATURE_EMISSION) &&
      !(SVDAG_FEATURE_ENV_MAP);
    if (nee && !lastEvent)
    {
      float lightPdf;
      vec3 wl = environmentSample(p, vec2(random01(rng), random01(rng)), lightPdf);
      vec3 f = bsdfEval(m, ns, wo, wl);
      if (lightPdf > 0.0f && max(f.x, max(f.y, f.z)) > 0.0f)
      {
        shadowDirection[shadows] = wl;
        shadowRadiance[shadows] = throughput * f * environmentRadiance(p, wl) *
          (powerHeuristic(lightPdf, bsdfPdf(m, ns, wo, wl)) / lightPdf);
        ++shadows;
      }
    }
    if (nee && SVDAG_FEATURE_SUN && p.sunRadiance.a > 0.0f)
    {
      float sunPdf;
      vec3 ws = sunSample(p, vec2(random01(rng), random01(rng)), sunPdf);
      vec3 fs = bsdfEval(m, ns, wo, ws);
      if (max(fs.x, max(fs.y, fs.z)) > 0.0f)
      {
        // Radiance E / omega over pdf 1 / omega is the irradiance E; a disk sun is MIS-weighted
        // against BSDF sampling, a delta sun (pdf 0) only reachable here.
        float w = sunPdf > 0.0f && !lastEvent ? powerHeuristic(sunPdf, bsdfPdf(m, ns, wo, ws)) : 1.0f;
        vec3 contribution = w * fs * vec3(p.sunRadiance);
        shadowDirection[shadows] = ws;
        shadowRadiance[shadows] = throughput * contribution;
        ++shadows;
      }
    }

    Material sm = m;
    if (!SVDAG_FEATURE_TRANSMISSION)
      sm.params.z = 0.0f;
    BsdfSample s = bsdfSample(sm, ns, wo, !h.inside, vec3(random01(rng), random01(rng), random01(rng)));
    ends = max(s.weight.x, max(s.weight.y, s.weight.z)) <= 0.0f ||
      (!s.transmitted && !lifted && !(dot(s.direction, n) > 0.0f));
    // The last event: the environment along the BSDF sample, unless something is in the way.
    if (!ends && lastEvent && !s.delta)
    {
      shadowDirection[shadows] = s.direction;
      shadowRadiance[shadows] = throughput * s.weight * environmentRadiance(p, s.direction);
      ++shadows;
      ends = true;
    }
    if (ends)
      continue;
    throughput *= s.weight;
    previousPdf = s.pdf;
    previousDelta = s.delta;
    // A reflected path of a smooth-shaded hit leaves from above the staircase, like the shadow
    // rays.
    o = s.transmitted ? position - epsilon * n : shadowOrigin;
    d = s.direction;
    tmax = 1e30f;
    skipStart = (SVDAG_FEATURE_TRANSMISSION && s.transmitted) || (lifted && !s.transmitted);
    if (bounce >= 2u)
    {
      float q = min(max(throughput.x, max(throughput.y, throughput.z)), 0.95f);
      if (random01(rng) >= q)
        ends = true;
      else
        throughput /= q;
    }
    ++bounce;
  }
  return finiteOrZero(radiance);
}

#ifdef __cplusplus
} // namespace shading
} // namespace svdag
#endif

#endif
