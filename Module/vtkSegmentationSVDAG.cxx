#include "vtkSegmentationSVDAG.h"

#include "vtkDataArray.h"
#include "vtkDoubleArray.h"
#include "vtkIdTypeArray.h"
#include "vtkUnsignedCharArray.h"
#include "vtkImageData.h"
#include "vtkInformation.h"
#include "vtkInformationVector.h"
#include "vtkMatrix3x3.h"
#include "vtkObjectFactory.h"
#include "vtkPointData.h"
#include "vtkNew.h"
#include "vtkSVDAGParallel.h"
#include "vtkStringArray.h"
#include "vtkTable.h"
#include "vtkTypeInt64Array.h"
#include "vtkType.h"

#include "svdag/Decoder.h"
#include "svdag/EncodingAnalysis.h"
#include "svdag/LabelAdjacency.h"
#include "svdag/LabelColoring.h"
#include "svdag/LabelStatistics.h"
#include "svdag/Palette.h"
#include "svdag/RandomAccess.h"
#include "svdag/Volume.h"

#include <new>
#include <stdexcept>
#include <string>
#include <type_traits>

vtkStandardNewMacro(vtkSegmentationSVDAG);

namespace
{
const int VTKTypes[svdag::ScalarTypeCount] = { VTK_SIGNED_CHAR, VTK_UNSIGNED_CHAR, VTK_SHORT,
  VTK_UNSIGNED_SHORT, VTK_INT, VTK_UNSIGNED_INT, VTK_LONG_LONG, VTK_UNSIGNED_LONG_LONG };

vtkDataArray* NewArrayOf(svdag::ScalarType type, vtkIdType n)
{
  vtkDataArray* a = vtkDataArray::CreateDataArray(VTKTypes[int(type)]);
  a->SetNumberOfTuples(n);
  return a;
}
} // namespace

vtkSegmentationSVDAG::vtkSegmentationSVDAG() = default;
vtkSegmentationSVDAG::~vtkSegmentationSVDAG() = default;

int vtkSegmentationSVDAG::ToVTKScalarType(int coreType)
{
  return (coreType >= 0 && coreType < svdag::ScalarTypeCount) ? VTKTypes[coreType] : -1;
}

int vtkSegmentationSVDAG::FromVTKScalarType(int vtkType)
{
  // VTK_CHAR's signedness is platform-defined; VTK_LONG and VTK_ID_TYPE are 64-bit here.
  switch (vtkType)
  {
    case VTK_CHAR: return int(std::is_signed<char>::value ? svdag::ScalarType::Int8 : svdag::ScalarType::UInt8);
    case VTK_SIGNED_CHAR: return int(svdag::ScalarType::Int8);
    case VTK_UNSIGNED_CHAR: return int(svdag::ScalarType::UInt8);
    case VTK_SHORT: return int(svdag::ScalarType::Int16);
    case VTK_UNSIGNED_SHORT: return int(svdag::ScalarType::UInt16);
    case VTK_INT: return int(svdag::ScalarType::Int32);
    case VTK_UNSIGNED_INT: return int(svdag::ScalarType::UInt32);
    case VTK_LONG: return int(sizeof(long) == 8 ? svdag::ScalarType::Int64 : svdag::ScalarType::Int32);
    case VTK_UNSIGNED_LONG: return int(sizeof(long) == 8 ? svdag::ScalarType::UInt64 : svdag::ScalarType::UInt32);
    case VTK_LONG_LONG: return int(svdag::ScalarType::Int64);
    case VTK_UNSIGNED_LONG_LONG: return int(svdag::ScalarType::UInt64);
    case VTK_ID_TYPE: return int(sizeof(vtkIdType) == 8 ? svdag::ScalarType::Int64 : svdag::ScalarType::Int32);
    default: return -1;
  }
}

void vtkSegmentationSVDAG::Initialize()
{
  this->Superclass::Initialize();
  this->Volume.reset();
  this->Modified();
}

