#include "svdagNrrdSlabSource.h"

#include "svdagVoxelStream.h"

#include "vtkErrorCode.h"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <map>
#include <vector>

namespace
{
// Limits that keep a binary file mistaken for a header from costing time or memory.
constexpr size_t MaxHeaderLine = size_t(1) << 20;
constexpr size_t MaxHeaderBytes = size_t(16) << 20;

struct FileCloser
{
  void operator()(std::FILE* f) const
  {
    if (f)
      std::fclose(f);
  }
};
using FilePtr = std::unique_ptr<std::FILE, FileCloser>;

[[noreturn]] void formatError(const std::string& message)
{
  throw svdagReadError(vtkErrorCode::FileFormatError, message);
}

std::vector<std::string> words(const std::string& s)
{
  std::vector<std::string> out;
  size_t i = 0;
  while (i < s.size())
  {
    while (i < s.size() && std::isspace(static_cast<unsigned char>(s[i])))
      ++i;
    size_t j = i;
    while (j < s.size() && !std::isspace(static_cast<unsigned char>(s[j])))
      ++j;
    if (j > i)
      out.push_back(s.substr(i, j - i));
    i = j;
  }
  return out;
}

// A whole string as a number, or an error naming the field.
double parseReal(const std::string& text, const std::string& field)
{
  const std::string t = svdagTrim(text);
  char* end = nullptr;
  errno = 0;
  const double v = std::strtod(t.c_str(), &end);
  if (t.empty() || *end != '\0' || errno == ERANGE)
    formatError("bad number '" + t + "' in NRRD field '" + field + "'");
  return v;
}

long long parseInteger(const std::string& text, const std::string& field)
{
  const std::string t = svdagTrim(text);
  char* end = nullptr;
  errno = 0;
  const long long v = std::strtoll(t.c_str(), &end, 10);
  if (t.empty() || *end != '\0' || errno == ERANGE)
    formatError("bad integer '" + t + "' in NRRD field '" + field + "'");
  return v;
}

// Splits a list of "(a,b,c)" vectors and bare words ("none") into items.
std::vector<std::string> vectorItems(const std::string& value, const std::string& field)
{
  std::vector<std::string> items;
  size_t i = 0;
  while (true)
  {
    while (i < value.size() && std::isspace(static_cast<unsigned char>(value[i])))
      ++i;
    if (i >= value.size())
      break;
    size_t j;
    if (value[i] == '(')
    {
      j = value.find(')', i);
      if (j == std::string::npos)
        formatError("unclosed '(' in NRRD field '" + field + "'");
      ++j;
    }
    else
    {
      j = i;
      while (j < value.size() && !std::isspace(static_cast<unsigned char>(value[j])))
        ++j;
    }
    items.push_back(value.substr(i, j - i));
    i = j;
  }
  return items;
}

std::array<double, 3> parseVector(const std::string& item, const std::string& field)
{
  if (item.size() < 2 || item.front() != '(' || item.back() != ')')
    formatError("expected a vector '(x,y,z)' in NRRD field '" + field + "', got '" + item + "'");
  const std::string inner = item.substr(1, item.size() - 2);
  std::vector<std::string> parts;
  size_t start = 0;
  while (true)
  {
    const size_t comma = inner.find(',', start);
    parts.push_back(inner.substr(start, comma - start));
    if (comma == std::string::npos)
      break;
    start = comma + 1;
  }
  if (parts.size() != 3)
    formatError("NRRD field '" + field + "' needs 3-D vectors (space dimension 3), got '" + item +
      "'");
  std::array<double, 3> v{};
  for (int a = 0; a < 3; ++a)
  {
    v[a] = parseReal(parts[a], field);
    if (!std::isfinite(v[a]))
      formatError("NRRD field '" + field + "' holds a non-finite value: '" + item + "'");
  }
  return v;
}

// A NRRD type: integers by signedness and bytes; floats by bytes; 0 bytes for "block".
struct NrrdType
{
  bool isSigned = false;
  int bytes = 0;
  bool isFloat = false;
};

// NRRD type spellings (teem's list) -> their type.
bool nrrdType(const std::string& spelling, NrrdType& type)
{
  static const std::map<std::string, NrrdType> types = {
    { "signed char", { true, 1 } }, { "int8", { true, 1 } }, { "int8_t", { true, 1 } },
    { "uchar", { false, 1 } }, { "unsigned char", { false, 1 } }, { "uint8", { false, 1 } },
    { "uint8_t", { false, 1 } },
    { "short", { true, 2 } }, { "short int", { true, 2 } }, { "signed short", { true, 2 } },
    { "signed short int", { true, 2 } }, { "int16", { true, 2 } }, { "int16_t", { true, 2 } },
    { "ushort", { false, 2 } }, { "unsigned short", { false, 2 } },
    { "unsigned short int", { false, 2 } }, { "uint16", { false, 2 } },
    { "uint16_t", { false, 2 } },
    { "int", { true, 4 } }, { "signed int", { true, 4 } }, { "int32", { true, 4 } },
    { "int32_t", { true, 4 } },
    { "uint", { false, 4 } }, { "unsigned int", { false, 4 } }, { "uint32", { false, 4 } },
    { "uint32_t", { false, 4 } },
    { "longlong", { true, 8 } }, { "long long", { true, 8 } }, { "long long int", { true, 8 } },
    { "signed long long", { true, 8 } }, { "signed long long int", { true, 8 } },
    { "int64", { true, 8 } }, { "int64_t", { true, 8 } },
    { "ulonglong", { false, 8 } }, { "unsigned long long", { false, 8 } },
    { "unsigned long long int", { false, 8 } }, { "uint64", { false, 8 } },
    { "uint64_t", { false, 8 } },
    { "float", { true, 4, true } }, { "double", { true, 8, true } }, { "block", { true, 0 } },
  };
  const auto it = types.find(svdagLower(spelling));
  if (it == types.end())
    return false;
  type = it->second;
  return true;
}

// Reads one header line (without the line end) into `line`; false at the end of the file.
bool readLine(std::FILE* f, std::string& line, const std::string& fileName)
{
  line.clear();
  int c;
  while ((c = std::fgetc(f)) != EOF)
  {
    if (c == '\n')
      return true;
    line.push_back(static_cast<char>(c));
    if (line.size() > MaxHeaderLine)
      formatError(fileName + ": NRRD header line longer than 1 MiB (not a NRRD header?)");
  }
  return !line.empty();
}

bool isSpatialKind(const std::string& kind)
{
  const std::string k = svdagLower(kind);
  return k == "domain" || k == "space" || k == "time" || k == "???" || k == "none";
}

} // namespace

