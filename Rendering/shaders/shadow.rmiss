#version 460
// An occlusion ray that reaches its end without hitting a block: not occluded. (Occlusion rays
// skip the closest-hit shader and stop at the first hit, so a hit leaves the payload at 1.)
#extension GL_EXT_ray_tracing : require
#extension GL_GOOGLE_include_directive : require
#include "Common.glsl"

layout(location = SVDAG_PAYLOAD_SHADOW) rayPayloadInEXT uint occluded;

void main()
{
  occluded = 0u;
}
