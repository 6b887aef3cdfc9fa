#include "svdagMetaImageSlabSource.h"

#include "svdagVoxelStream.h"

#include "vtkErrorCode.h"

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <string>
#include <vector>

namespace
{
constexpr size_t MaxHeaderBytes = size_t(1) << 20;

[[noreturn]] void formatError(const std::string& message)
{
  throw svdagReadError(vtkErrorCode::FileFormatError, message);
}

std::vector<double> numbers(const std::string& text, const std::string& key)
{
  std::vector<double> out;
  const char* p = text.c_str();
  while (true)
  {
    while (std::isspace(static_cast<unsigned char>(*p)))
      ++p;
    if (!*p)
      break;
    char* end = nullptr;
    errno = 0;
    const double v = std::strtod(p, &end);
    if (end == p || errno == ERANGE || !std::isfinite(v))
      formatError("bad number in MetaImage field '" + key + "': '" + text + "'");
    out.push_back(v);
    p = end;
  }
  return out;
}

bool boolean(const std::string& text)
{
  const std::string t = svdagLower(text);
  return t == "true" || t == "1" || t == "yes";
}

// MET_ element types -> (signed, bytes); bytes 0 for real types.
bool metType(const std::string& name, bool& isSigned, int& bytes)
{
  static const std::map<std::string, std::pair<bool, int>> types = {
    { "MET_CHAR", { true, 1 } }, { "MET_UCHAR", { false, 1 } }, { "MET_SHORT", { true, 2 } },
    { "MET_USHORT", { false, 2 } }, { "MET_INT", { true, 4 } }, { "MET_UINT", { false, 4 } },
    { "MET_LONG", { true, 4 } }, { "MET_ULONG", { false, 4 } }, { "MET_LONG_LONG", { true, 8 } },
    { "MET_ULONG_LONG", { false, 8 } }, { "MET_FLOAT", { true, 0 } },
    { "MET_DOUBLE", { true, 0 } },
  };
  const auto it = types.find(name);
  if (it == types.end())
    return false;
  isSigned = it->second.first;
  bytes = it->second.second;
  return true;
}
}

struct svdagMetaImageSlabSource::Impl
{
  std::unique_ptr<svdagVoxelStream> voxels;
};

