#version 460
// Compiles the shared shading header as GLSL (ctest runs glslangValidator on this file).
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
  results[gl_GlobalInvocationID.x] =
    vec4(finiteOrZero(s.weight + w * bsdfEval(m, n, wo, d) * envRadiance(d, 16u, 8u) / pdf), envPdf(d, 16u, 8u));
}