void vtkSegmentationSVDAG::SetVolume(std::shared_ptr<const svdag::Volume> volume)
{
  this->Volume = std::move(volume);
  this->Modified();
}

void vtkSegmentationSVDAG::ShallowCopy(vtkDataObject* src)
{
  if (auto* other = vtkSegmentationSVDAG::SafeDownCast(src))
  {
    this->Superclass::ShallowCopy(src);
    this->SetVolume(other->Volume);
  }
  else
  {
    vtkErrorMacro("ShallowCopy: source is not a vtkSegmentationSVDAG");
  }
}

void vtkSegmentationSVDAG::DeepCopy(vtkDataObject* src)
{
  if (auto* other = vtkSegmentationSVDAG::SafeDownCast(src))
  {
    this->Superclass::DeepCopy(src);
    this->SetVolume(other->Volume ? std::make_shared<const svdag::Volume>(*other->Volume) : nullptr);
  }
  else
  {
    vtkErrorMacro("DeepCopy: source is not a vtkSegmentationSVDAG");
  }
}

unsigned long vtkSegmentationSVDAG::GetActualMemorySize()
{
  unsigned long kib = this->Superclass::GetActualMemorySize();
  if (this->Volume)
  {
    const svdag::Volume& v = *this->Volume;
    const uint64_t bytes = (v.blocks.size() + v.roots.size() + v.mids.size()) * 4 +
      v.leaves.size() * 8 + v.labels.size() * sizeof(svdag::LabelInfo);
    kib += static_cast<unsigned long>((bytes + 1023) / 1024);
  }
  return kib;
}

void vtkSegmentationSVDAG::GetDimensions(int dims[3]) const
{
  for (int a = 0; a < 3; ++a)
    dims[a] = this->Volume ? this->Volume->geometry.dims[a] : 0;
}

void vtkSegmentationSVDAG::GetSpacing(double spacing[3]) const
{
  for (int a = 0; a < 3; ++a)
    spacing[a] = this->Volume ? this->Volume->geometry.spacing[a] : 1.0;
}

void vtkSegmentationSVDAG::GetOrigin(double origin[3]) const
{
  for (int a = 0; a < 3; ++a)
    origin[a] = this->Volume ? this->Volume->geometry.origin[a] : 0.0;
}

void vtkSegmentationSVDAG::GetDirection(double direction[9]) const
{
  const svdag::Geometry identity;
  const auto& d = this->Volume ? this->Volume->geometry.direction : identity.direction;
  std::copy(d.begin(), d.end(), direction);
}

vtkIdType vtkSegmentationSVDAG::GetNumberOfVoxels() const
{
  return this->Volume ? static_cast<vtkIdType>(this->Volume->geometry.voxelCount()) : 0;
}

int vtkSegmentationSVDAG::GetLabelScalarType() const
{
  return this->Volume ? VTKTypes[int(this->Volume->scalarType)] : VTK_VOID;
}

vtkIdType vtkSegmentationSVDAG::GetNumberOfLabels() const
{
  return this->Volume ? static_cast<vtkIdType>(this->Volume->labels.size()) : 0;
}

vtkDataArray* vtkSegmentationSVDAG::NewLabelValues() const
{
  if (!this->Volume)
    return nullptr;
  const svdag::Volume& v = *this->Volume;
  vtkDataArray* a = NewArrayOf(v.scalarType, static_cast<vtkIdType>(v.labels.size()));
  a->SetName("LabelValues");
  for (size_t i = 0; i < v.labels.size(); ++i)
    svdag::scalarStore(v.scalarType, a->GetVoidPointer(0), i, v.labels[i].value);
  return a;
}

vtkDataArray* vtkSegmentationSVDAG::NewBackgroundValue() const
{
  if (!this->Volume)
    return nullptr;
  vtkDataArray* a = NewArrayOf(this->Volume->scalarType, 1);
  a->SetName("Background");
  svdag::scalarStore(this->Volume->scalarType, a->GetVoidPointer(0), 0, this->Volume->background);
  return a;
}

