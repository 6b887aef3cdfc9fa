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
// VTK 9.1's vtkXMLDataParser trusts the block sizes of a compressed array's header: a last block
// larger than the block size, or blocks adding up to more than the array, make it write past its
// buffers (found by the fuzzer). Every compressed array's header is therefore checked against
// the array it must fill before VTK reads the file.
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
    if (compressor.empty())
      return; // uncompressed arrays: VTK checks their sizes itself
    this->WordSize = attribute(root, "header_type") == "UInt64" ? 8 : 4;
    this->BigEndian = attribute(root, "byte_order") == "BigEndian";
    const size_t appended = this->Text.find("<AppendedData");
    size_t dataStart = std::string::npos;
    bool appendedRaw = false;
    if (appended != std::string::npos)
    {
      const std::string encoding = attribute(this->tag(appended), "encoding");
      if (encoding != "raw" && encoding != "base64")
        this->fail("AppendedData encoding '" + encoding + "' (raw or base64)");
      appendedRaw = encoding == "raw";
      dataStart = this->Text.find('_', appended);
      if (dataStart == std::string::npos)
        this->fail("AppendedData without its '_' marker");
      ++dataStart;
    }
    for (size_t piece = this->Text.find("<Piece"); piece != std::string::npos && piece < appended;
         piece = this->Text.find("<Piece", piece + 1))
    {
      const uint64_t points = pointsOf(attribute(this->tag(piece), "Extent"));
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

  uint64_t pointsOf(const std::string& extent) const
  {
    long long e[6];
    if (std::sscanf(extent.c_str(), "%lld %lld %lld %lld %lld %lld", e, e + 1, e + 2, e + 3,
          e + 4, e + 5) != 6)
      this->fail("a Piece without a valid Extent");
    uint64_t points = 1;
    for (int a = 0; a < 3; ++a)
    {
      if (e[2 * a + 1] < e[2 * a] || e[2 * a + 1] - e[2 * a] >= (1ll << 31))
        this->fail("a Piece Extent of negative or absurd size");
      points *= uint64_t(e[2 * a + 1] - e[2 * a] + 1);
      if (points > (uint64_t(1) << 40))
        this->fail("a Piece of more than 2^40 points");
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
    const std::vector<uint64_t> h = this->words(at, raw, 3);
    const uint64_t blocks = h[0], blockSize = h[1], lastSize = h[2];
    const uint64_t total =
      blocks == 0 ? 0 : (blocks - 1) * blockSize + (lastSize != 0 ? lastSize : blockSize);
    if (blocks > bytes + 1 || (blocks > 0 && blockSize == 0) || lastSize > blockSize ||
      total != bytes)
      this->fail("a compressed array header of " + std::to_string(blocks) + " blocks of " +
        std::to_string(blockSize) + " bytes (last " + std::to_string(lastSize) +
        ") for an array of " + std::to_string(bytes) + " bytes");
    if (raw)
    {
      const std::vector<uint64_t> all = this->words(at, raw, size_t(3 + blocks));
      uint64_t compressed = 0;
      for (size_t b = 3; b < all.size(); ++b)
        compressed += all[b];
      if (compressed > this->Text.size() - at)
        this->fail("compressed blocks past the end of the file");
    }
  }

  std::string FileName;
  std::string Text;
  size_t WordSize = 4;
  bool BigEndian = false;
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
