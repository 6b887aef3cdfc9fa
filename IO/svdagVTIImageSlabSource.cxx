#include "svdagVTIImageSlabSource.h"

#include "vtkErrorCode.h"
#include "vtkNew.h"
#include "vtkXMLImageDataReader.h"

#include <array>
#include <cctype>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

namespace
{
// VTK 9.1's XML reader trusts what it reads: a compressed array's block sizes (a last block
// larger than the others wrote past a heap buffer), an appended section not starting at its '_'
// (4 GiB allocated), a DataArray without a format or a Piece with an inverted extent (a null
// stream read) were all found by the fuzzer. Before VTK reads the file, its structure is checked
// here: byte order, header type and compressor known, extents not inverted, every array's format
// known and its header describing exactly the array it fills, inside the file.
class HeaderCheck
{
public:
  HeaderCheck(const std::string& fileName)
    : FileName(fileName)
  {
    std::ifstream in(fileName, std::ios::binary);
    this->Text.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  }

  void run()
  {
    const size_t file = this->Text.find("<VTKFile");
    if (file == std::string::npos)
      return; // not ours to judge: vtkXMLImageDataReader reports it
    const std::string root = this->tag(file);
    const std::string compressor = attribute(root, "compressor");
    if (!compressor.empty() && compressor != "vtkZLibDataCompressor" &&
      compressor != "vtkLZ4DataCompressor" && compressor != "vtkLZMADataCompressor")
      this->fail("compressor '" + compressor + "'");
    this->Compressed = !compressor.empty();
    const std::string headerType = attribute(root, "header_type");
    if (!headerType.empty() && headerType != "UInt32" && headerType != "UInt64")
      this->fail("header_type '" + headerType + "' (UInt32 or UInt64)");
    this->WordSize = headerType == "UInt64" ? 8 : 4;
    const std::string byteOrder = attribute(root, "byte_order");
    if (byteOrder != "LittleEndian" && byteOrder != "BigEndian")
      this->fail("byte_order '" + byteOrder + "' (LittleEndian or BigEndian)");
    this->BigEndian = byteOrder == "BigEndian";
    const size_t appended = this->Text.find("<AppendedData");
    size_t dataStart = std::string::npos;
    bool appendedRaw = false;
    if (appended != std::string::npos)
    {
      const std::string encoding = attribute(this->tag(appended), "encoding");
      if (encoding != "raw" && encoding != "base64")
        this->fail("AppendedData encoding '" + encoding + "' (raw or base64)");
      appendedRaw = encoding == "raw";
      // The data starts after the '_' that must be the first character after the tag but for
      // white space (VTK, not finding it there, scans on and reads from elsewhere).
      dataStart = this->Text.find('>', appended) + 1;
      while (dataStart < this->Text.size() &&
        std::isspace(static_cast<unsigned char>(this->Text[dataStart])))
        ++dataStart;
      if (dataStart >= this->Text.size() || this->Text[dataStart] != '_')
        this->fail("AppendedData does not start with its '_' marker");
      ++dataStart;
    }
    const size_t image = this->Text.find("<ImageData");
    if (image == std::string::npos)
      this->fail("no ImageData element");
    const std::array<long long, 6> whole = extentOf(attribute(this->tag(image), "WholeExtent"));
    uint64_t covered = 0;
    for (size_t piece = this->Text.find("<Piece"); piece != std::string::npos && piece < appended;
         piece = this->Text.find("<Piece", piece + 1))
    {
      const std::array<long long, 6> extent = extentOf(attribute(this->tag(piece), "Extent"));
      for (int a = 0; a < 3; ++a)
      {
        if (extent[2 * a] < whole[2 * a] || extent[2 * a + 1] > whole[2 * a + 1])
          this->fail("a Piece outside the WholeExtent");
      }
      const uint64_t points = pointsOf(extent);
      covered += points;
      const size_t end = this->Text.find("</Piece>", piece);
      for (size_t a = this->Text.find("<DataArray", piece); a != std::string::npos && a < end;
           a = this->Text.find("<DataArray", a + 1))
      {
        const std::string element = this->tag(a);
        const std::string format = attribute(element, "format");
        if (format == "ascii")
          continue;
        const uint64_t bytes = points * componentsOf(element) * typeSize(attribute(element, "type"));
        if (format == "appended")
        {
          if (dataStart == std::string::npos)
            this->fail("an appended array without AppendedData");
          const uint64_t offset = number(attribute(element, "offset"), "offset");
          if (offset > this->Text.size() - dataStart)
            this->fail("an array offset past the end of the file");
          this->checkHeader(dataStart + size_t(offset), appendedRaw, bytes);
        }
        else if (format == "binary")
          this->checkHeader(this->Text.find('>', a) + 1, false, bytes);
        else
          this->fail("DataArray format '" + format + "' (ascii, binary or appended)");
      }
    }
    // VTK leaves the parts of the whole extent that no piece covers at zero: an incomplete file
    // would read as a volume with background there.
    if (covered != pointsOf(whole))
      this->fail("the pieces hold " + std::to_string(covered) + " of the whole extent's " +
        std::to_string(pointsOf(whole)) + " points");
  }

private:
  [[noreturn]] void fail(const std::string& what) const
  {
    throw svdagReadError(vtkErrorCode::FileFormatError,
      this->FileName + ": invalid VTK XML image data: " + what);
  }

