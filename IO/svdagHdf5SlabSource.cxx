#include "svdagHdf5SlabSource.h"

#include "svdagVoxelStream.h"

#include "vtkErrorCode.h"
#include "vtk_hdf5.h"

#include <cstdio>
#include <cstring>
#include <vector>

namespace
{
// HDF5 prints its error stack by default; a bad file is reported by our exception instead.
// The previous handler is restored, so other HDF5 users in the process are not affected.
class QuietHdf5Errors
{
public:
  QuietHdf5Errors()
  {
    H5Eget_auto2(H5E_DEFAULT, &this->Function, &this->Data);
    H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
  }
  ~QuietHdf5Errors() { H5Eset_auto2(H5E_DEFAULT, this->Function, this->Data); }
  QuietHdf5Errors(const QuietHdf5Errors&) = delete;
  QuietHdf5Errors& operator=(const QuietHdf5Errors&) = delete;

private:
  H5E_auto2_t Function = nullptr;
  void* Data = nullptr;
};

// An HDF5 identifier closed with its own close function.
class Handle
{
public:
  using Closer = herr_t (*)(hid_t);
  Handle() = default;
  Handle(hid_t id, Closer closer)
    : Id(id)
    , Close(closer)
  {
  }
  ~Handle() { this->reset(); }
  Handle(Handle&& o) noexcept : Id(o.Id), Close(o.Close) { o.Id = -1; }
  Handle& operator=(Handle&& o) noexcept
  {
    if (this != &o)
    {
      this->reset();
      this->Id = o.Id;
      this->Close = o.Close;
      o.Id = -1;
    }
    return *this;
  }
  void reset()
  {
    if (this->Id >= 0 && this->Close)
      this->Close(this->Id);
    this->Id = -1;
  }
  hid_t get() const { return this->Id; }
  bool valid() const { return this->Id >= 0; }

private:
  hid_t Id = -1;
  Closer Close = nullptr;
};

// True if `name` is a dataset of rank 3 with an integer element type.
bool isIntegerVolume(hid_t file, const char* name)
{
  Handle dataset(H5Dopen2(file, name, H5P_DEFAULT), H5Dclose);
  if (!dataset.valid())
    return false;
  Handle type(H5Dget_type(dataset.get()), H5Tclose);
  Handle space(H5Dget_space(dataset.get()), H5Sclose);
  return type.valid() && space.valid() && H5Tget_class(type.get()) == H5T_INTEGER &&
    H5Sget_simple_extent_ndims(space.get()) == 3;
}

struct VisitState
{
  hid_t file;
  std::vector<std::string> found;
};

herr_t collectVolumes(hid_t, const char* name, const H5O_info_t* info, void* data)
{
  auto* state = static_cast<VisitState*>(data);
  if (info->type == H5O_TYPE_DATASET && isIntegerVolume(state->file, name))
    state->found.push_back(std::string("/") + name);
  return 0;
}

hid_t nativeType(svdag::ScalarType t)
{
  switch (t)
  {
    case svdag::ScalarType::Int8: return H5T_NATIVE_INT8;
    case svdag::ScalarType::UInt8: return H5T_NATIVE_UINT8;
    case svdag::ScalarType::Int16: return H5T_NATIVE_INT16;
    case svdag::ScalarType::UInt16: return H5T_NATIVE_UINT16;
    case svdag::ScalarType::Int32: return H5T_NATIVE_INT32;
    case svdag::ScalarType::UInt32: return H5T_NATIVE_UINT32;
    case svdag::ScalarType::Int64: return H5T_NATIVE_INT64;
    case svdag::ScalarType::UInt64: return H5T_NATIVE_UINT64;
  }
  return H5T_NATIVE_UINT8;
}
}

struct svdagHdf5SlabSource::Impl
{
  std::string fileName;
  std::string datasetName;
  Handle file;
  Handle dataset;
};

