#version 460
// Compiles the shared shading and integrator headers as GLSL (ctest runs glslangValidator on it).
#extension GL_GOOGLE_include_directive : require
layout(local_size_x = 64) in;
layout(std430, binding = 0) readonly buffer Marginal { float marginal[]; };
layout(std430, binding = 1) readonly buffer Conditional { float conditional[]; };
layout(std430, binding = 2) readonly buffer Texels { vec4 texels[]; };
layout(std430, binding = 3) writeonly buffer Out { vec4 results[]; };
#define SVDAG_ENV_MARGINAL(i) marginal[(i)]
#define SVDAG_ENV_CONDITIONAL(i) conditional[(i)]
#define SVDAG_ENV_TEXEL(i) texels[(i)].xyz
#include "svdag_render/Shading.h"
layout(std430, binding = 4) readonly buffer Materials { Material materials[]; };

// The integrator too, with a stand-in for the ray tracing calls (a plane z = 0).
PathHit traceStandIn(vec3 o, vec3 d)
{
  PathHit h;
  h.hit = d.z < 0.0 && o.z > 0.0;
  h.inside = false;
  h.t = h.hit ? -o.z / d.z : 1e30;
  h.label = 0u;
  h.normal = vec3(0.0, 0.0, 1.0);
  return h;
}
#define SVDAG_FEATURE_NEE true
#define SVDAG_FEATURE_ENV_MAP true
#define SVDAG_FEATURE_SUN true
#define SVDAG_FEATURE_EMISSION true
#define SVDAG_FEATURE_TRANSMISSION true
#define SVDAG_FEATURE_PREVIEW false
#define SVDAG_TRACE(hit, origin, direction, tmax, skipStart, anyHit) hit = traceStandIn(origin, direction)
#define SVDAG_MATERIAL(label) materials[(label)]
#include "svdag_render/PathTracer.h"
layout(std430, binding = 5) readonly buffer Params { PathTracerParams params; };

void main()
{
  uint rng = pcgHash(gl_GlobalInvocationID.x);
  Material m = materials[gl_GlobalInvocationID.x];
  vec3 n = vec3(0.0, 0.0, 1.0);
  vec3 wo = normalize(vec3(0.3, 0.1, 0.9));
  BsdfSample s = bsdfSample(m, n, wo, true, vec3(random01(rng), random01(rng), random01(rng)));
  float pdf;
  vec3 d = envSample(vec2(random01(rng), random01(rng)), 16u, 8u, pdf);
  float w = powerHeuristic(pdf, bsdfPdf(m, n, wo, d));
  vec3 path = tracePath(params, vec3(0.0, 0.0, 2.0), normalize(vec3(0.1, 0.2, -1.0)), 1e30, rng);
  results[gl_GlobalInvocationID.x + 1u] = vec4(path, 1.0);
  results[gl_GlobalInvocationID.x] =
    vec4(finiteOrZero(s.weight + w * bsdfEval(m, n, wo, d) * envRadiance(d, 16u, 8u) / pdf), envPdf(d, 16u, 8u));
}
