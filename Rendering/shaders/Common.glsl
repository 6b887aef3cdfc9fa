// Declarations shared by the renderer's ray tracing shaders: the frame uniforms (GpuLayout.h),
// buffer-reference types for the volume streams and the outputs, the ray payload and the hit
// attributes.
#ifndef SVDAG_RENDER_COMMON_GLSL
#define SVDAG_RENDER_COMMON_GLSL

#extension GL_EXT_buffer_reference : require
#extension GL_EXT_buffer_reference_uvec2 : require

#include "svdag_render/GpuLayout.h"

layout(buffer_reference, std430, buffer_reference_align = 4) readonly buffer SvdagWords
{
  uint w[];
};
layout(buffer_reference, std430, buffer_reference_align = 8) readonly buffer SvdagAddresses
{
  uvec2 a[]; // device addresses (low word, high word)
};
layout(buffer_reference, std430, buffer_reference_align = 8) readonly buffer SvdagLeafMasks
{
  uvec2 m[]; // (bits 0..31, bits 32..63)
};
layout(buffer_reference, std430, buffer_reference_align = 4) writeonly buffer SvdagUintOutput
{
  uint v[];
};
layout(buffer_reference, std430, buffer_reference_align = 4) writeonly buffer SvdagFloatOutput
{
  float v[];
};
layout(buffer_reference, std430, buffer_reference_align = 16) writeonly buffer SvdagVec4Output
{
  vec4 v[];
};
layout(buffer_reference, std430, buffer_reference_align = 16) writeonly buffer SvdagUvec4Output
{
  uvec4 v[];
};

// The octahedral map of a unit vector into [-1, 1]^2 ((0, 0) for the zero vector), which the
// packings below quantize.
vec2 svdagOctahedral(vec3 n)
{
  vec2 o = n.xy / (abs(n.x) + abs(n.y) + abs(n.z) + 1e-20);
  if (n.z < 0.0)
    o = (1.0 - abs(o.yx)) * vec2(o.x >= 0.0 ? 1.0 : -1.0, o.y >= 0.0 ? 1.0 : -1.0);
  return o;
}

// A unit vector (or 0) in 16 bits: octahedral, two snorm8 (the coverage records, GpuLayout.h).
uint svdagPackDirection8(vec3 n)
{
  return packSnorm4x8(vec4(svdagOctahedral(n), 0.0, 0.0)) & 0xFFFFu;
}

layout(buffer_reference, std430, buffer_reference_align = 4) readonly buffer SvdagFloats
{
  float v[];
};
layout(buffer_reference, std430, buffer_reference_align = 16) readonly buffer SvdagVec4s
{
  vec4 v[];
};
// Read and written by the same invocation only (one pixel's accumulated sums).
layout(buffer_reference, std430, buffer_reference_align = 4) buffer SvdagFloatAccumulation
{
  float v[];
};
// Read and written by the same invocation only (one pixel's accumulated sums).
layout(buffer_reference, std430, buffer_reference_align = 16) buffer SvdagVec4Accumulation
{
  vec4 v[];
};

// Closest-hit -> raygen. label: label index + 1 (0: miss); t: world distance; normal: world
// entry face; shading.xyz: world shading normal (the face normal unless smooth shading,
// GpuLayout.h), shading.w: the world distance along it that shadow rays start at (PathHit.lift).
struct SvdagPayload
{
  vec3 normal;
  float t;
  uint label;
  vec4 shading;
};

// Intersection -> closest-hit (24 bytes; the limit is 32). normal: object-space entry face;
// block: the block index of a voxel-level hit (smooth shading reads its neighbour table),
// SVDAG_NO_BLOCK for block and leaf LOD hits (shaded with the face normal); cell: its cell index.
struct SvdagHitAttributes
{
  vec3 normal;
  uint label;
  uint block;
  uint cell;
};

// The color output's encoding (GpuLayout.h): the sRGB transfer function, then RGBA8 with R in
// the lowest byte.
float srgbEncode(float linear)
{
  float c = clamp(linear, 0.0, 1.0);
  return c <= 0.0031308 ? 12.92 * c : 1.055 * pow(c, 1.0 / 2.4) - 0.055;
}

uint packRGBA8(vec4 srgb)
{
  uvec4 b = uvec4(clamp(srgb, 0.0, 1.0) * 255.0 + 0.5);
  return b.r | (b.g << 8u) | (b.b << 16u) | (b.a << 24u);
}

// The color output of a pixel's linear RGBA (tone curve, sRGB, RGBA8).
uint svdagDisplayColor(vec4 hdr, float exposure)
{
  vec3 display = svdagToneMap(hdr.rgb, exposure);
  return packRGBA8(vec4(srgbEncode(display.r), srgbEncode(display.g), srgbEncode(display.b), hdr.a));
}

#endif
