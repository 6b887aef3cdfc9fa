/* Guided upsampling (upsample.comp, UpsamplePass.h), its parameters defined once for C++ (with
 * GLM) and GLSL, like GpuLayout.h.
 *
 * A frame traced at 1/r of the image's width and height (Renderer::setTraceReduction) is shown
 * at full resolution: the label, depth and normals of every full-resolution pixel come from its
 * own pixel-center ray (a primary-only trace, GpuLayout.h's outputs), and its color from the
 * reduced image's pixels around it that hit the same label:
 *   full pixel p at (x + 0.5) / r - 0.5 in reduced pixels; its 4 bilinear neighbours q, each
 *   weighted by the bilinear weight times 1 / (1 + |d_p - d_q| / (r * voxel side)) where q's
 *   label is p's (0 otherwise);
 *   where none of the 4 has p's label: the nearest same-label pixel of the 5x5 reduced pixels
 *   around p (by depth difference, then distance);
 *   where none of those has it either (a label thinner than the reduction that no reduced ray
 *   hit): the reduced pixel under p, the only case that shows another label's radiance;
 *   a background pixel of the guide: the background color (every reduced miss sees it).
 * The color output is the tone-mapped result (svdagDisplayColor), the variance output the
 * variance of the reduced pixel under p.
 * Only vec4 / uvec4 members: the std430 layout is the C++ struct's.
 */
#ifndef SVDAG_RENDER_UPSAMPLE_LAYOUT_H
#define SVDAG_RENDER_UPSAMPLE_LAYOUT_H

#ifdef __cplusplus
#include <cstdint>
#include <glm/glm.hpp>
namespace svdag
{
namespace render
{
namespace gpu
{
#define SVDAG_UPSAMPLE_PARAMS_BEGIN(Name) struct Name {
#define SVDAG_UPSAMPLE_PARAMS_END };
#else
#define SVDAG_UPSAMPLE_PARAMS_BEGIN(Name)                                                          \
  layout(buffer_reference, std430, buffer_reference_align = 16) readonly buffer Name {
#define SVDAG_UPSAMPLE_PARAMS_END };
#endif

/* Workgroups of SVDAG_UPSAMPLE_GROUP_SIZE^2 full-resolution pixels. */
#define SVDAG_UPSAMPLE_GROUP_SIZE 8
/* The fallback's search radius, in reduced pixels. */
#define SVDAG_UPSAMPLE_SEARCH_RADIUS 2

#ifdef __cplusplus
using glm::uvec4;
using glm::vec4;
#endif

SVDAG_UPSAMPLE_PARAMS_BEGIN(UpsampleParams)
  uvec4 sizes;      // x, y: the full image's width and height; z, w: the reduced image's
  vec4 background;  // linear premultiplied RGBA of a miss
  // x: the reduction r; y: the depth scale r * voxel side (world units); z: exposure (color)
  vec4 weights;
  uvec4 guides;     // addresses: xy the full label output, zw the full depth output
  uvec4 reducedGuides; // addresses: xy the reduced label output, zw the reduced depth output
  uvec4 reducedColors; // addresses: xy the reduced hdr (RGBA), zw the reduced variance
  uvec4 hdr;        // addresses: xy the full hdr written; zw the full color (RGBA8) written
  uvec4 variance;   // addresses: xy the full variance written; zw unused
SVDAG_UPSAMPLE_PARAMS_END

#ifdef __cplusplus
static_assert(sizeof(UpsampleParams) == 8 * 16, "UpsampleParams: vec4 and uvec4 members");
} // namespace gpu
} // namespace render
} // namespace svdag
#endif

#endif
