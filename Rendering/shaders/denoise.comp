#version 460
// The denoiser (DenoiseLayout.h says what it computes): the prepass, or one a-trous iteration.
#extension GL_GOOGLE_include_directive : require
#include "Common.glsl"
#include "svdag_render/DenoiseLayout.h"

layout(local_size_x = SVDAG_DENOISE_GROUP_SIZE, local_size_y = SVDAG_DENOISE_GROUP_SIZE) in;

layout(push_constant) uniform DenoisePush
{
  uvec2 params; // the address of the DenoiseParams
} push;

layout(buffer_reference, std430, buffer_reference_align = 4) readonly buffer DenoiseUints
{
  uint v[];
};
layout(buffer_reference, std430, buffer_reference_align = 4) buffer DenoiseFloats
{
  float v[];
};
layout(buffer_reference, std430, buffer_reference_align = 16) buffer DenoiseVec4s
{
  vec4 v[];
};
// Per pixel: label + 1, packed shading normal, depth bits, variance bits.
layout(buffer_reference, std430, buffer_reference_align = 16) buffer DenoiseGuides
{
  uvec4 v[];
};
// Per pixel: the edge coverage record, SVDAG_COVERAGE_RECORD_VEC4S 16-byte words (GpuLayout.h).
layout(buffer_reference, std430, buffer_reference_align = 16) readonly buffer DenoiseUvec4s
{
  uvec4 v[];
};
layout(buffer_reference, std430, buffer_reference_align = 16) readonly buffer DenoiseRecordVec4s
{
  vec4 v[];
};
layout(buffer_reference, std430, buffer_reference_align = 4) writeonly buffer DenoiseColor
{
  uint v[];
};

const vec3 LUMINANCE = vec3(0.2126, 0.7152, 0.0722);

DenoiseParams p;

// A unit normal in 32 bits (octahedral, two snorm16), so that a tap reads its guides in one load.
uint packNormal(vec3 n)
{
  return packSnorm2x16(svdagOctahedral(n));
}

vec3 unpackNormal(uint bits)
{
  vec2 o = unpackSnorm2x16(bits);
  vec3 n = vec3(o, 1.0 - abs(o.x) - abs(o.y));
  if (n.z < 0.0)
    n.xy = (1.0 - abs(n.yx)) * vec2(n.x >= 0.0 ? 1.0 : -1.0, n.y >= 0.0 ? 1.0 : -1.0);
  float length2 = dot(n, n);
  return length2 > 0.0 ? n * inversesqrt(length2) : n;
}

// The world position of pixel (x, y)'s pixel-center hit at distance t.
vec3 position(int x, int y, float t)
{
  float u = 2.0 * (float(x) + 0.5) / float(p.sizes.x) - 1.0;
  float v = 2.0 * (float(y) + 0.5) / float(p.sizes.y) - 1.0;
  vec3 origin = p.rayOrigin.xyz + u * p.rayOriginU.xyz + v * p.rayOriginV.xyz;
  vec3 span = p.rayDirection.xyz + u * p.rayDirectionU.xyz + v * p.rayDirectionV.xyz;
  return origin + t * normalize(span);
}

