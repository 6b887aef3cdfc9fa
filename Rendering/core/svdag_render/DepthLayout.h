/* The depth pass's parameters (depth.comp, DepthPass.h), defined once for C++ (with GLM) and
 * GLSL, like GpuLayout.h.
 *
 * The pass turns window depth into ray distances and back on the device, for a window depth
 * that another API (OpenGL) wrote into exported memory, so that it need not go through the host.
 * It computes in double precision (the shaderFloat64 feature) what the volume mapper computes on
 * the host otherwise, operation by operation, so that both give the same bits:
 *   SVDAG_DEPTH_PASS_LIMITS     per traced pixel, the ray limit at the surface the scene depth
 *                               holds (the mapper's rayLimits), less the renderer's advance of
 *                               the rays (Renderer::render, as for limits given by the host)
 *   SVDAG_DEPTH_PASS_COMPOSITE  per viewport pixel, the nearer of the scene depth and the
 *                               window depth of the traced hit covering it (the mapper's
 *                               compositedDepth, of the depths Renderer::image() holds)
 * The parameters are one struct (the same declaration in both languages) in a buffer reached
 * through its device address (pushed as a uvec2): the matrices and rays alone exceed the 128
 * bytes of push constants a device must offer. The shader loads the struct whole, once. Only
 * dvec4 members come before the uvec4 ones, so its std430 layout is the C++ struct's.
 */
#ifndef SVDAG_RENDER_DEPTH_LAYOUT_H
#define SVDAG_RENDER_DEPTH_LAYOUT_H

#ifdef __cplusplus
#include <cstdint>
#include <glm/glm.hpp>
namespace svdag
{
namespace render
{
namespace gpu
{
#endif

#define SVDAG_DEPTH_PASS_LIMITS 0u
#define SVDAG_DEPTH_PASS_COMPOSITE 1u
/* Workgroups of SVDAG_DEPTH_GROUP_SIZE^2 pixels. */
#define SVDAG_DEPTH_GROUP_SIZE 8
/* A ray limit lies this factor past the surface (the mapper's rayLimits says why). */
#define SVDAG_RAY_LIMIT_SLACK (1 + 1e-5)
/* The ray limit of a pixel where nothing was drawn (FLT_MAX: the ray is not limited). */
#define SVDAG_RAY_NOT_LIMITED 3.402823466e38f

#ifdef __cplusplus
using glm::dvec4;
using glm::uvec4;
#endif

struct DepthParams
{
  // Rows of the row-major clip-to-model matrix (limits) or model-to-clip matrix (composite).
  dvec4 matrix[4];
  // xyz: the view rays the depth is measured along (Camera.h's ViewRays, as the mapper has them)
  dvec4 origin;
  dvec4 originU;
  dvec4 originV;
  dvec4 direction;
  dvec4 directionU;
  dvec4 directionV;
  // xyz: the spans (direction, U, V) of the rays the renderer traced with, whose length scales
  // its advance (Renderer::render)
  dvec4 tracedDirection;
  dvec4 tracedDirectionU;
  dvec4 tracedDirectionV;
  // x: the advance (the approach parameter of the traced rays; 0: none); y: SVDAG_RAY_LIMIT_SLACK
  // as the host computes it (the shader folds no constants of its own)
  dvec4 scalars;
  uvec4 sizes;  // x, y: viewport width and height (scene depth pixels); z, w: traced image's
  uvec4 pass;   // x: SVDAG_DEPTH_PASS_*; y, z, w unused
  uvec4 depth;  // addresses: xy the scene depth (float per viewport pixel, rows from the bottom);
                // zw the output (float ray limit per traced pixel, or window depth per viewport
                // pixel)
  uvec4 traced; // addresses: xy label output, zw depth output of the trace (composite only)
};

#ifdef __cplusplus
static_assert(sizeof(DepthParams) == 14 * 32 + 4 * 16, "DepthParams: dvec4 members, then uvec4");
} // namespace gpu
} // namespace render
} // namespace svdag
#endif

#endif
