/* The data the renderer's shaders share with the host, defined once for C++ (with GLM) and GLSL.
 *
 * Like Module/core/svdag/Layout.h this file is written in the common subset of both languages.
 * The one uniform block holds only vec4 / uvec4 members, so its std140 layout in GLSL is exactly
 * the C++ struct's layout (16-byte members, no padding rules to get wrong). Buffers are reached
 * through buffer device addresses (GL_EXT_buffer_reference): a driver may cap descriptor ranges
 * (lavapipe: 128 MiB), addresses are not capped. Each address is a uvec2 (low, high word), two per
 * uvec4, so GLSL needs no 64-bit integers (GL_EXT_buffer_reference_uvec2).
 *
 * Primary rays (the pixel-center convention; tests generate the same rays):
 *   pixel (x, y), 0 <= x < width, 0 <= y < height, y = 0 is the BOTTOM row (VTK image order), its
 *   outputs at index x + width * y, at image coordinates
 *       u = 2 * (x + 0.5) / width - 1,   v = 2 * (y + 0.5) / height - 1
 *   Its ray (Camera.h's ViewRays) starts at rayOrigin + u * rayOriginU + v * rayOriginV with the
 *   unit direction of span = rayDirection + u * rayDirectionU + v * rayDirectionV, from t = 0 to
 *   |span| if rayOrigin.w == 1 (a far plane), else unbounded, and to at most the pixel's ray limit
 *   when rayLimits.xy is not 0 (an opaque surface in front). Since the direction has unit length,
 *   t is the distance in world units. A pinhole camera (VTK semantics: unit forward F, right
 *   R = normalize(cross(F, viewUp)), up U = cross(R, F), h = tan(viewAngle / 2), aspect = width /
 *   height) has origin = its position, span = F + u * h * aspect * R + v * h * U.
 *   (On the GPU, world coordinates are shifted by a reference point near the volume, Scene.h;
 *   distances and directions do not change.)
 *
 * Outputs, per pixel:
 *   label   uint32  label index + 1, 0 where the ray hits nothing (background)
 *   depth   float   distance from the ray origin along the ray (world units); SVDAG_DEPTH_MISS where
 *                   label == 0. Never NaN or inf.
 *   normal  3 float world-space unit shading normal: the entry face's, or with smooth shading
 *                   the smooth estimate (SmoothNormal.h); (0, 0, 0) on a miss and where the
 *                   camera is inside the hit voxel/box (no entry face); on a cut face
 *                   (Clipping.h) the clipping plane's outward normal. The same buffer then holds,
 *                   from float 3 * width * height on, the entry face normal of every pixel.
 *   hdr     4 float linear RGBA: the mean of all samples accumulated since the last reset (below)
 *   color   RGBA8   the tone-mapped display color, R in the lowest byte (bytes R, G, B, A in memory):
 *                   per channel x = exposure * hdr, then Reinhard's curve x / (1 + x), then the
 *                   sRGB transfer function; alpha = hdr.a
 *   variance float  the variance of the accumulated mean's luminance (luminance of a sample:
 *                   0.2126 r + 0.7152 g + 0.0722 b): (sum of squares / n - mean^2) / (n - 1)
 *                   over the n accumulated samples; 0 while n < 2
 *
 * Path tracing (camera.rgen, Shading.h, PathTracer.h): every pass adds sampling.y samples per
 * pixel, each a camera path through a uniformly jittered point of the pixel, except the first
 * sample of an accumulation, which goes through the pixel center and reuses the pixel-center
 * ray's hit (a restarting frame traces its primary rays once). A sample whose camera
 * ray hits nothing is the background (frame.background, alpha included): the environment lights
 * the scene but is not what the camera sees behind it, like VTK's renderer background. A hit
 * counts alpha 1. The sums live in the accumulation buffer (rgb + alpha sum per pixel); sampling.x
 * samples were accumulated before this pass (0: overwrite). Label, depth and normal come from the
 * un-jittered pixel-center ray (traced when sampling.x == 0; the image does not change while
 * samples accumulate). Random numbers: pcgHash of (pixel, global sample index, seed) per sample.
 */
#ifndef SVDAG_RENDER_GPU_LAYOUT_H
#define SVDAG_RENDER_GPU_LAYOUT_H