struct svdagNrrdSlabSource::Impl
{
  std::unique_ptr<svdagVoxelStream> voxels;
};

bool svdagNrrdSlabSource::hasSignature(const uint8_t* head, size_t size)
{
  return size >= 7 && std::memcmp(head, "NRRD000", 7) == 0;
}

svdagNrrdSlabSource::svdagNrrdSlabSource(const std::string& fileName, bool allowFloat)
  : impl(new Impl)
{
  FilePtr header(std::fopen(fileName.c_str(), "rb"));
  if (!header)
    throw svdagReadError(vtkErrorCode::CannotOpenFileError, "cannot open " + fileName);

  std::string line;
  if (!readLine(header.get(), line, fileName) || line.compare(0, 7, "NRRD000") != 0)
    formatError(fileName + " is not a NRRD file (no 'NRRD000X' magic line)");

  // Fields, by lower-case name. Key/value pairs (key:=value) and comments are skipped.
  std::map<std::string, std::string> fields;
  bool blankLineSeen = false;
  size_t headerBytes = line.size();
  while (readLine(header.get(), line, fileName))
  {
    headerBytes += line.size() + 1;
    if (headerBytes > MaxHeaderBytes)
      formatError(fileName + ": NRRD header longer than 16 MiB");
    const std::string t = svdagTrim(line);
    if (t.empty())
    {
      blankLineSeen = true;
      break;
    }
    if (t[0] == '#')
      continue;
    const size_t colon = t.find(": ");
    const size_t keyValue = t.find(":=");
    if (keyValue != std::string::npos && (colon == std::string::npos || keyValue < colon))
      continue;
    if (colon == std::string::npos)
    {
      // A field with an empty value has no ': ' but ends with ':'.
      if (t.back() == ':')
      {
        fields[svdagLower(t.substr(0, t.size() - 1))] = "";
        continue;
      }
      formatError(fileName + ": malformed NRRD header line '" + t.substr(0, 80) + "'");
    }
    fields[svdagLower(svdagTrim(t.substr(0, colon)))] = svdagTrim(t.substr(colon + 2));
  }
  auto field = [&](const char* name) -> const std::string* {
    const auto it = fields.find(name);
    return it == fields.end() ? nullptr : &it->second;
  };
  auto required = [&](const char* name) -> const std::string& {
    const std::string* v = field(name);
    if (!v)
      formatError(fileName + ": the NRRD header has no '" + name + "' field");
    return *v;
  };

  // Scalar type.
  const std::string& typeName = required("type");
  NrrdType type;
  if (!nrrdType(typeName, type))
    formatError(fileName + ": unknown NRRD type '" + typeName + "'");
  const int bytes = type.bytes;
  if (type.isFloat)
    this->setFloatSamples(allowFloat, 8 * bytes, fileName);
  else if (bytes == 0)
    svdagThrowNotIntegerLabels(fileName, typeName);
  else
    this->Type = svdagIntegerScalarType(type.isSigned, bytes, fileName + " has " + typeName);

  // Dimension and sizes.
  const long long dimension = parseInteger(required("dimension"), "dimension");
  const std::vector<std::string> sizeWords = words(required("sizes"));
  if (dimension == 4 && sizeWords.size() == 4)
    formatError(fileName + " is a 4-D NRRD (sizes " + required("sizes") +
      "): multi-layer segmentations (for example a 3D Slicer .seg.nrrd with overlapping "
      "segments) are not supported; export a single 3D labelmap");
  if (dimension != 3)
    formatError(fileName + " has " + std::to_string(dimension) +
      " dimensions; label volumes need 3 (x, y, z)");
  if (sizeWords.size() != 3)
    formatError(fileName + ": 'sizes' must list 3 values, got '" + required("sizes") + "'");
  for (int a = 0; a < 3; ++a)
  {
    const long long n = parseInteger(sizeWords[a], "sizes");
    if (n < 1 || n > INT32_MAX)
      formatError(fileName + ": size " + sizeWords[a] + " along axis " + std::to_string(a) +
        " is outside 1 .. 2^31-1");
    this->Geometry.dims[a] = static_cast<int32_t>(n);
  }
  if (const std::string* kinds = field("kinds"))
  {
    const auto k = words(*kinds);
    for (size_t a = 0; a < k.size(); ++a)
    {
      if (!isSpatialKind(k[a]))
        formatError(fileName + ": axis " + std::to_string(a) + " has kind '" + k[a] +
          "' (components, not space); label volumes need one integer component per voxel");
    }
  }

  // Geometry: space directions (+ space origin), or spacings.
  if (const std::string* directions = field("space directions"))
  {
    const auto items = vectorItems(*directions, "space directions");
    if (items.size() != 3)
      formatError(fileName + ": 'space directions' must list 3 vectors");
    for (int a = 0; a < 3; ++a)
    {
      if (svdagLower(items[a]) == "none")
        formatError(fileName + ": axis " + std::to_string(a) +
          " has no space direction (not a spatial axis)");
      const auto v = parseVector(items[a], "space directions");
      const double norm = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
      if (!(norm > 0) || !std::isfinite(norm))
        formatError(fileName + ": the space direction of axis " + std::to_string(a) +
          " has zero length");
      this->Geometry.spacing[a] = norm;
      // Column a of the row-major index-to-physical direction matrix.
      for (int r = 0; r < 3; ++r)
        this->Geometry.direction[3 * r + a] = v[r] / norm;
    }
  }
  else if (const std::string* spacings = field("spacings"))
  {
    const auto w = words(*spacings);
    if (w.size() != 3)
      formatError(fileName + ": 'spacings' must list 3 values");
    for (int a = 0; a < 3; ++a)
      this->Geometry.spacing[a] = parseReal(w[a], "spacings");
  }
  if (const std::string* origin = field("space origin"))
  {
    const auto items = vectorItems(*origin, "space origin");
    if (items.size() != 1)
      formatError(fileName + ": 'space origin' must be one vector");
    const auto v = parseVector(items[0], "space origin");
    for (int a = 0; a < 3; ++a)
      this->Geometry.origin[a] = v[a];
  }
  this->checkGeometry(fileName);

  // Byte order.
  bool bigEndian = false;
  if (bytes > 1)
  {
    const std::string endian = svdagLower(required("endian"));
    if (endian != "little" && endian != "big")
      formatError(fileName + ": unknown endian '" + endian + "'");
    bigEndian = endian == "big";
  }

  // Where the data is: after the header's blank line, or in the file named by 'data file'.
  std::string dataFileName = fileName;
  FilePtr data;
  const std::string* dataFile = field("data file");
  if (!dataFile)
    dataFile = field("datafile");
  if (dataFile)
  {
    const auto w = words(*dataFile);
    if (w.size() != 1 || w[0] == "LIST")
      formatError(fileName + ": NRRD data split over several files ('data file: " + *dataFile +
        "') is not supported");
    dataFileName = w[0];
    if (dataFileName[0] != '/')
    {
      const size_t slash = fileName.find_last_of('/');
      if (slash != std::string::npos)
        dataFileName = fileName.substr(0, slash + 1) + dataFileName;
    }
    data.reset(std::fopen(dataFileName.c_str(), "rb"));
    if (!data)
      throw svdagReadError(vtkErrorCode::FileNotFoundError,
        fileName + ": cannot open its data file " + dataFileName);
  }
  else
  {
    if (!blankLineSeen)
      throw svdagReadError(vtkErrorCode::PrematureEndOfFileError,
        fileName + ": the NRRD header is not followed by data (no blank line, no 'data file')");
    data = std::move(header);
  }

  long long lineSkip = 0, byteSkip = 0;
  if (const std::string* v = field("line skip"))
    lineSkip = parseInteger(*v, "line skip");
  else if (const std::string* v2 = field("lineskip"))
    lineSkip = parseInteger(*v2, "lineskip");
  if (const std::string* v = field("byte skip"))
    byteSkip = parseInteger(*v, "byte skip");
  else if (const std::string* v2 = field("byteskip"))
    byteSkip = parseInteger(*v2, "byteskip");
  if (lineSkip < 0 || byteSkip < -1)
    formatError(fileName + ": negative 'line skip' or 'byte skip'");
  for (long long i = 0; i < lineSkip; ++i)
  {
    int c;
    while ((c = std::fgetc(data.get())) != EOF && c != '\n')
    {
    }
    if (c == EOF)
      throw svdagReadError(vtkErrorCode::PrematureEndOfFileError,
        dataFileName + ": ends inside the lines skipped by 'line skip'");
  }
  const uint64_t here = static_cast<uint64_t>(ftello(data.get()));
  data.reset();

  const std::string encoding = svdagLower(required("encoding"));
  if (encoding == "raw")
  {
    uint64_t offset = here + uint64_t(byteSkip);
    if (byteSkip == -1)
    {
      // -1: the data is the last bytes of the file.
      const uint64_t total = this->Geometry.voxelCount() * uint64_t(bytes);
      const uint64_t size = svdagVoxelStream::fileSize(dataFileName);
      if (size < here + total)
        throw svdagReadError(vtkErrorCode::PrematureEndOfFileError,
          dataFileName + " is too short for the volume its header describes");
      offset = size - total;
    }
    impl->voxels.reset(new svdagVoxelStream(dataFileName, svdagVoxelStream::Encoding::Raw,
      offset, this->Geometry, this->sampleSize(), bigEndian));
  }
  else if (encoding == "gzip" || encoding == "gz")
  {
    // For compressed encodings the byte skip applies to the decompressed bytes.
    if (byteSkip == -1)
      formatError(fileName + ": 'byte skip: -1' is only allowed with raw encoding");
    impl->voxels.reset(new svdagVoxelStream(dataFileName,
      svdagVoxelStream::Encoding::Compressed, here, this->Geometry, this->sampleSize(), bigEndian,
      uint64_t(byteSkip)));
  }
  else
  {
    formatError(fileName + ": NRRD encoding '" + encoding +
      "' is not supported (supported: raw, gzip)");
  }
}

svdagNrrdSlabSource::~svdagNrrdSlabSource() = default;

void svdagNrrdSlabSource::readSlab(int32_t z0, int32_t nz, void* dst)
{
  this->checkSlab(z0, nz);
  impl->voxels->readSlab(z0, nz, dst);
}
