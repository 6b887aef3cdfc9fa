// The path tracer's environment light on the host: a constant radiance or an equirectangular
// OpenEXR image, with the CDF tables that Shading.h's envSample/envPdf read on the GPU.
#pragma once

#include <glm/glm.hpp>

#include <string>
#include <vector>

namespace svdag
{
namespace render
{

struct EnvironmentMap
{
  uint32_t width = 1;
  uint32_t height = 1;
  std::vector<glm::vec3> texels;   // row-major, row 0 at +z (Shading.h's convention)
  std::vector<float> marginal;     // height + 1 entries, 0 .. 1
  std::vector<float> conditional;  // height * (width + 1) entries, each row 0 .. 1

  // A uniform environment of the given linear radiance (one texel, uniform sampling).
  static EnvironmentMap constant(const glm::vec3& radiance);
  // Reads an equirectangular OpenEXR image (RGB(A), any channel type) scaled by `intensity`.
  // Throws std::runtime_error naming the file and the problem.
  static EnvironmentMap fromEXR(const std::string& path, float intensity = 1.0f);
  // From texels (width * height, row-major). Negative or non-finite radiance is an error.
  static EnvironmentMap fromTexels(uint32_t width, uint32_t height, std::vector<glm::vec3> texels);

  // Host-side mirrors of the shader functions, for tests and the CPU reference.
  float pdf(const glm::vec3& direction) const;
  glm::vec3 sample(const glm::vec2& u, float& pdf) const;
  glm::vec3 radiance(const glm::vec3& direction) const;
  bool isConstant() const { return width == 1 && height == 1; }

private:
  void buildDistribution();
};

} // namespace render
} // namespace svdag
