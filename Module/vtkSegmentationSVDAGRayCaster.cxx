#include "vtkSegmentationSVDAGRayCaster.h"

#include "vtkDataArray.h"
#include "vtkMath.h"
#include "vtkMatrix3x3.h"
#include "vtkObjectFactory.h"
#include "vtkSegmentationSVDAG.h"

#include "svdag/RayCaster.h"
#include "svdag/Volume.h"

#include <cmath>
#include <stdexcept>

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
  for (int a = 0; a < 3; ++a)
  {
    this->HitPosition[a] = 0.0;
    this->HitNormal[a] = 0.0;
    this->HitVoxel[a] = 0;
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

  svdag::RayHit hit;
  try
  {
    hit = svdag::RayCaster(volume).cast(ray, svdag::Lod(this->LOD));
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
  for (int r = 0; r < 3; ++r)
  {
    this->HitPosition[r] = origin[r] + hit.t * unit[r];
    this->HitVoxel[r] = hit.voxel[size_t(r)];
    for (int c = 0; c < 3; ++c)
      normal[r] += inverse[3 * c + r] * hit.normal[size_t(c)];
  }
  if (vtkMath::Norm(normal) > 0.0)
    vtkMath::Normalize(normal);
  for (int r = 0; r < 3; ++r)
    this->HitNormal[r] = normal[r];
  return 1;
}

void vtkSegmentationSVDAGRayCaster::PrintSelf(ostream& os, vtkIndent indent)
{
  this->Superclass::PrintSelf(os, indent);
  os << indent << "Input: " << this->Input.Get() << "\n";
  os << indent << "LOD: "
     << (this->LOD == LOD_BLOCK ? "block" : (this->LOD == LOD_LEAF ? "leaf" : "voxel")) << "\n";
  os << indent << "MaximumDistance: " << this->MaximumDistance << "\n";
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
