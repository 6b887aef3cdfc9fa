#include "vtkSegmentationSVDAGStreamBuilder.h"

#include "vtkCommand.h"
#include "vtkDataArray.h"
#include "vtkObjectFactory.h"
#include "vtkSVDAGParallel.h"
#include "vtkSegmentationSVDAG.h"

#include "svdag/Builder.h"

#include <algorithm>
#include <cstring>
#include <exception>
#include <memory>
#include <stdexcept>
#include <string>

vtkStandardNewMacro(vtkSegmentationSVDAGStreamBuilder);

struct vtkSegmentationSVDAGStreamBuilder::Internals
{
  svdag::Geometry Geometry;
  svdag::ScalarType Type = svdag::ScalarType::UInt8;
  std::unique_ptr<svdag::Builder> Builder; // null when not initialized (or finished)
  size_t SliceBytes = 0;
  // The trailing partial slab of the calls so far: Buffered slices starting at the builder's
  // next slab. Allocated on first use, one slab at most, released by Finish.
  std::vector<uint8_t> Buffer;
  int32_t Buffered = 0;

  int32_t NextSlice() const
  {
    return this->Builder ? this->Builder->nextSlab() + this->Buffered : 0;
  }
  // Depth of the slab starting at the builder's next slab (the last slab may be shorter).
  int32_t SlabDepth() const
  {
    return std::min(svdag::Builder::SlabDepth, this->Geometry.dims[2] - this->Builder->nextSlab());
  }
};

vtkSegmentationSVDAGStreamBuilder::vtkSegmentationSVDAGStreamBuilder()
  : Internal(new Internals)
{
}

vtkSegmentationSVDAGStreamBuilder::~vtkSegmentationSVDAGStreamBuilder() = default;

void vtkSegmentationSVDAGStreamBuilder::AddExcludedLabel(vtkTypeInt64 label)
{
  this->ExcludedLabels.push_back(label);
  this->Modified();
}

void vtkSegmentationSVDAGStreamBuilder::RemoveAllExcludedLabels()
{
  if (!this->ExcludedLabels.empty())
  {
    this->ExcludedLabels.clear();
    this->Modified();
  }
}

vtkIdType vtkSegmentationSVDAGStreamBuilder::GetNumberOfExcludedLabels() const
{
  return static_cast<vtkIdType>(this->ExcludedLabels.size());
}

vtkTypeInt64 vtkSegmentationSVDAGStreamBuilder::GetExcludedLabel(vtkIdType i) const
{
  return (i >= 0 && i < this->GetNumberOfExcludedLabels()) ? this->ExcludedLabels[size_t(i)] : 0;
}

bool vtkSegmentationSVDAGStreamBuilder::Initialize(const int dims[3], int scalarType)
{
  const double spacing[3] = { 1, 1, 1 };
  const double origin[3] = { 0, 0, 0 };
  return this->Initialize(dims, scalarType, spacing, origin);
}

bool vtkSegmentationSVDAGStreamBuilder::Initialize(
  const int dims[3], int scalarType, const double spacing[3], const double origin[3])
{
  const double identity[9] = { 1, 0, 0, 0, 1, 0, 0, 0, 1 };
  return this->Initialize(dims, scalarType, spacing, origin, identity);
}

bool vtkSegmentationSVDAGStreamBuilder::Initialize(const int dims[3], int scalarType,
  const double spacing[3], const double origin[3], const double direction[9])
{
  Internals& m = *this->Internal;
  // A volume in progress is discarded first, so a failed Initialize never leaves the previous
  // volume half-fed.
  m.Builder.reset();
  m.Buffer = std::vector<uint8_t>();
  m.Buffered = 0;
  this->Progress = 0.0;
  if (!dims || !spacing || !origin || !direction)
  {
    vtkErrorMacro("Initialize needs dimensions, spacing, origin and direction.");
    return false;
  }
  const int coreType = vtkSegmentationSVDAG::FromVTKScalarType(scalarType);
  if (coreType < 0)
  {
    vtkErrorMacro("Label volumes need an integer scalar type, not VTK type " << scalarType << ".");
    return false;
  }
  svdag::Geometry geometry;
  for (int a = 0; a < 3; ++a)
  {
    geometry.dims[a] = dims[a];
    geometry.spacing[a] = spacing[a];
    geometry.origin[a] = origin[a];
  }
  std::copy(direction, direction + 9, geometry.direction.begin());
  // The same options as vtkSegmentationSVDAGAlgorithm::GetBuildOptions, for identical output.
  svdag::BuildOptions options;
  options.background = static_cast<uint64_t>(this->BackgroundLabel);
  for (vtkTypeInt64 label : this->ExcludedLabels)
    options.excluded.push_back(static_cast<uint64_t>(label));
  try
  {
    const auto type = static_cast<svdag::ScalarType>(coreType);
    // checkGeometry (in the constructor) bounds the cell count, so the slice size below fits.
    m.Builder.reset(new svdag::Builder(geometry, type, options, vtkSVDAGParallelFor()));
    m.Geometry = geometry;
    m.Type = type;
    m.SliceBytes = size_t(dims[0]) * size_t(dims[1]) * size_t(svdag::scalarSize(type));
  }
  catch (const std::exception& e)
  {
    m.Builder.reset();
    vtkErrorMacro("Cannot start the volume: " << e.what());
    return false;
  }
  this->Modified();
  return true;
}

