#version 460
// Compile check: Layout.h and Traversal.h must be valid GLSL. Storage is plain SSBOs here; the
// renderer may map the same macros onto buffer references instead.
#extension GL_GOOGLE_include_directive : require

layout(local_size_x = 64) in;

layout(std430, binding = 0) readonly buffer RootStream { uint rootWords[]; };
layout(std430, binding = 1) readonly buffer MidStream { uint midWords[]; };
layout(std430, binding = 2) readonly buffer LeafMasks { uvec2 leafMasks[]; };
struct CheckBlock
{
  uvec4 lo;   // xyz: inclusive cell-local lower bounds
  uvec4 hi;   // xyz: inclusive cell-local upper bounds, w: root reference
};
layout(std430, binding = 3) readonly buffer Blocks { CheckBlock blocks[]; };
struct CheckRay
{
  vec4 origin; // xyz: cell-local origin, w: tmin
  vec4 dir;    // xyz: direction, w: tmax
};
layout(std430, binding = 4) readonly buffer Rays { CheckRay rays[]; };
layout(std430, binding = 5) writeonly buffer Hits { vec4 hits[]; };
// entryOnly: non-zero for the entry-only mode (Traversal.h), as the transmission hit group uses it.
layout(push_constant) uniform Widths { uint midRefBits; uint leafRefBits; uint lod; uint entryOnly; } widths;

#define SVDAG_WORD(stream, i) stream[i]
#define SVDAG_ROOT_STREAM rootWords
#define SVDAG_MID_STREAM midWords
#define SVDAG_LEAF(i) leafMasks[i]
#include "svdag/Layout.h"
#include "svdag/Traversal.h"

void main()
{
  uint i = gl_GlobalInvocationID.x;
  CheckBlock b = blocks[i];
  CheckRay r = rays[i];
  SvdagBlockHit h = svdagIntersectBlock(b.lo.xyz, b.hi.xyz, b.hi.w, widths.midRefBits,
    widths.leafRefBits, r.origin.xyz, r.dir.xyz, r.origin.w, r.dir.w, widths.lod, widths.entryOnly != 0u);
  hits[i] = h.hit ? vec4(vec3(h.normal), h.t) : vec4(0.0, 0.0, 0.0, -1.0);
}
