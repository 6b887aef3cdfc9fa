// The clipping planes and crop box of the VTK classes that own them (the volume mapper and the
// image renderer), as the core renderer takes them per frame (private to the Rendering module).
#pragma once

#include "vtkType.h"

#include <array>

class vtkObject;
class vtkPlaneCollection;

namespace svdag
{
namespace render
{
struct RenderSettings;
}

namespace vtkglue
{

// Sets settings.clipPlanes and settings.crop (replacing what they held): every vtkPlane of
// `planes` (may be null), given in VTK's world, mapped into the core renderer's world by
// worldToModel (row-major 4x4; x_model = worldToModel x_world, and a plane dot(n, x - o) >= 0
// keeps dot(M^-T n, x_model - M o) >= 0, M^-T n = modelToWorld^T n), and the crop box when
// `cropping` is on (bounds already in the core renderer's world). Validation is the core's
// (svdag::render::validate, when the frame is rendered).
void setClipping(render::RenderSettings& settings, vtkPlaneCollection* planes,
  const std::array<double, 16>& modelToWorld, const std::array<double, 16>& worldToModel,
  bool cropping, const double cropBounds[6]);

// The crop box setter both owners share: validates (min <= max, finite) and copies the box into
// `current` (6 values). Returns whether it changed; a bad box is reported by `owner`'s
// vtkErrorMacro and changes nothing.
bool setCroppingRegionPlanes(vtkObject* owner, double current[6], const double planes[6]);

// The identity, for a class whose planes are already in the core renderer's world.
std::array<double, 16> identityMatrix();

} // namespace vtkglue
} // namespace svdag
