/* The denoiser's parameters (denoise.comp, DenoisePass.h), defined once for C++ (with GLM) and
 * GLSL, like GpuLayout.h.
 *
 * An edge-avoiding a-trous wavelet filter (Dammertz et al. 2010, with the variance-guided
 * luminance weight of SVGF, Schied et al. 2017) over the displayed image (hdr, and the color made
 * from it), guided by the outputs the trace writes anyway (GpuLayout.h): the pixel-center label,
 * depth and shading normal. Between two pixels p and q the weight is
 *   0                                           where their labels differ (label edges are
 *                                               exact, so no radiance crosses an object boundary;
 *                                               background pixels are left as they are)
 *   h(dx) h(dy)                                 the B3-like 3x3 kernel (1/4, 1/2, 1/4), its taps
 *                                               `step` pixels apart (1, 2, 4, 8, 16)
 *   * max(dot(n_p, n_q), 0)^32                  normals (voxel faces: 1 on one face, 0 across)
 *   * exp(-|dot(n_p, x_q - x_p)| / planeSigma)  q's distance from p's tangent plane (world units)
 *   * exp(-|l_p - l_q| / (lumaSigma sqrt(var_p) + tiny))
 *                                               luminance, against the estimated standard
 *                                               deviation of p's value: as samples accumulate
 *                                               the variance of the mean falls and the filter
 *                                               fades out by itself, so a converged image is
 *                                               left as it is
 * The prepass gathers each pixel's guides into one 16-byte record (one load per tap) with var_p
 * (the accumulated mean's variance, GpuLayout.h's variance output, from
 * SVDAG_DENOISE_TEMPORAL_SAMPLES samples on; before that the spatial variance of the luminance
 * over the 5x5 same-label neighbourhood, divided by the samples; 0, i.e. unfiltered, for a pixel
 * with an 8-neighbour of another label from then on: its mean is the edge's antialiasing, not
 * noise). Such edge pixels are taps of another pixel only while the image is one sample (through
 * the pixel center, so of its own label); later their samples may have hit the neighbouring
 * label, so no radiance of one label reaches a pixel inside another. Positions are recomputed
 * from the depth and the rays. Every iteration filters the variance with the squared weights, as
 * SVGF does. The last iteration resolves the pixels that have a coverage record (GpuLayout.h: label
 * edges and steps between entry faces): the colors of the surfaces their sub-pixel rays hit, each
 * the 7x7 neighbourhood's mean of the pixels showing it (same label and entry face; once samples
 * accumulate, not on a label edge where some are; where some of the pixel's coverage rays were
 * whole paths, on label edges and creases, mixed with their mean radiance), weighted by the rays'
 * counts, then mixed with the pixel's own value by G / (G + samples), G the coverage rays.
 * Parameters live in a buffer reached through its device address (pushed as a uvec2), one slot per
 * dispatch of a frame. Only vec4 / uvec4 members: the std430 layout is the C++ struct's.
 */
#ifndef SVDAG_RENDER_DENOISE_LAYOUT_H
#define SVDAG_RENDER_DENOISE_LAYOUT_H

#ifdef __cplusplus
#include <cstdint>
#include <glm/glm.hpp>
namespace svdag
{
namespace render
{
namespace gpu
{
#define SVDAG_DENOISE_PARAMS_BEGIN(Name) struct Name {
#define SVDAG_DENOISE_PARAMS_END };
#else
#define SVDAG_DENOISE_PARAMS_BEGIN(Name)                                                           \
  layout(buffer_reference, std430, buffer_reference_align = 16) readonly buffer Name {
#define SVDAG_DENOISE_PARAMS_END };
#endif

/* sizes.z: the prepass (variance estimate and positions) or a filter iteration. */
#define SVDAG_DENOISE_PASS_PREPARE 0u
#define SVDAG_DENOISE_PASS_FILTER 1u
/* Filter iterations per frame (steps 1, 2, 4, ...): a footprint of 2^iterations + 1 pixels. */
#define SVDAG_DENOISE_ITERATIONS 5u
/* From this many accumulated samples on, the variance of the mean comes from the samples. */
#define SVDAG_DENOISE_TEMPORAL_SAMPLES 4u
/* Where coverage rays were whole paths, a surface's window estimate counts as this many of them
 * (denoise.comp's resolveEdge). */
#define SVDAG_DENOISE_WINDOW_SAMPLES 4u
/* The normal weight's power: 2^SVDAG_DENOISE_NORMAL_POWER_LOG2. */
#define SVDAG_DENOISE_NORMAL_POWER_LOG2 5u
/* Workgroups of SVDAG_DENOISE_GROUP_SIZE^2 pixels. */
#define SVDAG_DENOISE_GROUP_SIZE 8

#ifdef __cplusplus
using glm::uvec4;
using glm::vec4;
#endif

SVDAG_DENOISE_PARAMS_BEGIN(DenoiseParams)
  // xyz: the traced view rays (GpuLayout.h's rayOrigin ... rayDirectionV, relative to the
  // scene's reference point), which give each pixel's world position from its depth
  vec4 rayOrigin;
  vec4 rayOriginU;
  vec4 rayOriginV;
  vec4 rayDirection;
  vec4 rayDirectionU;
  vec4 rayDirectionV;
  // x: lumaSigma, y unused, z: planeSigma (world units), w: exposure (the color output)
  vec4 weights;
  uvec4 sizes;     // x, y: image width and height; z: SVDAG_DENOISE_PASS_*; w: step (pixels)
  uvec4 samples;   // x: samples accumulated in the image; y: 1 where this iteration is the last
  uvec4 guides;    // addresses: xy label output, zw depth output
  uvec4 guides2;   // addresses: xy normal output (shading normals), zw variance output
  uvec4 colors;    // addresses: xy the RGBA read, zw the RGBA written
  // addresses: xy the guides read, zw the guides written (per pixel a uvec4: label + 1, the
  // shading normal packed in 32 bits, the depth's float bits with the sign bit set on a label
  // edge, the variance's float bits)
  uvec4 variances;
  uvec4 geometry;  // addresses: xy the label edge coverage records (GpuLayout.h; 0: none), read
                   // by the last iteration; zw the color output (RGBA8), written by the last
                   // iteration
SVDAG_DENOISE_PARAMS_END

#ifdef __cplusplus
static_assert(sizeof(DenoiseParams) == 7 * 16 + 7 * 16, "DenoiseParams: vec4 and uvec4 members");
} // namespace gpu
} // namespace render
} // namespace svdag
#endif

#endif