svdagMetaImageSlabSource::svdagMetaImageSlabSource(const std::string& fileName, bool allowFloat)
  : impl(new Impl)
{
  std::FILE* f = std::fopen(fileName.c_str(), "rb");
  if (!f)
    throw svdagReadError(vtkErrorCode::CannotOpenFileError, "cannot open " + fileName);

  // "Key = Value" lines; ElementDataFile is the last one (inline data follows it).
  std::map<std::string, std::string> fields;
  std::string line;
  size_t headerBytes = 0;
  bool dataFileSeen = false;
  int c = 0;
  while (!dataFileSeen && c != EOF)
  {
    line.clear();
    while ((c = std::fgetc(f)) != EOF && c != '\n')
    {
      line.push_back(static_cast<char>(c));
      if (++headerBytes > MaxHeaderBytes)
      {
        std::fclose(f);
        formatError(fileName + ": MetaImage header longer than 1 MiB");
      }
    }
    const std::string t = svdagTrim(line);
    if (t.empty())
      continue;
    const size_t eq = t.find('=');
    if (eq == std::string::npos)
    {
      std::fclose(f);
      formatError(fileName + ": malformed MetaImage header line '" + t.substr(0, 80) + "'");
    }
    const std::string key = svdagLower(svdagTrim(t.substr(0, eq)));
    fields[key] = svdagTrim(t.substr(eq + 1));
    dataFileSeen = key == "elementdatafile";
  }
  const uint64_t headerEnd = static_cast<uint64_t>(ftello(f));
  std::fclose(f);
  if (!dataFileSeen)
    throw svdagReadError(vtkErrorCode::PrematureEndOfFileError,
      fileName + ": the MetaImage header has no ElementDataFile line (truncated file?)");

  auto field = [&](const char* key) -> const std::string* {
    const auto it = fields.find(key);
    return it == fields.end() ? nullptr : &it->second;
  };
  auto required = [&](const char* key, const char* name) -> const std::string& {
    const std::string* v = field(key);
    if (!v)
      formatError(fileName + ": the MetaImage header has no " + name);
    return *v;
  };

  const std::vector<double> ndimsValue = numbers(required("ndims", "NDims"), "NDims");
  if (ndimsValue.size() != 1 || ndimsValue[0] < 1 || ndimsValue[0] > 3 ||
    ndimsValue[0] != std::floor(ndimsValue[0]))
    formatError(fileName + ": NDims = " + *field("ndims") + "; label volumes need 1 to 3");
  const size_t ndims = size_t(ndimsValue[0]);
  // Axes the file does not have are one voxel thick.
  this->Geometry.dims = { { 1, 1, 1 } };

  const std::string& typeName = required("elementtype", "ElementType");
  bool isSigned = false;
  int bytes = 0;
  if (!metType(typeName, isSigned, bytes))
    formatError(fileName + ": MetaImage element type '" + typeName + "' is not supported");
  if (bytes == 0)
    this->setFloatSamples(allowFloat, typeName == "MET_FLOAT" ? 32 : 64, fileName);
  else
    this->Type = svdagIntegerScalarType(isSigned, bytes, fileName + " has " + typeName);
  if (const std::string* channels = field("elementnumberofchannels"))
  {
    const auto n = numbers(*channels, "ElementNumberOfChannels");
    if (n.size() != 1 || n[0] != 1)
      formatError("label volumes need one component per voxel; " + fileName + " has " +
        *channels);
  }

  const auto dims = numbers(required("dimsize", "DimSize"), "DimSize");
  if (dims.size() != ndims)
    formatError(fileName + ": DimSize must list NDims values");
  for (size_t a = 0; a < ndims; ++a)
  {
    if (dims[a] < 1 || dims[a] > INT32_MAX || dims[a] != std::floor(dims[a]))
      formatError(fileName + ": DimSize " + std::to_string(dims[a]) + " is outside 1 .. 2^31-1");
    this->Geometry.dims[a] = int32_t(dims[a]);
  }
  const std::string* spacing = field("elementspacing");
  if (!spacing)
    spacing = field("elementsize");
  if (spacing)
  {
    const auto v = numbers(*spacing, "ElementSpacing");
    if (v.size() != ndims)
      formatError(fileName + ": ElementSpacing must list NDims values");
    for (size_t a = 0; a < ndims; ++a)
      this->Geometry.spacing[a] = v[a];
  }
  for (const char* key : { "offset", "origin", "position" })
  {
    if (const std::string* origin = field(key))
    {
      const auto v = numbers(*origin, key);
      if (v.size() != ndims)
        formatError(fileName + ": " + key + " must list NDims values");
      for (size_t a = 0; a < ndims; ++a)
        this->Geometry.origin[a] = v[a];
      break;
    }
  }
  for (const char* key : { "transformmatrix", "rotation", "orientation" })
  {
    if (const std::string* matrix = field(key))
    {
      const auto v = numbers(*matrix, key);
      if (v.size() != ndims * ndims)
        formatError(fileName + ": " + key + " must list NDims x NDims values");
      for (size_t a = 0; a < ndims; ++a)
        for (size_t r = 0; r < ndims; ++r)
          this->Geometry.direction[3 * r + a] = v[ndims * a + r];
      break;
    }
  }
  this->checkGeometry(fileName);

  if (const std::string* binary = field("binarydata"))
  {
    if (!boolean(*binary))
      formatError(fileName + ": ASCII MetaImage data is not supported");
  }
  bool bigEndian = false;
  if (const std::string* msb = field("binarydatabyteordermsb"))
    bigEndian = boolean(*msb);
  else if (const std::string* msb2 = field("elementbyteordermsb"))
    bigEndian = boolean(*msb2);
  const bool compressed = field("compresseddata") && boolean(*field("compresseddata"));

  const std::string dataFile = *field("elementdatafile");
  std::string dataFileName = fileName;
  uint64_t offset = headerEnd;
  if (svdagLower(dataFile) != "local")
  {
    if (dataFile.empty() || svdagLower(dataFile.substr(0, 4)) == "list" ||
      dataFile.find('%') != std::string::npos)
      formatError(fileName + ": MetaImage data in several files ('" + dataFile +
        "') is not supported");
    dataFileName = dataFile;
    if (dataFileName[0] != '/')
    {
      const size_t slash = fileName.find_last_of('/');
      if (slash != std::string::npos)
        dataFileName = fileName.substr(0, slash + 1) + dataFileName;
    }
    offset = 0;
    if (const std::string* headerSize = field("headersize"))
    {
      const auto v = numbers(*headerSize, "HeaderSize");
      if (v.size() != 1 || v[0] < -1 || v[0] != std::floor(v[0]))
        formatError(fileName + ": bad HeaderSize '" + *headerSize + "'");
      if (v[0] == -1)
      {
        // -1: the data is the last bytes of the data file.
        const uint64_t total = this->Geometry.voxelCount() * uint64_t(this->sampleSize());
        const uint64_t size = svdagVoxelStream::fileSize(dataFileName);
        if (compressed || size < total)
          formatError(fileName + ": HeaderSize -1 needs raw data that fits in " + dataFileName);
        offset = size - total;
      }
      else
        offset = uint64_t(v[0]);
    }
  }
  if (const std::string* stored = compressed ? field("compresseddatasize") : nullptr)
  {
    // The size of the zlib stream: it must be what the data file holds after the header.
    const auto v = numbers(*stored, "CompressedDataSize");
    const uint64_t size = svdagVoxelStream::fileSize(dataFileName);
    const uint64_t held = size > offset ? size - offset : 0;
    if (v.size() != 1 || v[0] < 0 || v[0] != std::floor(v[0]) || uint64_t(v[0]) != held)
      throw svdagReadError(uint64_t(v.empty() ? 0 : v[0]) > held
          ? vtkErrorCode::PrematureEndOfFileError
          : vtkErrorCode::FileFormatError,
        fileName + ": CompressedDataSize = " + *stored + ", but " + dataFileName + " holds " +
          std::to_string(held) + " compressed bytes");
  }
  impl->voxels.reset(new svdagVoxelStream(dataFileName,
    compressed ? svdagVoxelStream::Encoding::Compressed : svdagVoxelStream::Encoding::Raw, offset,
    this->Geometry, this->sampleSize(), bigEndian));
}