bool svdagHdf5SlabSource::hasMagic(const std::string& fileName)
{
  static const unsigned char signature[8] = { 0x89, 'H', 'D', 'F', '\r', '\n', 0x1a, '\n' };
  std::FILE* f = std::fopen(fileName.c_str(), "rb");
  if (!f)
    return false;
  // The superblock sits at 0, 512, 1024, 2048, ... (after an optional user block).
  bool found = false;
  for (long offset = 0; !found && offset <= (1L << 20); offset = offset ? offset * 2 : 512)
  {
    unsigned char m[8] = {};
    if (std::fseek(f, offset, SEEK_SET) != 0 || std::fread(m, 1, 8, f) != 8)
      break;
    found = std::memcmp(m, signature, 8) == 0;
  }
  std::fclose(f);
  return found;
}

svdagHdf5SlabSource::svdagHdf5SlabSource(const std::string& fileName, const std::string& datasetName)
  : impl(new Impl)
{
  QuietHdf5Errors quiet;
  impl->fileName = fileName;
  impl->file = Handle(H5Fopen(fileName.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT), H5Fclose);
  if (!impl->file.valid())
    throw svdagReadError(vtkErrorCode::FileFormatError,
      fileName + ": cannot open as HDF5 (corrupt or truncated file?)");

  impl->datasetName = datasetName;
  if (impl->datasetName.empty())
  {
    VisitState state{ impl->file.get(), {} };
    // Only the object type is needed: the full info (H5O_INFO_ALL, what plain H5Ovisit asks
    // for) also walks each group's B-tree for its size, and HDF5 1.10 reads out of bounds there
    // on a corrupt B-tree address (found by the fuzzer).
    if (H5Ovisit2(impl->file.get(), H5_INDEX_NAME, H5_ITER_NATIVE, collectVolumes, &state,
          H5O_INFO_BASIC) < 0)
      throw svdagReadError(vtkErrorCode::FileFormatError,
        fileName + ": cannot list the HDF5 datasets (corrupt file?)");
    if (state.found.size() != 1)
    {
      std::string names;
      for (const auto& n : state.found)
        names += " " + n;
      throw svdagReadError(vtkErrorCode::FileFormatError,
        fileName + " holds " + std::to_string(state.found.size()) +
          " 3D integer datasets" + (names.empty() ? "" : " (" + names.substr(1) + ")") +
          "; choose one with SetDatasetName");
    }
    impl->datasetName = state.found[0];
  }
  impl->dataset = Handle(H5Dopen2(impl->file.get(), impl->datasetName.c_str(), H5P_DEFAULT), H5Dclose);
  if (!impl->dataset.valid())
    throw svdagReadError(vtkErrorCode::FileFormatError,
      fileName + " has no dataset '" + impl->datasetName + "'");

  Handle type(H5Dget_type(impl->dataset.get()), H5Tclose);
  Handle space(H5Dget_space(impl->dataset.get()), H5Sclose);
  if (!type.valid() || !space.valid())
    throw svdagReadError(vtkErrorCode::FileFormatError,
      fileName + ": cannot read the type of dataset '" + impl->datasetName + "'");
  const H5T_class_t typeClass = H5Tget_class(type.get());
  const size_t bytes = H5Tget_size(type.get());
  if (typeClass == H5T_FLOAT)
    svdagThrowNotIntegerLabels(fileName + ":" + impl->datasetName, "float" + std::to_string(8 * bytes));
  if (typeClass != H5T_INTEGER)
    svdagThrowNotIntegerLabels(fileName + ":" + impl->datasetName, "a non-numeric element type");
  this->Type = svdagIntegerScalarType(H5Tget_sign(type.get()) == H5T_SGN_2, int(bytes),
    fileName + ":" + impl->datasetName + " has " + std::to_string(8 * bytes) + "-bit integers");

  const int rank = H5Sget_simple_extent_ndims(space.get());
  if (rank != 3)
    throw svdagReadError(vtkErrorCode::FileFormatError,
      fileName + ":" + impl->datasetName + " has " + std::to_string(rank) +
        " dimensions; label volumes need 3 (z, y, x)");
  hsize_t dims[3] = { 0, 0, 0 };
  H5Sget_simple_extent_dims(space.get(), dims, nullptr);
  for (int a = 0; a < 3; ++a)
  {
    if (dims[2 - a] < 1 || dims[2 - a] > hsize_t(INT32_MAX))
      throw svdagReadError(vtkErrorCode::FileFormatError,
        fileName + ":" + impl->datasetName + " has an empty or absurd axis " + std::to_string(2 - a));
    this->Geometry.dims[a] = int32_t(dims[2 - a]);
  }
  this->checkGeometry(fileName);

  // A contiguous dataset is one block of the file: it must be exactly the voxels and lie inside
  // the file. (Chunked datasets are checked chunk by chunk by HDF5 as it reads them.)
  Handle plist(H5Dget_create_plist(impl->dataset.get()), H5Pclose);
  if (plist.valid() && H5Pget_layout(plist.get()) == H5D_CONTIGUOUS)
  {
    H5D_space_status_t status = H5D_SPACE_STATUS_ERROR;
    H5Dget_space_status(impl->dataset.get(), &status);
    if (status == H5D_SPACE_STATUS_ALLOCATED)
    {
      const uint64_t expected = this->Geometry.voxelCount() * uint64_t(bytes);
      const uint64_t stored = uint64_t(H5Dget_storage_size(impl->dataset.get()));
      const haddr_t offset = H5Dget_offset(impl->dataset.get());
      const uint64_t size = svdagVoxelStream::fileSize(fileName);
      if (stored != expected)
        throw svdagReadError(stored < expected ? vtkErrorCode::PrematureEndOfFileError
                                               : vtkErrorCode::FileFormatError,
          fileName + ":" + impl->datasetName + " stores " + std::to_string(stored) +
            " bytes, its dimensions and type describe " + std::to_string(expected));
      if (offset != HADDR_UNDEF && (offset > size || stored > size - offset))
        throw svdagReadError(vtkErrorCode::PrematureEndOfFileError,
          fileName + ":" + impl->datasetName + ": its " + std::to_string(stored) +
            " bytes at byte " + std::to_string(uint64_t(offset)) + " run past the end of the file (" +
            std::to_string(size) + " bytes; truncated file?)");
    }
  }
}