// Pixel (x, y)'s guides (label, packed shading normal, depth bits) and variance estimate.
void prepare(uint x, uint y)
{
  uint width = p.sizes.x, height = p.sizes.y;
  uint i = x + width * y;
  DenoiseUints labels = DenoiseUints(p.guides.xy);
  DenoiseVec4s colors = DenoiseVec4s(p.colors.xy);
  uint label = labels.v[i];
  float variance = 0.0;
  vec3 n = vec3(0.0);
  float t = 0.0;
  bool edge = false;
  if (label != 0u)
  {
    uint samples = max(p.samples.x, 1u);
    // A pixel on a label edge: its samples cover two labels, and their mean (the edge's
    // antialiasing) is what the filter would remove. Left as it is once samples accumulate
    // (variance 0: unfiltered), filtered only while a few samples are all noise; never a tap of
    // another pixel's filter, so no radiance of a neighbouring label reaches the inside of one.
    for (int dy = -1; dy <= 1; ++dy)
    {
      for (int dx = -1; dx <= 1; ++dx)
      {
        ivec2 q = ivec2(x, y) + ivec2(dx, dy);
        if (q.x >= 0 && q.y >= 0 && q.x < int(width) && q.y < int(height) &&
          labels.v[uint(q.x) + width * uint(q.y)] != label)
          edge = true;
      }
    }
    if (samples >= SVDAG_DENOISE_TEMPORAL_SAMPLES)
      variance = edge ? 0.0 : DenoiseFloats(p.guides2.zw).v[i];
    else
    {
      float sum = 0.0, squares = 0.0, count = 0.0;
      for (int dy = -2; dy <= 2; ++dy)
      {
        for (int dx = -2; dx <= 2; ++dx)
        {
          ivec2 q = ivec2(x, y) + ivec2(dx, dy);
          if (q.x < 0 || q.y < 0 || q.x >= int(width) || q.y >= int(height))
            continue;
          uint j = uint(q.x) + width * uint(q.y);
          if (labels.v[j] != label)
            continue;
          float l = dot(colors.v[j].rgb, LUMINANCE);
          sum += l;
          squares += l * l;
          count += 1.0;
        }
      }
      float mean = sum / count;
      variance = max(squares / count - mean * mean, 0.0) / float(samples);
    }
    DenoiseFloats normals = DenoiseFloats(p.guides2.xy);
    n = vec3(normals.v[3u * i], normals.v[3u * i + 1u], normals.v[3u * i + 2u]);
    t = DenoiseFloats(p.guides.zw).v[i];
  }
  // The edge flag rides in the depth's sign bit (depths are never negative).
  DenoiseGuides(p.variances.zw).v[i] =
    uvec4(label, packNormal(n), floatBitsToUint(edge ? -t : t), floatBitsToUint(variance));
}

