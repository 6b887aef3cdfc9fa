#version 460
// A closest-hit query (camera ray or path segment) that hits no block: background (label 0).
#extension GL_EXT_ray_tracing : require
#extension GL_GOOGLE_include_directive : require
#include "Common.glsl"

layout(location = SVDAG_PAYLOAD_CLOSEST) rayPayloadInEXT SvdagPayload payload;

void main()
{
  payload.label = 0u;
  payload.t = SVDAG_DEPTH_MISS;
  payload.normal = vec3(0.0);
}