svdagHdf5SlabSource::~svdagHdf5SlabSource()
{
  QuietHdf5Errors quiet;
  impl.reset();
}

void svdagHdf5SlabSource::readSlab(int32_t z0, int32_t nz, void* dst)
{
  this->checkSlab(z0, nz);
  QuietHdf5Errors quiet;
  const hsize_t start[3] = { hsize_t(z0), 0, 0 };
  const hsize_t count[3] = { hsize_t(nz), hsize_t(this->Geometry.dims[1]),
    hsize_t(this->Geometry.dims[0]) };
  Handle fileSpace(H5Dget_space(impl->dataset.get()), H5Sclose);
  Handle memorySpace(H5Screate_simple(3, count, nullptr), H5Sclose);
  if (!fileSpace.valid() || !memorySpace.valid() ||
    H5Sselect_hyperslab(fileSpace.get(), H5S_SELECT_SET, start, nullptr, count, nullptr) < 0 ||
    H5Dread(impl->dataset.get(), nativeType(this->Type), memorySpace.get(), fileSpace.get(),
      H5P_DEFAULT, dst) < 0)
    throw svdagReadError(vtkErrorCode::PrematureEndOfFileError,
      impl->fileName + ":" + impl->datasetName + ": cannot read z-slices " + std::to_string(z0) +
        ".." + std::to_string(z0 + nz - 1) + " (truncated or corrupt file?)");
}