  // The start tag beginning at `at`, without the closing '>'.
  std::string tag(size_t at) const
  {
    const size_t end = this->Text.find('>', at);
    if (end == std::string::npos)
      this->fail("a tag without its end");
    return this->Text.substr(at, end - at);
  }

  static std::string attribute(const std::string& tag, const char* name)
  {
    const std::string key = std::string(" ") + name + "=\"";
    const size_t at = tag.find(key);
    if (at == std::string::npos)
      return "";
    const size_t begin = at + key.size();
    const size_t end = tag.find('"', begin);
    return end == std::string::npos ? "" : tag.substr(begin, end - begin);
  }

  uint64_t number(const std::string& text, const char* what) const
  {
    if (text.empty() || text.find_first_not_of("0123456789") != std::string::npos ||
      text.size() > 18)
      this->fail(std::string("a bad ") + what + " '" + text + "'");
    return std::stoull(text);
  }

  std::array<long long, 6> extentOf(const std::string& text) const
  {
    std::array<long long, 6> e{};
    if (std::sscanf(text.c_str(), "%lld %lld %lld %lld %lld %lld", &e[0], &e[1], &e[2], &e[3],
          &e[4], &e[5]) != 6)
      this->fail("an extent that is not 6 integers ('" + text + "')");
    return e;
  }

  uint64_t pointsOf(const std::array<long long, 6>& e) const
  {
    uint64_t points = 1;
    for (int a = 0; a < 3; ++a)
    {
      if (e[2 * a + 1] < e[2 * a] || e[2 * a + 1] - e[2 * a] >= (1ll << 31))
        this->fail("an extent of negative or absurd size");
      points *= uint64_t(e[2 * a + 1] - e[2 * a] + 1);
      if (points > (uint64_t(1) << 40))
        this->fail("an extent of more than 2^40 points");
    }
    return points;
  }

  uint64_t componentsOf(const std::string& element) const
  {
    const std::string text = attribute(element, "NumberOfComponents");
    const uint64_t components = text.empty() ? 1 : number(text, "NumberOfComponents");
    if (components < 1 || components > 1024)
      this->fail("NumberOfComponents outside 1 .. 1024");
    return components;
  }

  uint64_t typeSize(const std::string& type) const
  {
    static const std::pair<const char*, uint64_t> sizes[] = { { "Int8", 1 }, { "UInt8", 1 },
      { "Int16", 2 }, { "UInt16", 2 }, { "Int32", 4 }, { "UInt32", 4 }, { "Int64", 8 },
      { "UInt64", 8 }, { "Float32", 4 }, { "Float64", 8 }, { "Char", 1 }, { "String", 1 } };
    for (const auto& s : sizes)
    {
      if (type == s.first)
        return s.second;
    }
    this->fail("DataArray type '" + type + "'");
  }

  // The first `count` header words at `at`, stored raw or as base64.
  std::vector<uint64_t> words(size_t at, bool raw, size_t count) const
  {
    std::string bytes;
    const size_t need = count * this->WordSize;
    if (raw)
    {
      if (at > this->Text.size() || this->Text.size() - at < need)
        this->fail("a compressed array header past the end of the file");
      bytes = this->Text.substr(at, need);
    }
    else
    {
      while (at < this->Text.size() && std::isspace(static_cast<unsigned char>(this->Text[at])))
        ++at;
      bytes = decodeBase64(at, need);
    }
    std::vector<uint64_t> out(count, 0);
    for (size_t w = 0; w < count; ++w)
    {
      for (size_t b = 0; b < this->WordSize; ++b)
      {
        const size_t k = this->BigEndian ? b : this->WordSize - 1 - b;
        out[w] = (out[w] << 8) | static_cast<unsigned char>(bytes[w * this->WordSize + k]);
      }
    }
    return out;
  }