svdagMetaImageSlabSource::~svdagMetaImageSlabSource() = default;

void svdagMetaImageSlabSource::readSlab(int32_t z0, int32_t nz, void* dst)
{
  this->checkSlab(z0, nz);
  impl->voxels->readSlab(z0, nz, dst);
}

bool svdagMetaImageSlabSource::canRead(const std::string& fileName)
{
  // A MetaImage header is "Key = Value" lines; look for the keys every image has, in the first
  // 4 KiB, and only in text (a binary file never passes).
  std::FILE* f = std::fopen(fileName.c_str(), "rb");
  if (!f)
    return false;
  char buffer[4096];
  const size_t n = std::fread(buffer, 1, sizeof(buffer), f);
  std::fclose(f);
  std::string text(buffer, n);
  // The header ends where the inline data starts (after "ElementDataFile = LOCAL").
  const size_t local = text.find("ElementDataFile");
  if (local != std::string::npos)
  {
    const size_t eol = text.find('\n', local);
    text.resize(eol == std::string::npos ? text.size() : eol);
  }
  for (unsigned char c : text)
  {
    if (!std::isprint(c) && !std::isspace(c))
      return false;
  }
  auto hasKey = [&](const char* key) {
    for (size_t at = text.find(key); at != std::string::npos; at = text.find(key, at + 1))
    {
      if (at == 0 || text[at - 1] == '\n')
      {
        const size_t eq = text.find_first_not_of(" \t", at + std::string(key).size());
        if (eq != std::string::npos && text[eq] == '=')
          return true;
      }
    }
    return false;
  };
  return hasKey("NDims") && hasKey("DimSize") && hasKey("ElementType");
}
