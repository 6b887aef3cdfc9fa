#include "vtkSegmentationSVDAGRayCaster.h"

#include "vtkDataArray.h"
#include "vtkMath.h"
#include "vtkMatrix3x3.h"
#include "vtkObjectFactory.h"
#include "vtkSegmentationSVDAG.h"

#include "svdag/RayCaster.h"
#include "svdag/Volume.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <stdexcept>
#include <vector>

vtkStandardNewMacro(vtkSegmentationSVDAGRayCaster);

vtkSegmentationSVDAGRayCaster::vtkSegmentationSVDAGRayCaster() = default;
vtkSegmentationSVDAGRayCaster::~vtkSegmentationSVDAGRayCaster() = default;

void vtkSegmentationSVDAGRayCaster::SetInputData(vtkSegmentationSVDAG* input)
{
  if (this->Input != input)
  {
    this->Input = input;
    this->Modified();
  }
}

vtkSegmentationSVDAG* vtkSegmentationSVDAGRayCaster::GetInput()
{
  return this->Input;
}

vtkDataArray* vtkSegmentationSVDAGRayCaster::GetHitLabelValue()
{
  return this->HitLabelValue;
}

void vtkSegmentationSVDAGRayCaster::ClearHit()
{
  this->Hit = 0;
  this->HitLabelIndex = -1;
  this->HitLabelValue = nullptr;
  this->HitDistance = 0.0;
  this->HitBlockIndex = -1;
  this->HitClippingPlane = -1;
  for (int a = 0; a < 3; ++a)
  {
    this->HitPosition[a] = 0.0;
    this->HitNormal[a] = 0.0;
    this->HitShadingNormal[a] = 0.0;
    this->HitVoxel[a] = 0;
  }
}

int vtkSegmentationSVDAGRayCaster::AddClippingPlane(const double origin[3], const double normal[3])
{
  if (this->ClippingPlanes.size() >= 6)
  {
    vtkErrorMacro("AddClippingPlane: at most 6 clipping planes are supported");
    return 0;
  }
  const double length = vtkMath::Norm(normal);
  if (!std::isfinite(length) || !(length > 0.0) || !std::isfinite(vtkMath::Norm(origin)))
  {
    vtkErrorMacro("AddClippingPlane: the origin must be finite and the normal finite and non-zero");
    return 0;
  }
  this->ClippingPlanes.push_back({ { origin[0], origin[1], origin[2], normal[0] / length,
    normal[1] / length, normal[2] / length } });
  this->Modified();
  return 1;
}

void vtkSegmentationSVDAGRayCaster::RemoveAllClippingPlanes()
{
  if (!this->ClippingPlanes.empty())
  {
    this->ClippingPlanes.clear();
    this->Modified();
  }
}

int vtkSegmentationSVDAGRayCaster::GetNumberOfClippingPlanes()
{
  return int(this->ClippingPlanes.size());
}

void vtkSegmentationSVDAGRayCaster::SetCroppingRegionPlanes(
  double xmin, double xmax, double ymin, double ymax, double zmin, double zmax)
{
  const double b[6] = { xmin, xmax, ymin, ymax, zmin, zmax };
  for (int a = 0; a < 3; ++a)
  {
    if (!std::isfinite(b[2 * a]) || !std::isfinite(b[2 * a + 1]) || !(b[2 * a] <= b[2 * a + 1]))
    {
      vtkErrorMacro("SetCroppingRegionPlanes: the box must be finite with min <= max on every "
                    "axis, got ("
        << xmin << ", " << xmax << ", " << ymin << ", " << ymax << ", " << zmin << ", " << zmax
        << ")");
      return;
    }
  }
  if (!std::equal(b, b + 6, this->CroppingRegionPlanes))
  {
    std::copy(b, b + 6, this->CroppingRegionPlanes);
    this->Modified();
  }
}