vtkIdType vtkSegmentationSVDAG::GetLabelVoxelCount(vtkIdType index) const
{
  if (!this->Volume || index < 0 || index >= this->GetNumberOfLabels())
  {
    vtkErrorMacro("GetLabelVoxelCount: label index " << index << " out of range");
    return 0;
  }
  return static_cast<vtkIdType>(this->Volume->labels[size_t(index)].voxels);
}

void vtkSegmentationSVDAG::GetLabelBounds(vtkIdType index, int bounds[6]) const
{
  if (!this->Volume || index < 0 || index >= this->GetNumberOfLabels())
  {
    vtkErrorMacro("GetLabelBounds: label index " << index << " out of range");
    std::fill(bounds, bounds + 6, 0);
    return;
  }
  const auto& b = this->Volume->labels[size_t(index)].bounds;
  std::copy(b.begin(), b.end(), bounds);
}

vtkIdType vtkSegmentationSVDAG::GetLabelIndexAt(int i, int j, int k) const
{
  if (!this->Volume)
    return -1;
  const auto& d = this->Volume->geometry.dims;
  if (i < 0 || j < 0 || k < 0 || i >= d[0] || j >= d[1] || k >= d[2])
  {
    vtkErrorMacro("GetLabelIndexAt: voxel (" << i << ", " << j << ", " << k
                                             << ") is outside the volume");
    return -1;
  }
  const uint64_t value = this->Volume->labelAt(i, j, k);
  if (value == this->Volume->background)
    return -1;
  return static_cast<vtkIdType>(this->Volume->findLabel(value));
}

vtkIdType vtkSegmentationSVDAG::GetNumberOfBlocks() const
{
  return this->Volume ? static_cast<vtkIdType>(this->Volume->blockCount) : 0;
}

vtkIdType vtkSegmentationSVDAG::GetNumberOfRootNodes() const
{
  return this->Volume ? static_cast<vtkIdType>(this->Volume->rootCount) : 0;
}

vtkIdType vtkSegmentationSVDAG::GetNumberOfMidNodes() const
{
  return this->Volume ? static_cast<vtkIdType>(this->Volume->midCount) : 0;
}

vtkIdType vtkSegmentationSVDAG::GetNumberOfLeaves() const
{
  return this->Volume ? static_cast<vtkIdType>(this->Volume->leaves.size()) : 0;
}

vtkIdType vtkSegmentationSVDAG::GetNumberOfDAGNodes() const
{
  return this->GetNumberOfRootNodes() + this->GetNumberOfMidNodes() + this->GetNumberOfLeaves();
}

vtkTypeInt64 vtkSegmentationSVDAG::GetBlocksMemorySize() const
{
  return this->Volume ? static_cast<vtkTypeInt64>(this->Volume->memory().blocks) : 0;
}

vtkTypeInt64 vtkSegmentationSVDAG::GetDAGMemorySize() const
{
  return this->Volume ? static_cast<vtkTypeInt64>(this->Volume->memory().dag()) : 0;
}

vtkTypeInt64 vtkSegmentationSVDAG::GetLabelTableMemorySize() const
{
  return this->Volume ? static_cast<vtkTypeInt64>(this->Volume->memory().labels) : 0;
}

vtkTypeInt64 vtkSegmentationSVDAG::GetCompressedSize() const
{
  return this->Volume ? static_cast<vtkTypeInt64>(this->Volume->memory().total()) : 0;
}

bool vtkSegmentationSVDAG::DecodeTo(vtkImageData* image) const
{
  std::string error;
  if (this->DecodeTo(image, error))
    return true;
  vtkErrorMacro("DecodeTo: " << error);
  return false;
}

