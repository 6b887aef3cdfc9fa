#include "vtkSegmentationSVDAGSlice.h"

#include "vtkDataArray.h"
#include "vtkImageData.h"
#include "vtkInformation.h"
#include "vtkInformationVector.h"
#include "vtkObjectFactory.h"
#include "vtkPointData.h"
#include "vtkSVDAGParallel.h"
#include "vtkSegmentationSVDAG.h"
#include "vtkStreamingDemandDrivenPipeline.h"

#include "svdag/RandomAccess.h"
#include "svdag/Volume.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <stdexcept>

vtkStandardNewMacro(vtkSegmentationSVDAGSlice);

struct vtkSegmentationSVDAGSlice::OutputGeometry
{
  int Extent[6] = { 0, 0, 0, 0, 0, 0 };
  double Spacing[3] = { 1, 1, 1 };
  double Origin[3] = { 0, 0, 0 };
  double Direction[9] = { 1, 0, 0, 0, 1, 0, 0, 0, 1 };
  svdag::PlaneSampling Plane; // oblique mode only
};

namespace
{
using Vec = std::array<double, 3>;

double Dot(const Vec& a, const Vec& b)
{
  return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

Vec Cross(const Vec& a, const Vec& b)
{
  return { { a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0] } };
}

bool Normalize(Vec& a)
{
  const double n = std::sqrt(Dot(a, a));
  if (!(n > 0) || !std::isfinite(n))
    return false;
  for (double& c : a)
    c /= n;
  return true;
}

// Inverse of a row-major 3x3 matrix; false when it is singular.
bool Invert(const std::array<double, 9>& m, std::array<double, 9>& r)
{
  const double det = m[0] * (m[4] * m[8] - m[5] * m[7]) - m[1] * (m[3] * m[8] - m[5] * m[6]) +
    m[2] * (m[3] * m[7] - m[4] * m[6]);
  if (!(std::fabs(det) > 0) || !std::isfinite(det))
    return false;
  r[0] = (m[4] * m[8] - m[5] * m[7]) / det;
  r[1] = (m[2] * m[7] - m[1] * m[8]) / det;
  r[2] = (m[1] * m[5] - m[2] * m[4]) / det;
  r[3] = (m[5] * m[6] - m[3] * m[8]) / det;
  r[4] = (m[0] * m[8] - m[2] * m[6]) / det;
  r[5] = (m[2] * m[3] - m[0] * m[5]) / det;
  r[6] = (m[3] * m[7] - m[4] * m[6]) / det;
  r[7] = (m[1] * m[6] - m[0] * m[7]) / det;
  r[8] = (m[0] * m[4] - m[1] * m[3]) / det;
  return true;
}
} // namespace

vtkSegmentationSVDAGSlice::vtkSegmentationSVDAGSlice() = default;
vtkSegmentationSVDAGSlice::~vtkSegmentationSVDAGSlice() = default;

int vtkSegmentationSVDAGSlice::FillInputPortInformation(int, vtkInformation* info)
{
  info->Set(vtkAlgorithm::INPUT_REQUIRED_DATA_TYPE(), "vtkSegmentationSVDAG");
  return 1;
}