int vtkSegmentationSVDAGRayCaster::CastRay(const double origin[3], const double direction[3])
{
  this->ClearHit();
  if (!this->Input || !this->Input->HasVolume())
  {
    vtkErrorMacro("CastRay: no input segmentation (call SetInputData with a built volume)");
    return 0;
  }
  const double length = vtkMath::Norm(direction);
  if (!std::isfinite(length) || length == 0.0 || !std::isfinite(vtkMath::Norm(origin)))
  {
    vtkErrorMacro("CastRay: the origin must be finite and the direction finite and non-zero");
    return 0;
  }
  const svdag::Volume& volume = *this->Input->GetVolume();
  const svdag::Geometry& g = volume.geometry;

  // Index-to-world linear part M = Direction * diag(Spacing), and its inverse.
  double m[9], inverse[9];
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c)
      m[3 * r + c] = g.direction[size_t(3 * r + c)] * g.spacing[size_t(c)];
  if (!(std::fabs(vtkMatrix3x3::Determinant(m)) > 0.0))
  {
    vtkErrorMacro("CastRay: the volume's index-to-world matrix is singular");
    return 0;
  }
  vtkMatrix3x3::Invert(m, inverse);

  // With a unit world direction the ray parameter is the world distance in both spaces.
  double unit[3] = { direction[0] / length, direction[1] / length, direction[2] / length };
  svdag::Ray ray;
  for (int r = 0; r < 3; ++r)
  {
    ray.origin[size_t(r)] = 0.5;
    ray.direction[size_t(r)] = 0.0;
    for (int c = 0; c < 3; ++c)
    {
      ray.origin[size_t(r)] += inverse[3 * r + c] * (origin[c] - g.origin[size_t(c)]);
      ray.direction[size_t(r)] += inverse[3 * r + c] * unit[c];
    }
  }
  ray.tmin = 0.0;
  ray.tmax = this->MaximumDistance;

  // Clipping planes and crop faces (world origin o, unit normal n) as index-space planes whose
  // function dot(n, world(p) - o) is a world distance, with world(p) = O + M (p - 0.5); moved
  // into the kept side by the margin the GPU renderer uses at least (Clipping.h: a quarter of a
  // thousandth of the smallest voxel side).
  std::vector<std::array<double, 6>> worldPlanes = this->ClippingPlanes;
  if (this->Cropping)
  {
    for (int a = 0; a < 3; ++a)
    {
      std::array<double, 6> lo{ { 0, 0, 0, 0, 0, 0 } }, hi = lo;
      lo[size_t(a)] = this->CroppingRegionPlanes[2 * a];
      lo[size_t(3 + a)] = 1.0;
      hi[size_t(a)] = this->CroppingRegionPlanes[2 * a + 1];
      hi[size_t(3 + a)] = -1.0;
      worldPlanes.push_back(lo);
      worldPlanes.push_back(hi);
    }
  }
  const double margin = 2.5e-4 * std::min({ g.spacing[0], g.spacing[1], g.spacing[2] });
  std::vector<std::array<double, 4>> clipPlanes;
  for (const auto& wp : worldPlanes)
  {
    std::array<double, 4> plane{ { 0, 0, 0, -margin } };
    for (int r = 0; r < 3; ++r)
    {
      plane[3] += wp[size_t(3 + r)] * (g.origin[size_t(r)] - wp[size_t(r)]);
      for (int c = 0; c < 3; ++c)
        plane[size_t(c)] += wp[size_t(3 + r)] * m[3 * r + c];
    }
    plane[3] -= 0.5 * (plane[0] + plane[1] + plane[2]);
    clipPlanes.push_back(plane);
  }

  svdag::RayHit hit;
  std::array<float, 3> shading{ { 0, 0, 0 } };
  try
  {
    svdag::RayCaster caster(volume);
    caster.setClipPlanes(clipPlanes);
    hit = caster.cast(ray, svdag::Lod(this->LOD));
    shading = caster.smoothNormal(ray, hit, svdag::Lod(this->LOD));
  }
  catch (const std::exception& e)
  {
    vtkErrorMacro("CastRay: " << e.what());
    return 0;
  }
  if (!hit.hit)
    return 0;

  this->Hit = 1;
  this->HitLabelIndex = static_cast<vtkIdType>(hit.label);
  this->HitBlockIndex = static_cast<vtkIdType>(hit.block);
  this->HitDistance = hit.t;
  vtkDataArray* value = vtkDataArray::CreateDataArray(
    vtkSegmentationSVDAG::ToVTKScalarType(int(volume.scalarType)));
  value->SetNumberOfTuples(1);
  value->SetName("HitLabel");
  svdag::scalarStore(volume.scalarType, value->GetVoidPointer(0), 0, volume.labels[hit.label].value);
  this->HitLabelValue.TakeReference(value);
  // Normals transform with the inverse transpose of M.
  double normal[3] = { 0.0, 0.0, 0.0 };
  double shadingNormal[3] = { 0.0, 0.0, 0.0 };
  for (int r = 0; r < 3; ++r)
  {
    this->HitPosition[r] = origin[r] + hit.t * unit[r];
    this->HitVoxel[r] = hit.voxel[size_t(r)];
    for (int c = 0; c < 3; ++c)
    {
      normal[r] += inverse[3 * c + r] * hit.normal[size_t(c)];
      shadingNormal[r] += inverse[3 * c + r] * double(shading[size_t(c)]);
    }
  }
  if (hit.clipPlane >= 0)
  {
    // A cut face: the kept region's outward normal there, which faces the ray.
    this->HitClippingPlane = hit.clipPlane;
    for (int r = 0; r < 3; ++r)
      normal[r] = -worldPlanes[size_t(hit.clipPlane)][size_t(3 + r)];
  }
  if (vtkMath::Norm(normal) > 0.0)
    vtkMath::Normalize(normal);
  if (vtkMath::Norm(shadingNormal) > 0.0)
    vtkMath::Normalize(shadingNormal);
  for (int r = 0; r < 3; ++r)
  {
    this->HitNormal[r] = normal[r];
    this->HitShadingNormal[r] = hit.clipPlane >= 0 ? normal[r] : shadingNormal[r];
  }
  return 1;
}

void vtkSegmentationSVDAGRayCaster::PrintSelf(ostream& os, vtkIndent indent)
{
  this->Superclass::PrintSelf(os, indent);
  os << indent << "Input: " << this->Input.Get() << "\n";
  os << indent << "LOD: "
     << (this->LOD == LOD_BLOCK ? "block" : (this->LOD == LOD_LEAF ? "leaf" : "voxel")) << "\n";
  os << indent << "MaximumDistance: " << this->MaximumDistance << "\n";
  os << indent << "ClippingPlanes: " << this->ClippingPlanes.size() << "\n";
  os << indent << "Cropping: " << this->Cropping << "\n";
  os << indent << "Hit: " << this->Hit << "\n";
  if (this->Hit)
  {
    os << indent << "HitLabelIndex: " << this->HitLabelIndex << "\n";
    os << indent << "HitDistance: " << this->HitDistance << "\n";
    os << indent << "HitPosition: (" << this->HitPosition[0] << ", " << this->HitPosition[1]
       << ", " << this->HitPosition[2] << ")\n";
    os << indent << "HitNormal: (" << this->HitNormal[0] << ", " << this->HitNormal[1] << ", "
       << this->HitNormal[2] << ")\n";
    os << indent << "HitVoxel: (" << this->HitVoxel[0] << ", " << this->HitVoxel[1] << ", "
       << this->HitVoxel[2] << ")\n";
    os << indent << "HitBlockIndex: " << this->HitBlockIndex << "\n";
  }
}