// SVDAG_CLIP_MAX_SLOTS: the size of the clipping plane array below.
#include "svdag/Clipping.h"

#ifdef __cplusplus
#include <cstdint>
#include <glm/glm.hpp>
namespace svdag
{
namespace render
{
namespace gpu
{
using glm::uvec4;
using glm::vec3;
using glm::vec4;
typedef uint32_t uint;
#define SVDAG_GPU_CONST constexpr uint
#define SVDAG_GPU_FN inline
#define SVDAG_UNIFORMS_BEGIN(Name) struct Name {
#define SVDAG_UNIFORMS_END(instance) };
#else
#define SVDAG_GPU_CONST const uint
#define SVDAG_GPU_FN
#define SVDAG_UNIFORMS_BEGIN(Name)                                                                 \
  layout(std140, set = 0, binding = SVDAG_BINDING_FRAME) uniform Name {
#define SVDAG_UNIFORMS_END(instance) } instance;
#endif

/* Miss shaders (index into the miss region) and ray payload locations. */
#define SVDAG_MISS_CLOSEST 0
#define SVDAG_MISS_SHADOW 1
#define SVDAG_PAYLOAD_CLOSEST 0
#define SVDAG_PAYLOAD_SHADOW 1

/* Specialization constant ids of the path tracer's feature switches (PathTracer.h). */
#define SVDAG_CONSTANT_NEE 0
#define SVDAG_CONSTANT_ENV_MAP 1
#define SVDAG_CONSTANT_SUN 2
#define SVDAG_CONSTANT_EMISSION 3
#define SVDAG_CONSTANT_TRANSMISSION 4
#define SVDAG_CONSTANT_PREVIEW 5
#define SVDAG_CONSTANT_SMOOTH_SHADING 6
#define SVDAG_CONSTANT_CLIPPING 7
/* The compute backend's step statistics (camera.comp; the ray tracing shaders have none). */
#define SVDAG_CONSTANT_STEP_STATISTICS 8
#define SVDAG_CONSTANT_COUNT 9

/* The compute backend's workgroup: SVDAG_COMPUTE_GROUP_SIZE^2 pixels (camera.comp). */
#define SVDAG_COMPUTE_GROUP_SIZE 8

/* Descriptor set 0 (the compute backend has no TLAS binding). */
#define SVDAG_BINDING_TLAS 0
#define SVDAG_BINDING_FRAME 1

/* Level of detail (frame.image.z): svdag::render::Lod's values, and BLOCK, LEAF, VOXEL equal
 * Traversal.h's SVDAG_LOD_* (static_asserts in RenderSettings.cpp); AUTO picks
 * one per ray from the projected size of a voxel at the block's entry distance. */
SVDAG_GPU_CONST SVDAG_RENDER_LOD_BLOCK = 0u;
SVDAG_GPU_CONST SVDAG_RENDER_LOD_LEAF = 1u;
SVDAG_GPU_CONST SVDAG_RENDER_LOD_VOXEL = 2u;
SVDAG_GPU_CONST SVDAG_RENDER_LOD_AUTO = 3u;

/* Shading normal (frame.image.w): the entry face's, or SmoothNormal.h's estimate; the values of
 * svdag::render::Shading (static_assert in RenderSettings.cpp). */
SVDAG_GPU_CONST SVDAG_SHADING_VOXEL = 0u;
SVDAG_GPU_CONST SVDAG_SHADING_SMOOTH = 1u;

/* Depth written where a ray hits nothing (FLT_MAX; finite, so no inf ever reaches an output). */
#define SVDAG_DEPTH_MISS 3.402823466e38f

/* Edge coverage, for the denoiser (DenoiseLayout.h). One sample per pixel goes through the pixel
 * center, so a pixel on an edge shows one surface where the image should show a blend. With the
 * denoiser on, the first full-resolution pass of an accumulation is followed by a second dispatch
 * of the trace with coverage.z = 1: every pixel whose pixel-center surface (label and entry face)
 * differs from one of its 8 neighbours' (a label edge, or a step of a voxel staircase) traces
 * SVDAG_COVERAGE_GRID^2 camera rays through the centers of a grid of as many sub-pixels (clipping,
 * hidden labels and ray limits as for any camera ray) and counts the surfaces they hit: a surface
 * is a label and an entry face (a groove's walls and floor are lit unlike the face around them). On
 * a label edge (a pixel-center label that differs from one of its 8 neighbours') each of these rays
 * is a whole camera path (the frame's bounces, next-event estimation, sun), so that the denoiser
 * has samples of every surface's radiance at the edge itself, where shading changes fastest
 * (occlusion at a crease). On a crease within a label (a step whose two faces meet concave: either
 * pixel-center hit lies in front of the other's face plane) the grid's corner rays are whole paths
 * (SVDAG_COVERAGE_CORNERS, below), the others first hits; on a convex step, first hits only. Its
 * record is SVDAG_COVERAGE_RECORD_VEC4S 16-byte words per pixel (from index
 * SVDAG_COVERAGE_RECORD_VEC4S * i) for up to SVDAG_COVERAGE_SLOTS surfaces: a uvec4 of slot k's
 * label index + 1 (0: background); a uvec4 of its count (bits 0..7) and its world entry face
 * normal, octahedral, as two snorm8 (bits 16..31; 0 for none); then per slot a vec4: the sum of the
 * radiance of its rays that were whole paths (rgb; a miss: the background's) and their number (w).
 * A count of 0 marks an unused slot, all counts 0 any other pixel; rays beyond the slots go
 * uncounted. Samples and accumulations are untouched by that dispatch. */
#define SVDAG_COVERAGE_GRID 4u
#define SVDAG_COVERAGE_SLOTS 4u
#define SVDAG_COVERAGE_RECORD_VEC4S (2u + SVDAG_COVERAGE_SLOTS)
/* An edge pixel traces its grid's four corner rays first; where all four hit one surface, that
 * surface counts for every ray of the grid and the others are not traced (a straight boundary
 * that leaves the corners on one side leaves the whole square between them there; what the
 * corners miss is a feature thinner than a sub-pixel inside it). */
#define SVDAG_COVERAGE_CORNERS 4u

SVDAG_UNIFORMS_BEGIN(FrameUniforms)
  vec4 rayOrigin;      // xyz: ray origin at u = v = 0 minus the scene's reference point (Scene.h:
                       // the instance transform is shifted alike); w: 1 = bounded (far plane)
  vec4 rayOriginU;     // xyz: origin change per unit u; w unused
  vec4 rayOriginV;     // xyz: origin change per unit v; w unused
  vec4 rayDirection;   // xyz: span at u = v = 0 (not unit length); w unused
  vec4 rayDirectionU;  // xyz: span change per unit u; w unused
  vec4 rayDirectionV;  // xyz: span change per unit v; w unused
  vec4 background;     // linear RGBA of camera samples that hit nothing
  vec4 display;        // x: exposure (color output, see above); y, z, w unused
  vec4 autoLod;        // x: world size of one voxel; y: pixels a leaf (4 voxels) or block
                       //    (16 voxels) may cover to be drawn at that coarser level; z: world
                       //    size of a pixel at the ray origin, w: its growth per unit distance (a
                       //    voxel at distance t covers x / (z + w t) pixels)
  uvec4 image;         // x: width, y: height, z: LOD (SVDAG_RENDER_LOD_*), w: shading
                       // (SVDAG_SHADING_*; the shaders compile smooth shading in or out by
                       // SVDAG_CONSTANT_SMOOTH_SHADING, set from the same setting)
  uvec4 grid;          // x, y: cells along x and y (cell index = cx + nx * (cy + ny * cz));
                       // z: primitives per BLAS (instance i's primitive p is entry
                       // i * z + p of the primitive -> block buffer); w: log2 of the words
                       // per chunk of the block stream (Scene.h)
  uvec4 widths;        // x: cell bits, y: label bits, z: root ref bits, w: mid ref bits
  uvec4 widths2;       // x: leaf ref bits, y: bits per block record; zw: address of the
                       // neighbour table (smooth shading only: 27 root refs per block,
                       // svdag::neighbourTable; 0 otherwise)
  uvec4 volumeStreams; // addresses: xy the block stream's chunks (a table of addresses), zw roots
  uvec4 volumeStreams2; // addresses: xy mids, zw leaves
  uvec4 sceneOutputs;  // addresses: xy primitive -> block index (uint32), zw label output
  uvec4 outputs;       // addresses: xy depth, zw normal (3 floats per pixel)
  uvec4 outputs2;      // addresses: xy hdr (vec4 per pixel), zw color (RGBA8 per pixel)
  // The path tracer's PathTracerParams (Shading.h), member by member:
  vec4 sunDirection;   // xyz: unit direction towards the sun (world), w: cos(angular radius)
  vec4 sunRadiance;    // rgb: irradiance at normal incidence, a: 1 = on
  vec4 environment;    // rgb: constant radiance or the map's scale; a: ray epsilon (world units)
  uvec4 lighting;      // x, y: environment map size (1 x 1 = constant), z: max bounces, w: flags
  uvec4 sampling;      // x: samples accumulated before this pass, y: samples per pixel this pass,
                       // z: seed, w: number of label materials (label index bound)
  uvec4 materials;     // addresses: xy materials (Material, 64 bytes per label index),
                       // zw accumulation (vec4 per pixel: rgb sum, alpha sum)
  uvec4 environmentMap; // addresses: xy marginal CDF (float), zw conditional CDFs (float)
  uvec4 environmentMap2; // addresses: xy texels (vec4 per texel, rgb radiance); z, w unused
  uvec4 rayLimits;     // addresses: xy per-pixel ray limit (float; 0: none); z, w unused
  uvec4 statistics;    // addresses: xy luminance sums of squares (float per pixel), zw variance
  // The compute backend (camera.comp, GridTraversal.h): rows of the affine map from world
  // coordinates (relative to the scene's reference point) to volume index space, the inverse of
  // the ray tracing backend's instance transform.
  vec4 worldToIndexX;
  vec4 worldToIndexY;
  vec4 worldToIndexZ;
  uvec4 cellGrid;      // addresses: xy each cell's first block (uint32, cells + 1 entries, Scene.h),
                       // zw the hidden label bits (bit l of word l / 32; 0: none hidden)
  uvec4 volumeDims;    // xyz: voxels along x, y, z; w: cells along z
  uvec4 stepStatistics; // addresses: xy per-pixel step counters (the statistics variant only:
                       // Traversal.h's SVDAG_STAT_COUNT uint32 per pixel, counter c of pixel i
                       // at i * SVDAG_STAT_COUNT + c, summed over the pass's rays); z, w unused
  uvec4 coverage;      // addresses: xy the coverage records (above); z: 1 = this
                       // dispatch traces the coverage of edge pixels, not samples
  // Clipping (Module/core/svdag/Clipping.h): every ray, primary and secondary, is clipped to the
  // region the planes keep. x: planes used in clipPlanes (0: no clipping); y, z, w unused.
  uvec4 clipping;
  // (unit normal, w) relative to the scene's reference point like rayOrigin, w including the
  // margin: up to SVDAG_CLIP_MAX_PLANES user planes, then the crop box's six faces.
  vec4 clipPlanes[SVDAG_CLIP_MAX_SLOTS];
SVDAG_UNIFORMS_END(frame)

/* Reinhard's tone curve on exposure-scaled linear radiance (the color output). */
SVDAG_GPU_FN vec3 svdagToneMap(vec3 linear, float exposure)
{
  vec3 x = max(linear * exposure, vec3(0.0f));
  return x / (vec3(1.0f) + x);
}

/* Base color of a label index: a hash to a well-spread hue-like RGB in [0.15, 0.95]. */
SVDAG_GPU_FN uint svdagHashLabel(uint x)
{
  // A 32-bit integer finalizer (xorshift-multiply): every bit of x affects every output bit.
  x ^= x >> 16u;
  x *= 0x7feb352du;
  x ^= x >> 15u;
  x *= 0x846ca68bu;
  x ^= x >> 16u;
  return x;
}
SVDAG_GPU_FN vec3 svdagLabelColor(uint labelIndex)
{
  uint h = svdagHashLabel(labelIndex);
  vec3 c = vec3(float(h & 255u), float((h >> 8u) & 255u), float((h >> 16u) & 255u)) / 255.0f;
  return vec3(0.15f) + 0.8f * c;
}

#ifdef __cplusplus
// 36 members and the clipping plane array (a vec4 array has a 16-byte stride in std140 too).
static_assert(sizeof(FrameUniforms) == (36 + SVDAG_CLIP_MAX_SLOTS) * 16,
  "FrameUniforms must stay a list of 16-byte members");
} // namespace gpu
} // namespace render
} // namespace svdag
#endif

#endif