bool vtkSegmentationSVDAG::DecodeTo(vtkImageData* image, std::string& error) const
{
  if (!this->Volume || !image)
  {
    error = image ? "no compressed volume" : "no output image";
    return false;
  }
  const svdag::Volume& v = *this->Volume;
  const auto& g = v.geometry;
  image->Initialize();
  vtkDataArray* labels = nullptr;
  try
  {
    // Refused before allocating when the dense array cannot fit (a tiny file of a huge volume);
    // a failed allocation (VTK throws std::bad_alloc) is reported the same way.
    svdag::checkDecodeMemory(v);
    const uint64_t bytes = svdag::decodedBytes(v);
    try
    {
      labels = NewArrayOf(v.scalarType, static_cast<vtkIdType>(g.voxelCount()));
    }
    catch (const std::bad_alloc&)
    {
      throw std::length_error("decoding " + std::to_string(g.dims[0]) + " x " +
        std::to_string(g.dims[1]) + " x " + std::to_string(g.dims[2]) + " " +
        svdag::scalarName(v.scalarType) + " voxels needs " + std::to_string(bytes) + " bytes (" +
        svdag::formatBytes(bytes) + "), and that much memory is not available");
    }
    if (labels->GetNumberOfTuples() != static_cast<vtkIdType>(g.voxelCount()))
      throw std::length_error("cannot allocate " + std::to_string(bytes) + " bytes (" +
        svdag::formatBytes(bytes) + ") for the decoded labels");
    labels->SetName("Labels");
    svdag::decode(v, labels->GetVoidPointer(0), vtkSVDAGParallelFor());
  }
  catch (const std::exception& e)
  {
    if (labels)
      labels->Delete();
    error = e.what();
    return false;
  }
  image->SetDimensions(g.dims[0], g.dims[1], g.dims[2]);
  image->SetSpacing(g.spacing[0], g.spacing[1], g.spacing[2]);
  image->SetOrigin(g.origin[0], g.origin[1], g.origin[2]);
  image->SetDirectionMatrix(g.direction.data());
  image->GetPointData()->SetScalars(labels);
  labels->Delete();
  return true;
}

namespace
{
// An image holding `box` of the volume's geometry, with `scalars` (a new array, handed over).
void SetBoxImage(vtkImageData* image, const svdag::Geometry& g, const svdag::Box& box,
  vtkDataArray* scalars)
{
  image->Initialize();
  image->SetExtent(box[0], box[1], box[2], box[3], box[4], box[5]);
  image->SetSpacing(g.spacing[0], g.spacing[1], g.spacing[2]);
  image->SetOrigin(g.origin[0], g.origin[1], g.origin[2]);
  image->SetDirectionMatrix(g.direction.data());
  image->GetPointData()->SetScalars(scalars);
  scalars->Delete();
}

// A new array of `n` values of `type` (a vtkDataArray type id), or a std::length_error.
vtkDataArray* NewOutputArray(int vtkType, uint64_t n, uint64_t valueBytes, const char* name)
{
  svdag::checkOutputMemory(n * valueBytes, std::string("the ") + name + " array of " +
      std::to_string(n) + " values");
  vtkDataArray* a = nullptr;
  try
  {
    a = vtkDataArray::CreateDataArray(vtkType);
    a->SetNumberOfTuples(static_cast<vtkIdType>(n));
  }
  catch (const std::bad_alloc&)
  {
    if (a)
      a->Delete();
    throw std::length_error(std::string("cannot allocate the ") + name + " array of " +
      std::to_string(n) + " values");
  }
  if (a->GetNumberOfTuples() != static_cast<vtkIdType>(n))
  {
    a->Delete();
    throw std::length_error(std::string("cannot allocate the ") + name + " array of " +
      std::to_string(n) + " values");
  }
  a->SetName(name);
  return a;
}
} // namespace