// An edge pixel's color from its coverage record (GpuLayout.h): the colors of the surfaces (label
// index + 1, 0: background; entry face) its sub-pixel rays hit, weighted by how many rays hit each.
// A surface's color is the mean of the pixels in the 7x7 window that show it, in this
// iteration's input (wider windows served membranes' thin strips better, narrower ones rounded
// cells' staircases: bench/README.md). Preferred are pixels of its label and face that are not on
// a label edge (an edge pixel's value may mix labels once samples accumulate), then edge pixels of
// them (a thin part, a groove's wall), then its label's pixels whatever their face; background
// pixels are all exact. In a one-sample image an edge pixel's value is its pixel-center sample's,
// of its own label only, and nearest to the edge: there edge pixels count as much as the others
// (preferring pixels away from the edge brightened creases, whose occlusion those do not see).
// `own` (the pixel's value) stands for a surface of its own label where its label is not in the
// window. On a label edge the coverage rays were whole paths, on a crease within a label its corner
// rays (GpuLayout.h), whose mean is the surface's radiance at the edge itself but noisy, where the
// window's mean is smooth but biased by how fast shading changes at the edge (occlusion at a
// crease): a surface's color is then the mean of both, the window's estimate counting as
// SVDAG_DENOISE_WINDOW_SAMPLES paths, or the paths' mean alone where the window shows none of the
// surface. The estimate gives way to the pixel's own mean as samples accumulate (weight G / (G +
// samples), G the coverage rays), so that the accumulating image still converges to the path
// tracer's. The window is read once for all the record's surfaces.
vec4 resolveEdge(uint x, uint y, uvec4 labels, uvec4 keys, uint record, uint ownLabel, vec4 own)
{
  uint width = p.sizes.x, height = p.sizes.y;
  DenoiseVec4s colors = DenoiseVec4s(p.colors.xy);
  DenoiseGuides guides = DenoiseGuides(p.variances.xy);
  DenoiseFloats normals = DenoiseFloats(p.guides2.xy);
  uint faces = 3u * width * height; // where the entry face normals start (GpuLayout.h)
  // Per surface k of the record: the most preferred kind of pixel seen so far (4: none; the
  // preference order above) and the sum and count of that kind's pixels, in window order. Kept
  // per surface rather than per surface and kind: a local array indexed by a kind computed per
  // tap lives in memory on a CPU driver (lavapipe), and the loop over surfaces unrolls.
  uvec4 bestKinds = uvec4(4u);
  vec4 sums[SVDAG_COVERAGE_SLOTS];
  vec4 weights = vec4(0.0);
  for (uint k = 0u; k < SVDAG_COVERAGE_SLOTS; ++k)
    sums[k] = vec4(0.0);
  for (int dy = -3; dy <= 3; ++dy)
  {
    for (int dx = -3; dx <= 3; ++dx)
    {
      ivec2 q = ivec2(x, y) + ivec2(dx, dy);
      if (q.x < 0 || q.y < 0 || q.x >= int(width) || q.y >= int(height))
        continue;
      uint j = uint(q.x) + width * uint(q.y);
      uvec4 gq = guides.v[j];
      if (all(notEqual(labels, uvec4(gq.x))))
        continue;
      uint faceBits = 0u;
      uint edge = (gq.z & 0x80000000u) != 0u && p.samples.x > 1u ? 1u : 0u;
      if (gq.x != 0u)
        faceBits = svdagPackDirection8(vec3(normals.v[faces + 3u * j],
                     normals.v[faces + 3u * j + 1u], normals.v[faces + 3u * j + 2u])) << 16u;
      vec4 c = colors.v[j];
      for (uint k = 0u; k < SVDAG_COVERAGE_SLOTS; ++k)
      {
        if (labels[k] != gq.x || (keys[k] & 0xFFu) == 0u)
          continue;
        uint kind = gq.x == 0u ? 0u : (faceBits == (keys[k] & 0xFFFF0000u) ? 0u : 2u) + edge;
        if (kind < bestKinds[k])
        {
          bestKinds[k] = kind;
          sums[k] = c;
          weights[k] = 1.0;
        }
        else if (kind == bestKinds[k])
        {
          sums[k] += c;
          weights[k] += 1.0;
        }
      }
    }
  }
  DenoiseRecordVec4s paths = DenoiseRecordVec4s(p.geometry.xy);
  vec4 sum = vec4(0.0);
  float counted = 0.0;
  for (uint k = 0u; k < SVDAG_COVERAGE_SLOTS; ++k)
  {
    float n = float(keys[k] & 0xFFu);
    if (n == 0.0)
      continue;
    bool found = weights[k] > 0.0;
    vec4 c = found ? sums[k] / weights[k] : own;
    vec4 path = paths.v[record + 2u + k];
    if (path.w > 0.0 && labels[k] != 0u)
    {
      float window = found ? float(SVDAG_DENOISE_WINDOW_SAMPLES) : 0.0;
      c = vec4((path.rgb + window * c.rgb) / (path.w + window), 1.0);
      found = true;
    }
    if (found || labels[k] == ownLabel)
    {
      sum += n * c;
      counted += n;
    }
  }
  if (counted == 0.0)
    return own;
  float rays = float(SVDAG_COVERAGE_GRID * SVDAG_COVERAGE_GRID);
  return mix(own, sum / counted, rays / (rays + float(max(p.samples.x, 1u))));
}

