#include "svdagHdf5SlabSource.h"

#include "svdagVoxelStream.h"

#include "vtkErrorCode.h"
#include "vtk_hdf5.h"

#include <algorithm>
#include <array>
#include <cstdio>
#include <cstring>
#include <type_traits>
#include <vector>

static_assert(std::is_same<hid_t, int64_t>::value, "checkChunkIndex takes a hid_t as int64_t");

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

// The element type class of `name` if it is a dataset of rank 3, else H5T_NO_CLASS.
H5T_class_t volumeClass(hid_t file, const char* name)
{
  Handle dataset(H5Dopen2(file, name, H5P_DEFAULT), H5Dclose);
  if (!dataset.valid())
    return H5T_NO_CLASS;
  Handle type(H5Dget_type(dataset.get()), H5Tclose);
  Handle space(H5Dget_space(dataset.get()), H5Sclose);
  if (!type.valid() || !space.valid() || H5Sget_simple_extent_ndims(space.get()) != 3)
    return H5T_NO_CLASS;
  return H5Tget_class(type.get());
}

struct VisitState
{
  hid_t file;
  std::vector<std::string> integers; // the 3D integer datasets
  std::vector<std::string> floats;   // the 3D float datasets
};

herr_t collectVolumes(hid_t, const char* name, const H5O_info_t* info, void* data)
{
  auto* state = static_cast<VisitState*>(data);
  if (info->type != H5O_TYPE_DATASET)
    return 0;
  const H5T_class_t typeClass = volumeClass(state->file, name);
  if (typeClass == H5T_INTEGER)
    state->integers.push_back(std::string("/") + name);
  else if (typeClass == H5T_FLOAT)
    state->floats.push_back(std::string("/") + name);
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

// The memory type HDF5 converts the dataset's elements to: the native type of the source's
// samples (native float and double for floats, whatever their order and width in the file).
hid_t nativeType(const svdagSlabSource& source)
{
  switch (source.sampleKind())
  {
    case svdagSampleKind::Float32: return H5T_NATIVE_FLOAT;
    case svdagSampleKind::Float64: return H5T_NATIVE_DOUBLE;
    case svdagSampleKind::Integer: break;
  }
  return nativeType(source.scalarType());
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

svdagHdf5SlabSource::svdagHdf5SlabSource(
  const std::string& fileName, const std::string& datasetName, bool allowFloat)
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
    VisitState state{ impl->file.get(), {}, {} };
    // Only the object type is needed: the full info (H5O_INFO_ALL, what plain H5Ovisit asks
    // for) also walks each group's B-tree for its size, and HDF5 1.10 reads out of bounds there
    // on a corrupt B-tree address (found by the fuzzer).
    if (H5Ovisit2(impl->file.get(), H5_INDEX_NAME, H5_ITER_NATIVE, collectVolumes, &state,
          H5O_INFO_BASIC) < 0)
      throw svdagReadError(vtkErrorCode::FileFormatError,
        fileName + ": cannot list the HDF5 datasets (corrupt file?)");
    // Integer datasets first: a float one is chosen only where the file holds no integer
    // volume, so that allowing floats never changes how an integer file reads (and without
    // them, the float volume is refused as floats are).
    const bool floats = state.integers.empty();
    const std::vector<std::string>& found = floats ? state.floats : state.integers;
    if (found.size() != 1)
    {
      std::string names;
      for (const auto& n : found)
        names += " " + n;
      throw svdagReadError(vtkErrorCode::FileFormatError,
        fileName + " holds " + std::to_string(found.size()) + " 3D " +
          (!floats ? "integer" : found.empty() ? "integer or float" : "float") + " datasets" +
          (names.empty() ? "" : " (" + names.substr(1) + ")") + "; choose one with SetDatasetName");
    }
    impl->datasetName = found[0];
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
    this->setFloatSamples(allowFloat, int(8 * bytes), fileName + ":" + impl->datasetName);
  else if (typeClass != H5T_INTEGER)
    svdagThrowNotIntegerLabels(fileName + ":" + impl->datasetName, "a non-numeric element type");
  else
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
  // the file. A chunked one must have a chunk index that finds all its chunks.
  Handle plist(H5Dget_create_plist(impl->dataset.get()), H5Pclose);
  if (plist.valid() && H5Pget_layout(plist.get()) == H5D_CHUNKED)
    this->checkChunkIndex(plist.get());
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

// HDF5 reads a chunk that its chunk index does not find as the fill value, as it must for a
// chunk never written. A damaged index (a B-tree key that the search no longer reaches)
// therefore read as a volume with holes of fill value instead of an error (found by the
// fuzzer: two flipped bytes of a B-tree key, 768 voxels of 0, where h5py's whole-dataset read
// fails). So before any slab is read:
// - H5Dget_num_chunks walks the whole index (it fails on a damaged node);
// - every chunk position of the extent is looked up the way H5Dread looks it up
//   (H5Dget_chunk_storage_size: the index search), and the search must find as many chunks as
//   the walk counted. A search finds a chunk only at the position its index entry names, so
//   equal counts mean that every chunk of the index is found where it belongs, and the
//   positions where none is found are chunks never written: they read as the fill value (a
//   warning says so; an error where the dataset defines no fill value);
// - up to ListedChunkLimit chunks, each chunk the walk lists (H5Dget_chunk_info, HDF5 1.10.5+)
//   must lie on the chunk grid and inside the file, be as large as an unfiltered chunk where
//   its filter mask says filters were skipped, share no byte with another chunk (a child
//   address turned into another chunk's would read that chunk's voxels twice) and be the chunk
//   the search finds at its position. HDF5 1.10 finds the i-th chunk by walking i chunks, so
//   this listing takes quadratic time: 0.4 s for 4096 chunks, as long as reading their voxels.
void svdagHdf5SlabSource::checkChunkIndex(hid_t plist)
{
  const std::string name = impl->fileName + ": dataset " + impl->datasetName;
  auto fail = [&](const std::string& what) {
    throw svdagReadError(vtkErrorCode::FileFormatError, name + ": " + what);
  };
  const hid_t dataset = impl->dataset.get();
  hsize_t chunk[3] = { 0, 0, 0 };
  if (H5Pget_chunk(plist, 3, chunk) != 3 || !chunk[0] || !chunk[1] || !chunk[2])
    fail("cannot read its chunk dimensions (corrupt file?)");
  const hsize_t dims[3] = { hsize_t(this->Geometry.dims[2]), hsize_t(this->Geometry.dims[1]),
    hsize_t(this->Geometry.dims[0]) }; // (z, y, x), as HDF5 sees them
  hsize_t grid[3];
  for (int a = 0; a < 3; ++a)
    grid[a] = (dims[a] + chunk[a] - 1) / chunk[a];
  const uint64_t positions = uint64_t(grid[0]) * grid[1] * grid[2]; // <= voxels <= 2^40
  auto where = [](const hsize_t* o) {
    return "(z, y, x) = (" + std::to_string(o[0]) + ", " + std::to_string(o[1]) + ", " +
      std::to_string(o[2]) + ")";
  };
  const char* corrupt = " (corrupt chunk index)";

  // HDF5 1.10 refuses H5S_ALL here: the dataset's own space, all of it selected, says the same.
  Handle space(H5Dget_space(dataset), H5Sclose);
  hsize_t indexed = 0;
  if (!space.valid() || H5Sselect_all(space.get()) < 0 ||
    H5Dget_num_chunks(dataset, space.get(), &indexed) < 0)
    fail("its chunk index cannot be walked (corrupt B-tree or chunk index)");

  uint64_t found = 0, unwrittenVoxels = 0;
  hsize_t offset[3];
  for (hsize_t gz = 0; gz < grid[0]; ++gz)
  {
    for (hsize_t gy = 0; gy < grid[1]; ++gy)
    {
      for (hsize_t gx = 0; gx < grid[2]; ++gx)
      {
        offset[0] = gz * chunk[0];
        offset[1] = gy * chunk[1];
        offset[2] = gx * chunk[2];
        // HDF5 1.10 fails here for a chunk never written: a failure is a chunk not found.
        hsize_t bytes = 0;
        if (H5Dget_chunk_storage_size(dataset, offset, &bytes) >= 0 && bytes > 0)
        {
          ++found;
          continue;
        }
        uint64_t voxels = 1;
        for (int a = 0; a < 3; ++a)
          voxels *= std::min(chunk[a], dims[a] - offset[a]);
        unwrittenVoxels += voxels;
      }
    }
  }
  if (found != indexed)
    fail("its chunk index holds " + std::to_string(indexed) + " chunks, but searching it at the " +
      std::to_string(positions) + " chunk positions of the dataset finds " + std::to_string(found) +
      " (corrupt chunk index: the chunks not found would read as the fill value)");

  if (indexed <= ListedChunkLimit)
  {
    const int filters = std::max(0, H5Pget_nfilters(plist));
    const uint64_t unfilteredChunkBytes =
      uint64_t(chunk[0]) * chunk[1] * chunk[2] * uint64_t(this->sampleSize());
    const uint64_t fileSize = svdagVoxelStream::fileSize(impl->fileName);
    struct Listed
    {
      haddr_t address;
      hsize_t size;
      std::array<hsize_t, 3> offset;
    };
    std::vector<Listed> listed;
    for (hsize_t i = 0; i < indexed; ++i)
    {
      unsigned mask = 0;
      haddr_t address = HADDR_UNDEF;
      hsize_t size = 0;
      if (H5Dget_chunk_info(dataset, space.get(), i, offset, &mask, &address, &size) < 0)
        fail("cannot read chunk " + std::to_string(i) + " of its chunk index" + corrupt);
      for (int a = 0; a < 3; ++a)
      {
        if (offset[a] % chunk[a] != 0 || offset[a] >= dims[a])
          fail("its chunk index holds a chunk at " + where(offset) +
            ", which is no chunk position of the dataset" + corrupt);
      }
      if (address == HADDR_UNDEF || size == 0 || address > fileSize || size > fileSize - address)
        fail("the chunk at " + where(offset) + " is " + std::to_string(size) + " bytes at byte " +
          std::to_string(uint64_t(address)) + ", not inside the file (" +
          std::to_string(fileSize) + " bytes; corrupt chunk index or truncated file?)");
      // HDF5 stores a chunk unfiltered where an optional filter failed, and marks the filters
      // it skipped in the mask (bits past the dataset's filters it ignores). A corrupt mask
      // would pass compressed bytes through as voxels, so a chunk that skips filters must be
      // as large as an unfiltered chunk.
      const unsigned skipped = filters >= 32 ? mask : mask & ((1u << filters) - 1u);
      if (skipped != 0 && size != unfilteredChunkBytes)
        fail("the chunk at " + where(offset) + " is marked as not filtered (filter mask " +
          std::to_string(mask) + "), but its " + std::to_string(size) + " bytes are not the " +
          std::to_string(unfilteredChunkBytes) + " of an unfiltered chunk" + corrupt);
      hsize_t searched = 0;
      if (H5Dget_chunk_storage_size(dataset, offset, &searched) < 0 || searched != size)
        fail("the chunk index lists a chunk of " + std::to_string(size) + " bytes at " +
          where(offset) + ", searching it there finds " + std::to_string(searched) + " bytes" +
          corrupt);
      listed.push_back({ address, size, { offset[0], offset[1], offset[2] } });
    }
    std::sort(listed.begin(), listed.end(),
      [](const Listed& a, const Listed& b) { return a.address < b.address; });
    for (size_t i = 1; i < listed.size(); ++i)
    {
      if (listed[i - 1].address + listed[i - 1].size > listed[i].address)
        fail("the chunks at " + where(listed[i - 1].offset.data()) + " and " +
          where(listed[i].offset.data()) + " share bytes of the file" + corrupt);
    }
  }

  const uint64_t unwritten = positions - found;
  if (unwritten == 0)
    return;
  H5D_fill_time_t fillTime = H5D_FILL_TIME_IFSET;
  H5D_fill_value_t fillDefined = H5D_FILL_VALUE_UNDEFINED;
  if (H5Pget_fill_time(plist, &fillTime) < 0 || H5Pfill_value_defined(plist, &fillDefined) < 0)
    fail("cannot read its fill value (corrupt file?)");
  // HDF5 leaves the reader's buffer as it was for chunks never written when no fill value is
  // defined or fill values are never written.
  if (fillTime == H5D_FILL_TIME_NEVER || fillDefined == H5D_FILL_VALUE_UNDEFINED)
    fail(std::to_string(unwritten) + " of its " + std::to_string(positions) +
      " chunks were never written and it defines no fill value for them (their voxels are "
      "undefined)");
  uint64_t fill = 0; // 8 bytes: room for any sample
  if (H5Pget_fill_value(plist, nativeType(*this), &fill) < 0)
    fail("cannot read its fill value (corrupt file?)");
  std::string fillText;
  if (this->Kind == svdagSampleKind::Integer)
  {
    const uint64_t value = svdag::scalarLoad(this->Type, &fill, 0);
    fillText = svdag::scalarSigned(this->Type) ? std::to_string(int64_t(value)) : std::to_string(value);
  }
  else
  {
    float single = 0;
    double value = 0;
    if (this->Kind == svdagSampleKind::Float32)
      std::memcpy(&single, &fill, sizeof single);
    else
      std::memcpy(&value, &fill, sizeof value);
    const bool isSingle = this->Kind == svdagSampleKind::Float32;
    fillText = svdagFloatRepr(isSingle ? double(single) : value, isSingle);
  }
  this->Warnings.push_back(name + ": " + std::to_string(unwritten) + " of its " +
    std::to_string(positions) + " chunks were never written; their " +
    std::to_string(unwrittenVoxels) + " voxels read as the fill value " + fillText);
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
    H5Dread(impl->dataset.get(), nativeType(*this), memorySpace.get(), fileSpace.get(),
      H5P_DEFAULT, dst) < 0)
    throw svdagReadError(vtkErrorCode::PrematureEndOfFileError,
      impl->fileName + ":" + impl->datasetName + ": cannot read z-slices " + std::to_string(z0) +
        ".." + std::to_string(z0 + nz - 1) + " (truncated or corrupt file?)");
}