bool vtkSegmentationSVDAG::DecodeExtentTo(const int extent[6], vtkImageData* image) const
{
  std::string error;
  if (this->DecodeExtentTo(extent, image, error))
    return true;
  vtkErrorMacro("DecodeExtentTo: " << error);
  return false;
}

bool vtkSegmentationSVDAG::DecodeExtentTo(
  const int extent[6], vtkImageData* image, std::string& error) const
{
  if (!this->Volume || !image || !extent)
  {
    error = !this->Volume ? "no compressed volume" : !image ? "no output image" : "no extent";
    return false;
  }
  const svdag::Volume& v = *this->Volume;
  const svdag::Box box{ { extent[0], extent[1], extent[2], extent[3], extent[4], extent[5] } };
  try
  {
    svdag::checkBox(v, box, "DecodeExtentTo");
    vtkDataArray* labels = NewOutputArray(VTKTypes[int(v.scalarType)], svdag::boxVoxels(box),
      uint64_t(svdag::scalarSize(v.scalarType)), "Labels");
    try
    {
      svdag::decodeBox(v, box, labels->GetVoidPointer(0), vtkSVDAGParallelFor());
    }
    catch (...)
    {
      labels->Delete();
      throw;
    }
    SetBoxImage(image, v.geometry, box, labels);
  }
  catch (const std::exception& e)
  {
    error = e.what();
    return false;
  }
  return true;
}

bool vtkSegmentationSVDAG::DecodeLabelMaskTo(
  vtkIdType labelIndex, const int extent[6], vtkImageData* image) const
{
  std::string error;
  if (this->DecodeLabelMaskTo(labelIndex, extent, image, error))
    return true;
  vtkErrorMacro("DecodeLabelMaskTo: " << error);
  return false;
}

bool vtkSegmentationSVDAG::DecodeLabelMaskTo(
  vtkIdType labelIndex, const int extent[6], vtkImageData* image, std::string& error) const
{
  if (!this->Volume || !image || !extent)
  {
    error = !this->Volume ? "no compressed volume" : !image ? "no output image" : "no extent";
    return false;
  }
  const svdag::Volume& v = *this->Volume;
  if (labelIndex < 0 || labelIndex >= static_cast<vtkIdType>(v.labels.size()))
  {
    error = "label index " + std::to_string(labelIndex) + " is not in the label table of " +
      std::to_string(v.labels.size()) + " labels";
    return false;
  }
  const svdag::Box box{ { extent[0], extent[1], extent[2], extent[3], extent[4], extent[5] } };
  try
  {
    svdag::checkBox(v, box, "DecodeLabelMaskTo");
    vtkDataArray* mask = NewOutputArray(VTK_UNSIGNED_CHAR, svdag::boxVoxels(box), 1, "Mask");
    svdag::decodeMask(v, uint32_t(labelIndex), box,
      static_cast<uint8_t*>(mask->GetVoidPointer(0)), vtkSVDAGParallelFor());
    SetBoxImage(image, v.geometry, box, mask);
  }
  catch (const std::exception& e)
  {
    error = e.what();
    return false;
  }
  return true;
}

bool vtkSegmentationSVDAG::ComputeLabelStatistics(
  vtkDoubleArray* centroids, vtkIdTypeArray* surfaceVoxels) const
{
  if (!this->Volume)
  {
    vtkErrorMacro("ComputeLabelStatistics: no compressed volume");
    return false;
  }
  std::vector<svdag::LabelStatistics> stats;
  try
  {
    stats = svdag::labelStatistics(*this->Volume, vtkSVDAGParallelFor());
  }
  catch (const std::exception& e)
  {
    vtkErrorMacro("ComputeLabelStatistics: " << e.what());
    return false;
  }
  const vtkIdType n = static_cast<vtkIdType>(stats.size());
  if (centroids)
  {
    centroids->SetNumberOfComponents(3);
    centroids->SetNumberOfTuples(n);
    centroids->SetName("Centroids");
    for (vtkIdType i = 0; i < n; ++i)
    {
      const auto c = stats[size_t(i)].centroid();
      centroids->SetTypedTuple(i, c.data());
    }
  }
  if (surfaceVoxels)
  {
    surfaceVoxels->SetNumberOfComponents(1);
    surfaceVoxels->SetNumberOfTuples(n);
    surfaceVoxels->SetName("SurfaceVoxels");
    for (vtkIdType i = 0; i < n; ++i)
      surfaceVoxels->SetValue(i, static_cast<vtkIdType>(stats[size_t(i)].surfaceVoxels));
  }
  return true;
}

