#version 460
// Guided upsampling of a reduced trace (UpsampleLayout.h says what it computes).
#extension GL_GOOGLE_include_directive : require
#include "Common.glsl"
#include "svdag_render/UpsampleLayout.h"

layout(local_size_x = SVDAG_UPSAMPLE_GROUP_SIZE, local_size_y = SVDAG_UPSAMPLE_GROUP_SIZE) in;

layout(push_constant) uniform UpsamplePush
{
  uvec2 params; // the address of the UpsampleParams
} push;

layout(buffer_reference, std430, buffer_reference_align = 4) readonly buffer UpsampleUints
{
  uint v[];
};
layout(buffer_reference, std430, buffer_reference_align = 4) buffer UpsampleFloats
{
  float v[];
};
layout(buffer_reference, std430, buffer_reference_align = 16) buffer UpsampleVec4s
{
  vec4 v[];
};
layout(buffer_reference, std430, buffer_reference_align = 4) writeonly buffer UpsampleColor
{
  uint v[];
};

void main()
{
  UpsampleParams p = UpsampleParams(push.params);
  uvec2 pixel = gl_GlobalInvocationID.xy;
  if (pixel.x >= p.sizes.x || pixel.y >= p.sizes.y)
    return;
  uint i = pixel.x + p.sizes.x * pixel.y;
  int width = int(p.sizes.z), height = int(p.sizes.w);
  float r = p.weights.x;
  UpsampleUints labels = UpsampleUints(p.reducedGuides.xy);
  UpsampleFloats depths = UpsampleFloats(p.reducedGuides.zw);
  UpsampleVec4s colors = UpsampleVec4s(p.reducedColors.xy);
  uint label = UpsampleUints(p.guides.xy).v[i];
  float depth = UpsampleFloats(p.guides.zw).v[i];

  // The reduced pixel under p, and p's position in reduced pixel centers.
  ivec2 under = min(ivec2(vec2(pixel) / r), ivec2(width - 1, height - 1));
  vec4 result = colors.v[under.x + width * under.y];
  if (label == 0u)
    result = p.background;
  else
  {
    vec2 at = (vec2(pixel) + 0.5) / r - 0.5;
    ivec2 base = ivec2(floor(at));
    vec2 f = at - vec2(base);
    vec4 sum = vec4(0.0);
    float weights = 0.0;
    for (int dy = 0; dy <= 1; ++dy)
    {
      for (int dx = 0; dx <= 1; ++dx)
      {
        ivec2 q = clamp(base + ivec2(dx, dy), ivec2(0), ivec2(width - 1, height - 1));
        uint j = uint(q.x + width * q.y);
        if (labels.v[j] != label)
          continue;
        float w = (dx == 0 ? 1.0 - f.x : f.x) * (dy == 0 ? 1.0 - f.y : f.y);
        w = max(w, 1e-4) / (1.0 + abs(depth - depths.v[j]) / p.weights.y);
        sum += w * colors.v[j];
        weights += w;
      }
    }
    if (weights > 0.0)
      result = sum / weights;
    else
    {
      // The nearest same-label pixel around p: by depth difference, then by distance.
      float best = 3.4e38;
      for (int dy = -SVDAG_UPSAMPLE_SEARCH_RADIUS; dy <= SVDAG_UPSAMPLE_SEARCH_RADIUS; ++dy)
      {
        for (int dx = -SVDAG_UPSAMPLE_SEARCH_RADIUS; dx <= SVDAG_UPSAMPLE_SEARCH_RADIUS; ++dx)
        {
          ivec2 q = under + ivec2(dx, dy);
          if (q.x < 0 || q.y < 0 || q.x >= width || q.y >= height)
            continue;
          uint j = uint(q.x + width * q.y);
          if (labels.v[j] != label)
            continue;
          float score = abs(depth - depths.v[j]) / p.weights.y + 1e-3 * float(dx * dx + dy * dy);
          if (score < best)
          {
            best = score;
            result = colors.v[j];
          }
        }
      }
    }
  }
  UpsampleVec4s(p.hdr.xy).v[i] = result;
  UpsampleColor(p.hdr.zw).v[i] = svdagDisplayColor(result, p.weights.z);
  UpsampleFloats(p.variance.xy).v[i] =
    UpsampleFloats(p.reducedColors.zw).v[under.x + width * under.y];
}