  // `need` bytes decoded from the base64 text at `at` (the header is one base64 chunk).
  std::string decodeBase64(size_t at, size_t need) const
  {
    std::string out;
    uint32_t group = 0;
    int bits = 0;
    for (size_t i = at; i < this->Text.size() && out.size() < need; ++i)
    {
      const char c = this->Text[i];
      const char* alphabet = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
      const char* p = c ? std::strchr(alphabet, c) : nullptr;
      if (!p)
        break;
      group = (group << 6) | uint32_t(p - alphabet);
      bits += 6;
      if (bits >= 8)
      {
        bits -= 8;
        out.push_back(char((group >> bits) & 0xff));
      }
    }
    if (out.size() < need)
      this->fail("a compressed array header that is not valid base64");
    return out;
  }

  void checkHeader(size_t at, bool raw, uint64_t bytes) const
  {
    if (!this->Compressed)
    {
      // One word: the array's byte count, then the bytes.
      const uint64_t stored = this->words(at, raw, 1)[0];
      if (stored != bytes)
        this->fail("an array header of " + std::to_string(stored) + " bytes for an array of " +
          std::to_string(bytes) + " bytes");
      if (raw && bytes > this->Text.size() - at - this->WordSize)
        this->fail("array data past the end of the file");
      return;
    }
    const std::vector<uint64_t> h = this->words(at, raw, 3);
    const uint64_t blocks = h[0], blockSize = h[1], lastSize = h[2];
    const uint64_t total =
      blocks == 0 ? 0 : (blocks - 1) * blockSize + (lastSize != 0 ? lastSize : blockSize);
    if (blocks > bytes + 1 || (blocks > 0 && blockSize == 0) || lastSize > blockSize ||
      total != bytes)
      this->fail("a compressed array header of " + std::to_string(blocks) + " blocks of " +
        std::to_string(blockSize) + " bytes (last " + std::to_string(lastSize) +
        ") for an array of " + std::to_string(bytes) + " bytes");
    // The compressed blocks must be there: raw, after the header words; base64, in the chunk
    // that follows the header's own base64 chunk.
    const std::vector<uint64_t> all = this->words(at, raw, size_t(3 + blocks));
    uint64_t compressed = 0;
    for (size_t b = 3; b < all.size(); ++b)
      compressed += all[b];
    uint64_t available = 0;
    if (raw)
      available = this->Text.size() - at - all.size() * this->WordSize;
    else
    {
      size_t data = at;
      while (data < this->Text.size() && std::isspace(static_cast<unsigned char>(this->Text[data])))
        ++data;
      data += 4 * ((all.size() * this->WordSize + 2) / 3); // the header chunk, padded
      uint64_t chars = 0;
      for (; data < this->Text.size(); ++data)
      {
        const char c = this->Text[data];
        if (std::isalnum(static_cast<unsigned char>(c)) || c == '+' || c == '/' || c == '=')
          ++chars;
        else if (!std::isspace(static_cast<unsigned char>(c)))
          break;
      }
      available = chars / 4 * 3;
    }
    if (compressed > available)
      this->fail("compressed blocks of " + std::to_string(compressed) + " bytes where the file holds " +
        std::to_string(available));
  }

  std::string FileName;
  std::string Text;
  size_t WordSize = 4;
  bool BigEndian = false;
  bool Compressed = false;
};
} // namespace

svdagVTIImageSlabSource::svdagVTIImageSlabSource(const std::string& fileName)
  : svdagVTKImageSlabSource(vtkSmartPointer<vtkXMLImageDataReader>::New(), fileName)
{
  HeaderCheck(fileName).run();
  vtkXMLImageDataReader::SafeDownCast(this->reader())->SetFileName(fileName.c_str());
  this->open();
  this->checkGeometry(fileName);
}

bool svdagVTIImageSlabSource::canRead(const std::string& fileName)
{
  vtkNew<vtkXMLImageDataReader> reader;
  return reader->CanReadFile(fileName.c_str()) != 0;
}
