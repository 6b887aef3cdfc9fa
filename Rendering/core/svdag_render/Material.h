/* The per-label material of the path tracer, std430 layout (64 bytes): the one definition used by
 * the host (Renderer, uploads) and the shaders (Shading.h includes it). Common subset of GLSL 4.60
 * and C++17 with GLM; on its own so that host code can hold materials without Shading.h's
 * buffer-access macros.
 */
#ifndef SVDAG_RENDER_MATERIAL_H
#define SVDAG_RENDER_MATERIAL_H

#ifdef __cplusplus
#include <glm/glm.hpp>
namespace svdag
{
namespace shading
{
#endif

struct Material
{
#ifdef __cplusplus
  glm::vec4 baseColorVisibility; // rgb base color (linear), a = visibility (0 hidden, 1 visible)
  glm::vec4 emission;            // rgb emitted radiance, a unused
  glm::vec4 params;              // x roughness, y metallic, z transmission weight, w index of refraction
  glm::vec4 extra;               // x specular (dielectric reflectance scale, 0.5 -> F0 = 0.04), yzw unused
#else
  vec4 baseColorVisibility;
  vec4 emission;
  vec4 params;
  vec4 extra;
#endif
};

#ifdef __cplusplus
static_assert(sizeof(Material) == 64, "Material is 64 bytes (std430)");
} // namespace shading
} // namespace svdag
#endif

#endif
