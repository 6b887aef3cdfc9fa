#version 460
// The nearest block hit: label index + 1, world distance and world-space face normal.
#extension GL_EXT_ray_tracing : require
#extension GL_GOOGLE_include_directive : require
#include "Common.glsl"

layout(location = SVDAG_PAYLOAD_CLOSEST) rayPayloadInEXT SvdagPayload payload;
hitAttributeEXT SvdagHitAttributes attributes;

void main()
{
  payload.label = attributes.label + 1u;
  // The world ray's direction has unit length and t is shared by the object-space ray (the
  // instance transform is affine and the direction is not renormalised): t is the distance.
  payload.t = gl_HitTEXT;
  // Normals transform with the inverse transpose of object-to-world, i.e. the transpose of
  // world-to-object: n_world = transpose(W) * n = n * W.
  vec3 n = attributes.normal * mat3(gl_WorldToObjectEXT);
  payload.normal = dot(n, n) > 0.0 ? normalize(n) : vec3(0.0);
}