bool vtkSegmentationSVDAGSlice::ComputeOutputGeometry(
  vtkSegmentationSVDAG* input, OutputGeometry& out, std::string& error)
{
  const svdag::Volume& v = *input->GetVolume();
  const svdag::Geometry& g = v.geometry;
  if (this->Mode == AXIS_ALIGNED)
  {
    try
    {
      const svdag::Box box = svdag::sliceBox(v, this->Axis, this->Index);
      std::copy(box.begin(), box.end(), out.Extent);
    }
    catch (const std::exception& e)
    {
      error = e.what();
      return false;
    }
    std::copy(g.spacing.begin(), g.spacing.end(), out.Spacing);
    std::copy(g.origin.begin(), g.origin.end(), out.Origin);
    std::copy(g.direction.begin(), g.direction.end(), out.Direction);
    return true;
  }

  // Oblique: the grid in world space first, then the same grid in index space for the core.
  Vec n{ { this->PlaneNormal[0], this->PlaneNormal[1], this->PlaneNormal[2] } };
  if (!Normalize(n))
  {
    error = "the plane normal must be finite and not (0, 0, 0)";
    return false;
  }
  const Vec o{ { this->PlaneOrigin[0], this->PlaneOrigin[1], this->PlaneOrigin[2] } };
  if (!std::isfinite(o[0]) || !std::isfinite(o[1]) || !std::isfinite(o[2]))
  {
    error = "the plane origin must be finite";
    return false;
  }
  // World direction of each index axis: the columns of the row-major direction matrix.
  const auto& D = g.direction;
  const Vec axes[3] = { { { D[0], D[3], D[6] } }, { { D[1], D[4], D[7] } },
    { { D[2], D[5], D[8] } } };
  Vec u{ { this->PlaneXAxis[0], this->PlaneXAxis[1], this->PlaneXAxis[2] } };
  const bool automatic = u[0] == 0 && u[1] == 0 && u[2] == 0;
  if (automatic)
  {
    int best = 0;
    for (int a = 1; a < 3; ++a)
      if (std::fabs(Dot(axes[a], n)) < std::fabs(Dot(axes[best], n)))
        best = a;
    u = axes[best];
  }
  const double along = Dot(u, n);
  for (int i = 0; i < 3; ++i)
    u[i] -= along * n[i];
  if (!Normalize(u) || std::fabs(along) > 1 - 1e-9)
  {
    error = "the plane x axis must be finite and not along the plane normal";
    return false;
  }
  const Vec w = Cross(n, u);
  double su = this->OutputSpacing[0], sv = this->OutputSpacing[1];
  const double smallest = *std::min_element(g.spacing.begin(), g.spacing.end());
  if (su == 0)
    su = smallest;
  if (sv == 0)
    sv = smallest;
  if (!(su > 0) || !(sv > 0) || !std::isfinite(su) || !std::isfinite(sv))
  {
    error = "the output spacing must be positive and finite (0: automatic)";
    return false;
  }

  Vec corner;
  int nu = this->OutputDimensions[0], nv = this->OutputDimensions[1];
  if (nu < 0 || nv < 0)
  {
    error = "the output dimensions must not be negative";
    return false;
  }
  if (nu > 0 && nv > 0)
  {
    for (int i = 0; i < 3; ++i)
      corner[i] = o[i] - 0.5 * (nu - 1) * su * u[i] - 0.5 * (nv - 1) * sv * w[i];
  }
  else
  {
    // Cover the projection of the 8 outermost voxel centers.
    double aMin = std::numeric_limits<double>::max(), aMax = -aMin, bMin = aMin, bMax = -aMin;
    for (int c = 0; c < 8; ++c)
    {
      Vec p = { { g.origin[0], g.origin[1], g.origin[2] } };
      for (int a = 0; a < 3; ++a)
      {
        const double t = ((c >> a) & 1) ? double(g.dims[a] - 1) * g.spacing[a] : 0.0;
        for (int i = 0; i < 3; ++i)
          p[i] += t * axes[a][i];
      }
      const Vec rel{ { p[0] - o[0], p[1] - o[1], p[2] - o[2] } };
      aMin = std::min(aMin, Dot(rel, u));
      aMax = std::max(aMax, Dot(rel, u));
      bMin = std::min(bMin, Dot(rel, w));
      bMax = std::max(bMax, Dot(rel, w));
    }
    const double cu = std::floor((aMax - aMin) / su + 1e-9) + 1;
    const double cv = std::floor((bMax - bMin) / sv + 1e-9) + 1;
    if (!(cu < double(1 << 30)) || !(cv < double(1 << 30)))
    {
      error = "the plane would need more than 2^30 samples along an axis; set OutputDimensions "
              "or a larger OutputSpacing";
      return false;
    }
    nu = int(cu);
    nv = int(cv);
    for (int i = 0; i < 3; ++i)
      corner[i] = o[i] + aMin * u[i] + bMin * w[i];
  }

  std::array<double, 9> inverse;
  if (!Invert(D, inverse))
  {
    error = "the volume's direction matrix is singular";
    return false;
  }
  // World point p -> continuous index: (D^-1 (p - origin)) / spacing, per axis.
  auto toIndex = [&](const Vec& p, bool point) {
    Vec r;
    for (int a = 0; a < 3; ++a)
    {
      double s = 0;
      for (int i = 0; i < 3; ++i)
        s += inverse[3 * a + i] * (point ? p[i] - g.origin[i] : p[i]);
      r[a] = s / g.spacing[a];
    }
    return r;
  };
  out.Plane.origin = toIndex(corner, true);
  out.Plane.uStep = toIndex({ { su * u[0], su * u[1], su * u[2] } }, false);
  out.Plane.vStep = toIndex({ { sv * w[0], sv * w[1], sv * w[2] } }, false);
  out.Plane.nu = nu;
  out.Plane.nv = nv;
  try
  {
    svdag::checkPlaneSampling(v, out.Plane);
  }
  catch (const std::exception& e)
  {
    error = e.what();
    return false;
  }
  const int extent[6] = { 0, nu - 1, 0, nv - 1, 0, 0 };
  std::copy(extent, extent + 6, out.Extent);
  out.Spacing[0] = su;
  out.Spacing[1] = sv;
  out.Spacing[2] = 1;
  std::copy(corner.begin(), corner.end(), out.Origin);
  const double direction[9] = { u[0], w[0], n[0], u[1], w[1], n[1], u[2], w[2], n[2] };
  std::copy(direction, direction + 9, out.Direction);
  return true;
}

