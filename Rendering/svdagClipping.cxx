#include "svdagClipping.h"

#include "vtkObject.h"
#include "vtkPlane.h"
#include "vtkPlaneCollection.h"

#include <svdag_render/RenderSettings.h>

#include <algorithm>
#include <exception>

namespace svdag
{
namespace vtkglue
{

std::array<double, 16> identityMatrix()
{
  return { { 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1 } };
}

void setClipping(render::RenderSettings& settings, vtkPlaneCollection* planes,
  const std::array<double, 16>& modelToWorld, const std::array<double, 16>& worldToModel,
  bool cropping, const double cropBounds[6])
{
  settings.clipPlanes.clear();
  if (planes)
  {
    vtkCollectionSimpleIterator it;
    planes->InitTraversal(it);
    while (vtkPlane* plane = planes->GetNextPlane(it))
    {
      double o[3], n[3];
      plane->GetOrigin(o);
      plane->GetNormal(n);
      render::ClipPlane p;
      for (int r = 0; r < 3; ++r)
      {
        p.origin[r] = worldToModel[4 * r + 3];
        p.normal[r] = 0;
        for (int c = 0; c < 3; ++c)
        {
          p.origin[r] += worldToModel[4 * r + c] * o[c];
          p.normal[r] += modelToWorld[4 * c + r] * n[c];
        }
      }
      settings.clipPlanes.push_back(p);
    }
  }
  settings.crop = render::CropBox();
  if (cropping)
  {
    settings.crop.on = true;
    std::copy(cropBounds, cropBounds + 6, settings.crop.bounds.begin());
  }
}

bool setCroppingRegionPlanes(vtkObject* owner, double current[6], const double planes[6])
{
  render::CropBox box;
  try
  {
    box = render::validCropBox({ { planes[0], planes[1], planes[2], planes[3], planes[4],
      planes[5] } });
  }
  catch (const std::exception& e)
  {
    vtkErrorWithObjectMacro(owner, "SetCroppingRegionPlanes: " << e.what());
    return false;
  }
  if (std::equal(box.bounds.begin(), box.bounds.end(), current))
    return false;
  std::copy(box.bounds.begin(), box.bounds.end(), current);
  return true;
}

} // namespace vtkglue
} // namespace svdag