bool vtkSegmentationSVDAG::ComputeLabelAdjacency(vtkIdTypeArray* pairs) const
{
  if (!this->Volume)
  {
    vtkErrorMacro("ComputeLabelAdjacency: no compressed volume");
    return false;
  }
  if (!pairs)
  {
    vtkErrorMacro("ComputeLabelAdjacency: no output array");
    return false;
  }
  std::vector<svdag::LabelPair> found;
  try
  {
    found = svdag::labelAdjacency(*this->Volume, vtkSVDAGParallelFor());
  }
  catch (const std::exception& e)
  {
    vtkErrorMacro("ComputeLabelAdjacency: " << e.what());
    return false;
  }
  pairs->SetNumberOfComponents(2);
  pairs->SetNumberOfTuples(static_cast<vtkIdType>(found.size()));
  pairs->SetName("LabelAdjacency");
  for (size_t i = 0; i < found.size(); ++i)
  {
    pairs->SetTypedComponent(vtkIdType(i), 0, vtkIdType(found[i][0]));
    pairs->SetTypedComponent(vtkIdType(i), 1, vtkIdType(found[i][1]));
  }
  return true;
}

bool vtkSegmentationSVDAG::ComputeEncodingStatistics(vtkTable* table) const
{
  if (!this->Volume)
  {
    vtkErrorMacro("ComputeEncodingStatistics: no compressed volume");
    return false;
  }
  if (!table)
  {
    vtkErrorMacro("ComputeEncodingStatistics: no output table");
    return false;
  }
  svdag::EncodingAnalysis analysis;
  try
  {
    analysis = svdag::analyzeEncoding(*this->Volume, vtkSVDAGParallelFor());
  }
  catch (const std::exception& e)
  {
    vtkErrorMacro("ComputeEncodingStatistics: " << e.what());
    return false;
  }
  const vtkIdType rows = svdag::EncodingLevelCount;
  while (table->GetNumberOfColumns() > 0)
  {
    table->RemoveColumn(table->GetNumberOfColumns() - 1);
  }
  vtkNew<vtkStringArray> level;
  level->SetName("level");
  level->SetNumberOfValues(rows);
  for (vtkIdType r = 0; r < rows; ++r)
  {
    level->SetValue(r, svdag::encodingLevelName(static_cast<svdag::EncodingLevel>(r)));
  }
  table->AddColumn(level);
  auto addColumn = [&](const char* name, auto field) {
    using Value = std::decay_t<decltype(analysis.levels[0].*field)>;
    using Array = std::conditional_t<std::is_floating_point<Value>::value, vtkDoubleArray,
      vtkTypeInt64Array>;
    vtkNew<Array> column;
    column->SetName(name);
    column->SetNumberOfValues(rows);
    for (vtkIdType r = 0; r < rows; ++r)
    {
      column->SetValue(r, static_cast<typename Array::ValueType>(analysis.levels[size_t(r)].*field));
    }
    table->AddColumn(column);
  };
  using L = svdag::LevelAnalysis;
  addColumn("nodes", &L::nodes);
  addColumn("bits", &L::bits);
  addColumn("header_bits", &L::headerBits);
  addColumn("reference_bits", &L::referenceBits);
  addColumn("references", &L::references);
  addColumn("reference_width", &L::referenceWidth);
  addColumn("incoming_references", &L::incomingReferences);
  addColumn("referenced_once", &L::referencedOnce);
  addColumn("max_incoming", &L::maxIncoming);
  addColumn("top1_percent_share", &L::top1PercentShare);
  addColumn("top10_percent_share", &L::top10PercentShare);
  addColumn("reference_entropy_bits", &L::referenceEntropyBits);
  addColumn("mirror_classes", &L::mirrorClasses);
  addColumn("mirror_bits", &L::mirrorBits);
  addColumn("symmetry_classes", &L::symmetryClasses);
  addColumn("symmetry_bits", &L::symmetryBits);
  addColumn("compact_bytes", &L::compactBytes);
  return true;
}

