#include "svdag_render/EnvironmentMap.h"

#include <OpenEXR/ImfArray.h>
#include <OpenEXR/ImfRgbaFile.h>

#include <cmath>
#include <stdexcept>

namespace svdag
{
namespace render
{
// The shared shader code reads its tables through macros (globals on the GPU); on the host they
// point at the map being queried, per thread.
static thread_local const EnvironmentMap* currentMap = nullptr;
#define SVDAG_ENV_MARGINAL(i) (::svdag::render::currentMap->marginal[(i)])
#define SVDAG_ENV_CONDITIONAL(i) (::svdag::render::currentMap->conditional[(i)])
#define SVDAG_ENV_TEXEL(i) (::svdag::render::currentMap->texels[(i)])
} // namespace render
} // namespace svdag

#include "svdag_render/Shading.h"

namespace svdag
{
namespace render
{

EnvironmentMap EnvironmentMap::constant(const glm::vec3& radiance)
{
  return fromTexels(1, 1, { radiance });
}

EnvironmentMap EnvironmentMap::fromTexels(uint32_t width, uint32_t height, std::vector<glm::vec3> texels)
{
  if (width == 0 || height == 0 || texels.size() != size_t(width) * height)
    throw std::runtime_error("environment map: texel count does not match its size");
  for (const glm::vec3& t : texels)
  {
    for (int c = 0; c < 3; ++c)
    {
      if (!std::isfinite(t[c]) || t[c] < 0)
        throw std::runtime_error("environment map: radiance must be finite and non-negative");
    }
  }
  EnvironmentMap map;
  map.width = width;
  map.height = height;
  map.texels = std::move(texels);
  map.buildDistribution();
  return map;
}

EnvironmentMap EnvironmentMap::fromEXR(const std::string& path, float intensity)
{
  std::vector<glm::vec3> texels;
  int width = 0, height = 0;
  try
  {
    Imf::RgbaInputFile file(path.c_str());
    const Imath::Box2i window = file.dataWindow();
    width = window.max.x - window.min.x + 1;
    height = window.max.y - window.min.y + 1;
    if (width <= 0 || height <= 0 || int64_t(width) * height > (int64_t(1) << 28))
      throw std::runtime_error("unsupported image size");
    Imf::Array2D<Imf::Rgba> pixels(height, width);
    file.setFrameBuffer(&pixels[0][0] - window.min.x - window.min.y * width, 1, size_t(width));
    file.readPixels(window.min.y, window.max.y);
    texels.resize(size_t(width) * size_t(height));
    for (int y = 0; y < height; ++y)
    {
      for (int x = 0; x < width; ++x)
      {
        const Imf::Rgba& p = pixels[y][x];
        texels[size_t(y) * size_t(width) + size_t(x)] =
          intensity * glm::vec3(float(p.r), float(p.g), float(p.b));
      }
    }
  }
  catch (const std::exception& e)
  {
    throw std::runtime_error("cannot read environment map '" + path + "': " + e.what());
  }
  return fromTexels(uint32_t(width), uint32_t(height), std::move(texels));
}

void EnvironmentMap::buildDistribution()
{
  // Rows weighted by their solid angle (sin theta); texels by luminance, with a small floor so
  // that every direction keeps a non-zero density (MIS then never divides by a zero pdf).
  marginal.assign(height + 1, 0.0f);
  conditional.assign(size_t(height) * (width + 1), 0.0f);
  std::vector<double> rowSums(height, 0.0);
  double total = 0;
  double maxLum = 0;
  for (const glm::vec3& t : texels)
    maxLum = std::max(maxLum, double(shading::luminance(t)));
  const double floorLum = maxLum > 0 ? 1e-3 * maxLum : 1.0;
  for (uint32_t r = 0; r < height; ++r)
  {
    const double sinTheta = std::sin(M_PI * (r + 0.5) / height);
    float* cdf = conditional.data() + size_t(r) * (width + 1);
    double sum = 0;
    std::vector<double> acc(width + 1, 0.0);
    for (uint32_t c = 0; c < width; ++c)
    {
      sum += std::max(double(shading::luminance(texels[size_t(r) * width + c])), floorLum);
      acc[c + 1] = sum;
    }
    for (uint32_t c = 0; c <= width; ++c)
      cdf[c] = float(acc[c] / sum);
    cdf[width] = 1.0f;
    rowSums[r] = sum * sinTheta;
    total += rowSums[r];
  }
  double acc = 0;
  for (uint32_t r = 0; r < height; ++r)
  {
    acc += rowSums[r];
    marginal[r + 1] = float(acc / total);
  }
  marginal[height] = 1.0f;
}

float EnvironmentMap::pdf(const glm::vec3& direction) const
{
  currentMap = this;
  return shading::envPdf(direction, width, height);
}

glm::vec3 EnvironmentMap::sample(const glm::vec2& u, float& pdfOut) const
{
  currentMap = this;
  return shading::envSample(u, width, height, pdfOut);
}

glm::vec3 EnvironmentMap::radiance(const glm::vec3& direction) const
{
  currentMap = this;
  return shading::envRadiance(direction, width, height);
}

} // namespace render
} // namespace svdag