bool vtkSegmentationSVDAGStreamBuilder::IsInitialized() const
{
  return this->Internal->Builder != nullptr;
}

int vtkSegmentationSVDAGStreamBuilder::GetNextSlice() const
{
  return this->Internal->NextSlice();
}

bool vtkSegmentationSVDAGStreamBuilder::AddSlab(vtkDataArray* values)
{
  return this->AddSlices(values, -1, -1);
}

bool vtkSegmentationSVDAGStreamBuilder::AddSlab(vtkDataArray* values, int z0)
{
  if (z0 < 0)
  {
    vtkErrorMacro("The first slice index must not be negative (got " << z0 << ").");
    return false;
  }
  return this->AddSlices(values, z0, -1);
}

bool vtkSegmentationSVDAGStreamBuilder::AddSlab(vtkDataArray* values, int z0, int nz)
{
  if (z0 < 0 || nz < 1)
  {
    vtkErrorMacro("Slices need a first index >= 0 and a count >= 1 (got z0 = "
      << z0 << ", nz = " << nz << ").");
    return false;
  }
  return this->AddSlices(values, z0, nz);
}

// z0 and nz are -1 when the caller did not give them.
bool vtkSegmentationSVDAGStreamBuilder::AddSlices(vtkDataArray* values, int z0, int nz)
{
  Internals& m = *this->Internal;
  if (!m.Builder)
  {
    vtkErrorMacro("AddSlab before Initialize (or after Finish).");
    return false;
  }
  if (!values)
  {
    vtkErrorMacro("AddSlab needs an array of label values.");
    return false;
  }
  const int coreType = vtkSegmentationSVDAG::FromVTKScalarType(values->GetDataType());
  if (coreType != int(m.Type) || values->GetNumberOfComponents() != 1)
  {
    vtkErrorMacro("The slices must have one component of type "
      << svdag::scalarName(m.Type) << "; array '" << (values->GetName() ? values->GetName() : "")
      << "' has " << values->GetNumberOfComponents() << " component(s) of type "
      << values->GetDataTypeAsString() << ".");
    return false;
  }
  const int32_t next = m.NextSlice();
  const int32_t depth = m.Geometry.dims[2];
  const vtkIdType sliceValues = vtkIdType(m.Geometry.dims[0]) * m.Geometry.dims[1];
  const vtkIdType tuples = values->GetNumberOfTuples();
  if (tuples < 1 || tuples % sliceValues != 0 || (nz > 0 && tuples != sliceValues * nz))
  {
    const std::string need = nz > 0
      ? std::to_string(nz) + " slices need " + std::to_string(sliceValues * nz)
      : "whole slices need a positive multiple of " + std::to_string(sliceValues);
    vtkErrorMacro("The array has " << tuples << " values; in a volume of " << m.Geometry.dims[0]
                                   << " x " << m.Geometry.dims[1] << " voxels per slice, " << need
                                   << ".");
    return false;
  }
  const vtkIdType count = tuples / sliceValues;
  if (z0 >= 0 && z0 != next)
  {
    vtkErrorMacro("Slices out of order: got slices from z = " << z0 << ", expected z = " << next
                                                              << ".");
    return false;
  }
  if (count > vtkIdType(depth - next))
  {
    vtkErrorMacro("Too many slices: " << count << " from z = " << next << " in a volume of "
                                      << depth << " slices (" << (depth - next) << " missing).");
    return false;
  }

  const auto* data = static_cast<const uint8_t*>(values->GetVoidPointer(0));
  int32_t remaining = int32_t(count);
  try
  {
    while (remaining > 0)
    {
      const int32_t z = m.Builder->nextSlab();
      const int32_t slab = m.SlabDepth();
      if (m.Buffered == 0 && remaining >= slab)
      {
        // A whole slab in the caller's array: no copy.
        m.Builder->addSlab(z, slab, data);
        data += size_t(slab) * m.SliceBytes;
        remaining -= slab;
      }
      else
      {
        const int32_t take = std::min(remaining, slab - m.Buffered);
        if (m.Buffer.empty())
          m.Buffer.resize(size_t(svdag::Builder::SlabDepth) * m.SliceBytes);
        std::memcpy(m.Buffer.data() + size_t(m.Buffered) * m.SliceBytes, data,
          size_t(take) * m.SliceBytes);
        data += size_t(take) * m.SliceBytes;
        remaining -= take;
        m.Buffered += take;
        if (m.Buffered < slab)
          break;
        m.Builder->addSlab(z, slab, m.Buffer.data());
        m.Buffered = 0;
      }
      this->Progress = double(m.Builder->nextSlab()) / depth;
      this->InvokeEvent(vtkCommand::ProgressEvent, &this->Progress);
    }
  }
  catch (const std::exception& e)
  {
    // Only a core failure gets here (the checks above match addSlab's): the pools may be
    // inconsistent now, so the volume is dropped rather than continued.
    m.Builder.reset();
    m.Buffer = std::vector<uint8_t>();
    m.Buffered = 0;
    vtkErrorMacro("Cannot compress the slices: " << e.what() << " (the volume was discarded).");
    return false;
  }
  this->Modified();
  return true;
}