namespace
{
void SetColors(vtkDoubleArray* out, const std::vector<svdag::color::RGB>& colors, const char* name)
{
  out->SetNumberOfComponents(3);
  out->SetNumberOfTuples(static_cast<vtkIdType>(colors.size()));
  out->SetName(name);
  for (size_t i = 0; i < colors.size(); ++i)
    out->SetTypedTuple(vtkIdType(i), colors[i].data());
}
} // namespace

bool vtkSegmentationSVDAG::ComputeDistinctLabelColors(vtkDoubleArray* colors) const
{
  if (!this->Volume)
  {
    vtkErrorMacro("ComputeDistinctLabelColors: no compressed volume");
    return false;
  }
  if (!colors)
  {
    vtkErrorMacro("ComputeDistinctLabelColors: no output array");
    return false;
  }
  try
  {
    SetColors(colors, svdag::distinctLabelColors(*this->Volume, vtkSVDAGParallelFor()), "Colors");
  }
  catch (const std::exception& e)
  {
    vtkErrorMacro("ComputeDistinctLabelColors: " << e.what());
    return false;
  }
  return true;
}

void vtkSegmentationSVDAG::GetCategoricalPalette(vtkIdType n, vtkDoubleArray* colors)
{
  if (colors)
    SetColors(colors, svdag::color::categoricalPalette(size_t(std::max<vtkIdType>(n, 0))), "Palette");
}

vtkSegmentationSVDAG* vtkSegmentationSVDAG::GetData(vtkInformation* info)
{
  return info ? vtkSegmentationSVDAG::SafeDownCast(info->Get(DATA_OBJECT())) : nullptr;
}

vtkSegmentationSVDAG* vtkSegmentationSVDAG::GetData(vtkInformationVector* v, int i)
{
  return vtkSegmentationSVDAG::GetData(v->GetInformationObject(i));
}

void vtkSegmentationSVDAG::PrintSelf(ostream& os, vtkIndent indent)
{
  this->Superclass::PrintSelf(os, indent);
  if (!this->Volume)
  {
    os << indent << "Volume: (none)\n";
    return;
  }
  const svdag::Volume& v = *this->Volume;
  const auto& g = v.geometry;
  const svdag::MemoryUsage m = v.memory();
  os << indent << "Dimensions: " << g.dims[0] << " " << g.dims[1] << " " << g.dims[2] << "\n";
  os << indent << "Spacing: " << g.spacing[0] << " " << g.spacing[1] << " " << g.spacing[2] << "\n";
  os << indent << "Origin: " << g.origin[0] << " " << g.origin[1] << " " << g.origin[2] << "\n";
  os << indent << "LabelType: " << svdag::scalarName(v.scalarType) << "\n";
  os << indent << "NumberOfLabels: " << v.labels.size() << "\n";
  os << indent << "NumberOfBlocks: " << v.blockCount << "\n";
  os << indent << "DAGNodes (root/mid/leaf): " << v.rootCount << " / " << v.midCount << " / "
     << v.leaves.size() << "\n";
  os << indent << "Bytes (blocks/DAG/labels/total): " << m.blocks << " / " << m.dag() << " / "
     << m.labels << " / " << m.total() << "\n";
}
