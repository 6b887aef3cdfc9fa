#version 460
// The nearest block hit -> the payload (HitPayload.glsl, shared with the compute backend).
#extension GL_EXT_ray_tracing : require
#extension GL_GOOGLE_include_directive : require
#include "Common.glsl"
#include "Streams.glsl"
#include "HitPayload.glsl"

layout(location = SVDAG_PAYLOAD_CLOSEST) rayPayloadInEXT SvdagPayload payload;
hitAttributeEXT SvdagHitAttributes attributes;

void main()
{
  svdagBindStreams();
  // The hit point in the block's cell-local coordinates, as block.rint anchors the ray.
  vec3 origin = gl_ObjectRayOriginEXT - vec3(svdagCellCoord(attributes.cell) * CELL_SIZE);
  payload = svdagHitPayload(attributes.label, gl_HitTEXT, attributes.normal, attributes.block,
    origin + gl_HitTEXT * gl_ObjectRayDirectionEXT, gl_ObjectRayDirectionEXT,
    mat3(gl_WorldToObjectEXT));
}