bool vtkSegmentationSVDAGStreamBuilder::AddVolume(vtkSegmentationSVDAG* part)
{
  Internals& m = *this->Internal;
  if (!m.Builder)
  {
    vtkErrorMacro("AddVolume before Initialize (or after Finish).");
    return false;
  }
  if (!part || !part->GetVolume())
  {
    vtkErrorMacro("AddVolume needs a vtkSegmentationSVDAG that holds a volume.");
    return false;
  }
  if (m.Buffered != 0)
  {
    vtkErrorMacro("Cannot append a volume at z = " << m.NextSlice()
                                                   << ": the slices added so far do not end on a "
                                                      "16-slice slab.");
    return false;
  }
  try
  {
    m.Builder->addVolume(*part->GetVolume());
  }
  catch (const std::logic_error& e) // also std::invalid_argument: nothing was changed
  {
    vtkErrorMacro("Cannot append the volume: " << e.what() << ".");
    return false;
  }
  catch (const std::exception& e)
  {
    m.Builder.reset();
    m.Buffer = std::vector<uint8_t>();
    vtkErrorMacro("Cannot append the volume: " << e.what() << " (the volume was discarded).");
    return false;
  }
  this->Progress = double(m.Builder->nextSlab()) / m.Geometry.dims[2];
  this->InvokeEvent(vtkCommand::ProgressEvent, &this->Progress);
  this->Modified();
  return true;
}

bool vtkSegmentationSVDAGStreamBuilder::Finish(vtkSegmentationSVDAG* output)
{
  Internals& m = *this->Internal;
  if (!output)
  {
    vtkErrorMacro("Finish needs an output vtkSegmentationSVDAG.");
    return false;
  }
  if (!m.Builder)
  {
    vtkErrorMacro("Finish before Initialize (or a second Finish).");
    return false;
  }
  const int32_t next = m.NextSlice();
  if (next != m.Geometry.dims[2])
  {
    vtkErrorMacro("Cannot finish: " << (m.Geometry.dims[2] - next) << " of " << m.Geometry.dims[2]
                                    << " slices are missing (next slice z = " << next << ").");
    return false;
  }
  try
  {
    output->SetVolume(std::make_shared<const svdag::Volume>(m.Builder->finish()));
  }
  catch (const std::exception& e)
  {
    vtkErrorMacro("Cannot compress the label volume: " << e.what());
    m.Builder.reset();
    return false;
  }
  m.Builder.reset();
  m.Buffer = std::vector<uint8_t>();
  m.Buffered = 0;
  this->Progress = 1.0;
  this->Modified();
  return true;
}

void vtkSegmentationSVDAGStreamBuilder::PrintSelf(ostream& os, vtkIndent indent)
{
  this->Superclass::PrintSelf(os, indent);
  const Internals& m = *this->Internal;
  os << indent << "BackgroundLabel: " << this->BackgroundLabel << "\n";
  os << indent << "ExcludedLabels:";
  for (vtkTypeInt64 label : this->ExcludedLabels)
    os << " " << label;
  os << "\n";
  os << indent << "Initialized: " << (m.Builder ? "yes" : "no") << "\n";
  if (m.Builder)
  {
    os << indent << "Dimensions: " << m.Geometry.dims[0] << " " << m.Geometry.dims[1] << " "
       << m.Geometry.dims[2] << "\n";
    os << indent << "ScalarType: " << svdag::scalarName(m.Type) << "\n";
    os << indent << "NextSlice: " << m.NextSlice() << "\n";
    os << indent << "BufferedSlices: " << m.Buffered << "\n";
  }
  os << indent << "Progress: " << this->Progress << "\n";
}
