#include "svdag_render/CompileAhead.h"

#include "svdag_render/Camera.h"
#include "svdag_render/Renderer.h"

#include <svdag/Builder.h>

#include <cstdint>
#include <memory>

namespace svdag
{
namespace render
{

void compileAhead(const RenderSettings& settings)
{
  Geometry geometry;
  geometry.dims = { { 1, 1, 1 } };
  const uint8_t label = 1;
  auto volume = std::make_shared<const Volume>(Builder::build(geometry, ScalarType::UInt8, &label));
  RenderSettings first = settings;
  // One pass of one sample: the first frame's pipelines, not its cost.
  first.samplesPerPixel = 1;
  Renderer renderer;
  renderer.setSettings(first);
  renderer.setVolume(volume);
  renderer.setImageSize(2, 2);
  renderer.setCamera(frameVolume(geometry, 30, 20));
  renderer.render();
}

} // namespace render
} // namespace svdag