int vtkSegmentationSVDAGSlice::RequestInformation(
  vtkInformation*, vtkInformationVector** in, vtkInformationVector* out)
{
  vtkSegmentationSVDAG* input = vtkSegmentationSVDAG::GetData(in[0]);
  if (!input || !input->HasVolume())
  {
    // The input's data only exists after it executes; RequestData checks again.
    return 1;
  }
  OutputGeometry g;
  std::string error;
  if (!this->ComputeOutputGeometry(input, g, error))
  {
    vtkErrorMacro("Cannot slice the volume: " << error);
    return 0;
  }
  vtkInformation* info = out->GetInformationObject(0);
  info->Set(vtkStreamingDemandDrivenPipeline::WHOLE_EXTENT(), g.Extent, 6);
  info->Set(vtkDataObject::SPACING(), g.Spacing, 3);
  info->Set(vtkDataObject::ORIGIN(), g.Origin, 3);
  info->Set(vtkDataObject::DIRECTION(), g.Direction, 9);
  vtkDataObject::SetPointDataActiveScalarInfo(info, input->GetLabelScalarType(), 1);
  return 1;
}

int vtkSegmentationSVDAGSlice::RequestUpdateExtent(
  vtkInformation*, vtkInformationVector**, vtkInformationVector*)
{
  // The input is one data object, not an image: there is no extent to ask for upstream.
  return 1;
}

int vtkSegmentationSVDAGSlice::RequestData(
  vtkInformation*, vtkInformationVector** in, vtkInformationVector* out)
{
  vtkSegmentationSVDAG* input = vtkSegmentationSVDAG::GetData(in[0]);
  vtkImageData* output = vtkImageData::GetData(out);
  output->Initialize();
  if (!input || !input->HasVolume())
  {
    vtkErrorMacro("The input holds no compressed volume.");
    return 0;
  }
  OutputGeometry g;
  std::string error;
  if (!this->ComputeOutputGeometry(input, g, error))
  {
    vtkErrorMacro("Cannot slice the volume: " << error);
    return 0;
  }
  const svdag::Volume& v = *input->GetVolume();
  if (this->Mode == AXIS_ALIGNED)
  {
    if (!input->DecodeExtentTo(g.Extent, output, error))
    {
      vtkErrorMacro("Decoding the slice failed: " << error);
      return 0;
    }
    this->UpdateProgress(1.0);
    return 1;
  }
  vtkDataArray* labels = vtkDataArray::CreateDataArray(input->GetLabelScalarType());
  try
  {
    labels->SetNumberOfTuples(vtkIdType(g.Plane.nu) * vtkIdType(g.Plane.nv));
    labels->SetName("Labels");
    svdag::resamplePlane(v, g.Plane, labels->GetVoidPointer(0), vtkSVDAGParallelFor());
  }
  catch (const std::exception& e)
  {
    labels->Delete();
    vtkErrorMacro("Resampling the plane failed: " << e.what());
    return 0;
  }
  output->SetExtent(g.Extent);
  output->SetSpacing(g.Spacing);
  output->SetOrigin(g.Origin);
  output->SetDirectionMatrix(g.Direction);
  output->GetPointData()->SetScalars(labels);
  labels->Delete();
  this->UpdateProgress(1.0);
  return 1;
}

void vtkSegmentationSVDAGSlice::PrintSelf(ostream& os, vtkIndent indent)
{
  this->Superclass::PrintSelf(os, indent);
  os << indent << "Mode: " << (this->Mode == AXIS_ALIGNED ? "AxisAligned" : "Oblique") << "\n";
  os << indent << "Axis: " << this->Axis << "\n";
  os << indent << "Index: " << this->Index << "\n";
  os << indent << "PlaneOrigin: " << this->PlaneOrigin[0] << " " << this->PlaneOrigin[1] << " "
     << this->PlaneOrigin[2] << "\n";
  os << indent << "PlaneNormal: " << this->PlaneNormal[0] << " " << this->PlaneNormal[1] << " "
     << this->PlaneNormal[2] << "\n";
  os << indent << "PlaneXAxis: " << this->PlaneXAxis[0] << " " << this->PlaneXAxis[1] << " "
     << this->PlaneXAxis[2] << "\n";
  os << indent << "OutputDimensions: " << this->OutputDimensions[0] << " "
     << this->OutputDimensions[1] << "\n";
  os << indent << "OutputSpacing: " << this->OutputSpacing[0] << " " << this->OutputSpacing[1]
     << "\n";
}