// One a-trous iteration at pixel (x, y).
void filterPixel(uint x, uint y)
{
  uint width = p.sizes.x, height = p.sizes.y;
  int step = int(p.sizes.w);
  uint i = x + width * y;
  DenoiseVec4s colors = DenoiseVec4s(p.colors.xy);
  DenoiseGuides guides = DenoiseGuides(p.variances.xy);
  vec4 center = colors.v[i];
  uvec4 g = guides.v[i];
  float centerVariance = uintBitsToFloat(g.w);
  vec4 result = center;
  float resultVariance = centerVariance;
  if (g.x != 0u && centerVariance > 0.0)
  {
    vec3 n = unpackNormal(g.y);
    // The tangent plane n . x = plane through the center's hit.
    float plane = dot(n, position(int(x), int(y), abs(uintBitsToFloat(g.z))));
    float luma = dot(center.rgb, LUMINANCE);
    float lumaScale = 1.0 / (p.weights.x * sqrt(centerVariance) + 1e-10);
    float planeScale = 1.0 / p.weights.z;
    vec4 sum = vec4(0.0);
    float weights = 0.0, varianceSum = 0.0;
    for (int dy = -1; dy <= 1; ++dy)
    {
      for (int dx = -1; dx <= 1; ++dx)
      {
        ivec2 q = ivec2(x, y) + step * ivec2(dx, dy);
        if (q.x < 0 || q.y < 0 || q.x >= int(width) || q.y >= int(height))
          continue;
        uint j = uint(q.x) + width * uint(q.y);
        uvec4 gq = guides.v[j];
        // Never another label. Label edge pixels (the sign bit of the depth): once samples
        // accumulate, no other pixel's tap (their samples may have hit the neighbouring label);
        // in a one-sample image (through pixel centers: of their own labels only) taps, and an
        // edge pixel's only taps, so that an edge is filtered along itself (a crease's
        // occlusion darkens its edge pixels, which the pixels beside them do not share).
        bool tapEdge = (gq.z & 0x80000000u) != 0u;
        if (gq.x != g.x ||
          (j != i && (p.samples.x > 1u ? tapEdge : (g.z & 0x80000000u) != 0u && !tapEdge)))
          continue;
        vec4 c = colors.v[j];
        // The 3x3 kernel (1/4, 1/2, 1/4) in each direction.
        float w = (dx == 0 ? 0.5 : 0.25) * (dy == 0 ? 0.5 : 0.25);
        if (j != i)
        {
          // facing^32 by squaring, and one exp for the plane and luminance terms: the filter's
          // cost is in these taps.
          float facing = max(dot(n, unpackNormal(gq.y)), 0.0);
          for (uint k = 0u; k < SVDAG_DENOISE_NORMAL_POWER_LOG2; ++k)
            facing *= facing;
          float distance = abs(dot(n, position(q.x, q.y, abs(uintBitsToFloat(gq.z)))) - plane);
          w *= facing * exp(-distance * planeScale -
            abs(dot(c.rgb, LUMINANCE) - luma) * lumaScale);
        }
        sum += w * c;
        weights += w;
        varianceSum += w * w * uintBitsToFloat(gq.w);
      }
    }
    // The center's own weight is never 0, so weights > 0.
    result = sum / weights;
    resultVariance = varianceSum / (weights * weights);
  }
  // The last iteration resolves edge pixels (label edges and steps between faces, background
  // ones too) from their coverage.
  if (p.samples.y != 0u && (p.geometry.x != 0u || p.geometry.y != 0u))
  {
    DenoiseUvec4s records = DenoiseUvec4s(p.geometry.xy);
    uint record = SVDAG_COVERAGE_RECORD_VEC4S * i;
    uvec4 keys = records.v[record + 1u];
    if (keys != uvec4(0u))
      result = resolveEdge(x, y, records.v[record], keys, record, g.x, result);
  }
  DenoiseVec4s(p.colors.zw).v[i] = result;
  DenoiseGuides(p.variances.zw).v[i] = uvec4(g.xyz, floatBitsToUint(resultVariance));
  if (p.samples.y != 0u)
    DenoiseColor(p.geometry.zw).v[i] = svdagDisplayColor(result, p.weights.w);
}

void main()
{
  p = DenoiseParams(push.params);
  uvec2 pixel = gl_GlobalInvocationID.xy;
  if (pixel.x >= p.sizes.x || pixel.y >= p.sizes.y)
    return;
  if (p.sizes.z == SVDAG_DENOISE_PASS_PREPARE)
    prepare(pixel.x, pixel.y);
  else
    filterPixel(pixel.x, pixel.y);
}
