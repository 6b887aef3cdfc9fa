#include "svdagVTIImageSlabSource.h"

#include "vtkErrorCode.h"
#include "vtkNew.h"
#include "vtkXMLImageDataReader.h"

#include <algorithm>
#include <array>
#include <cctype>
#include <cstdint>
#include <cstdio>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

namespace
{
// VTK 9.1's XML reader trusts what it reads: a compressed array's block sizes (a last block
// larger than the others wrote past a heap buffer), an appended section not starting at its '_'
// (4 GiB allocated), a DataArray without a format or a Piece with an inverted extent (a null
// stream read) were all found by the fuzzer, and so was base64 text with a character outside its
// alphabet, which VTK's decoder stops at without an error (the rest of the array stays 0).
// Before VTK reads the file, its structure is checked here: byte order, header type and
// compressor known, extents not inverted, every array's format known and its header describing
// exactly the array it fills, inside the file; and all base64 text (inline binary arrays, a
// base64 AppendedData section) exactly as VTK 9.1 writes it: per array one padded run for its
// header word and data together (uncompressed), or one for its header words and one for all its
// compressed blocks, nothing between them, appended arrays back to back, only white space around
// an inline array's text.
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
    std::vector<size_t> inPieces; // the arrays checked against their piece's extent
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
        if (attribute(element, "format") == "ascii")
          continue;
        this->checkArray(a, points * componentsOf(element) * typeSize(attribute(element, "type")),
          dataStart, appendedRaw);
        inPieces.push_back(a);
      }
    }
    // VTK decodes the arrays outside the pieces (field data; string arrays are <Array>) too:
    // their base64 is checked against their own headers, there is no extent to compare with.
    for (const char* name : { "<DataArray", "<Array " })
    {
      for (size_t a = this->Text.find(name); a != std::string::npos && a < appended;
           a = this->Text.find(name, a + 1))
      {
        if (std::find(inPieces.begin(), inPieces.end(), a) == inPieces.end() &&
          attribute(this->tag(a), "format") != "ascii")
          this->checkArray(a, UnknownSize, dataStart, appendedRaw);
      }
    }
    if (dataStart != std::string::npos && !appendedRaw)
      this->checkAppendedRuns(dataStart);
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

  // The byte count of an array that has no extent to compare with (outside the pieces).
  static constexpr uint64_t UnknownSize = ~uint64_t(0);

  // White space as XML and vtkXMLDataParser know it (the parser skips exactly these before an
  // inline array's text); std::isspace would also skip \v and \f, which VTK would decode.
  static bool isXmlSpace(char c) { return c == ' ' || c == '\t' || c == '\n' || c == '\r'; }

  // The 6-bit value of a base64 character (RFC 4648's alphabet), -1 for any other ('=' too).
  static int sextet(char c)
  {
    if (c >= 'A' && c <= 'Z')
      return c - 'A';
    if (c >= 'a' && c <= 'z')
      return c - 'a' + 26;
    if (c >= '0' && c <= '9')
      return c - '0' + 52;
    if (c == '+')
      return 62;
    if (c == '/')
      return 63;
    return -1;
  }

  // Checks the array whose start tag is at `a`: its format, and its header (raw or base64) and
  // base64 text against `bytes`, the byte count its extent implies (UnknownSize outside the
  // pieces). `dataStart` is where the appended data begins, after its '_'.
  void checkArray(size_t a, uint64_t bytes, size_t dataStart, bool appendedRaw)
  {
    const std::string element = this->tag(a);
    const std::string name = attribute(element, "Name");
    const std::string format = attribute(element, "format");
    if (format == "appended")
    {
      if (dataStart == std::string::npos)
        this->fail("an appended array without AppendedData");
      const uint64_t offset = number(attribute(element, "offset"), "offset");
      if (offset > this->Text.size() - dataStart)
        this->fail("an array offset past the end of the file");
      const size_t at = dataStart + size_t(offset);
      const size_t end = this->checkHeader(at, appendedRaw, bytes, name);
      if (!appendedRaw)
        this->AppendedRuns.push_back({ at, end, name });
    }
    else if (format == "binary")
    {
      // vtkXMLDataParser starts at the first character after the start tag that is not white
      // space, as VTK's writer indents the text.
      size_t at = this->Text.find('>', a) + 1;
      while (at < this->Text.size() && isXmlSpace(this->Text[at]))
        ++at;
      this->checkEnd(this->checkHeader(at, false, bytes, name), name);
    }
    else
      this->fail("DataArray format '" + format + "' (ascii, binary or appended)");
  }

  // Fails on the character at `i` in an array's base64 text, where a base64 character (or the
  // padding, `padding`) of its `part` run, `bytes` long (UnknownSize: not known yet), belongs.
  [[noreturn]] void failBase64(size_t i, const std::string& name, const char* part,
    uint64_t bytes, bool padding) const
  {
    std::string what;
    // White space followed by the next tag (or nothing) is the end of the text, not a space in it.
    size_t next = i;
    while (next < this->Text.size() && isXmlSpace(this->Text[next]))
      ++next;
    const bool ends = next >= this->Text.size() || this->Text[next] == '<';
    const char c = i < this->Text.size() ? this->Text[i] : '\0';
    if (sextet(c) >= 0)
      what = "it goes on past them"; // only where its padding belongs
    else if (c == '=')
      what = "padding '=' before the end of the run";
    else if (ends)
      what = padding ? "its padding '=' is missing" : "the text ends early";
    else if (isXmlSpace(c))
      what = "white space inside the run";
    else
    {
      char hex[8];
      std::snprintf(hex, sizeof(hex), "0x%02x", static_cast<unsigned char>(c));
      what = std::string("invalid base64 character ") +
        (c > ' ' && c < 127 ? std::string("'") + c + "' (" + hex + ")" : std::string(hex));
    }
    this->fail("array '" + name + "': base64 " + part +
      (bytes == UnknownSize ? std::string() : " of " + std::to_string(bytes) + " bytes") + ": " +
      what + " at byte offset " + std::to_string(i));
  }

  // Checks that the base64 text at `at` is one run of `bytes` bytes as vtkBase64OutputStream
  // writes it (4 characters for every 3 bytes, the last group padded to 4 with '='), and
  // returns where it ends. Neither white space nor anything else may interrupt it: VTK's reader
  // decodes 4 characters at a time as they come, and an invalid one ends its read silently
  // (the rest of the array stays 0). The unused low bits of a run's last character are not
  // checked: no decoded byte depends on them.
  size_t checkRun(size_t at, uint64_t bytes, const std::string& name, const char* part) const
  {
    const uint64_t left = at < this->Text.size() ? this->Text.size() - at : 0;
    // More bytes than the rest of the file could encode: the scan fails where the text ends.
    const uint64_t chars = bytes > left ? left + 1 : 4 * ((bytes + 2) / 3);
    const uint64_t data = bytes > left ? chars : (4 * bytes + 2) / 3;
    for (uint64_t k = 0; k < chars; ++k)
    {
      const size_t i = at + size_t(k);
      if (i >= this->Text.size() || (k < data ? sextet(this->Text[i]) < 0 : this->Text[i] != '='))
        this->failBase64(i, name, part, bytes, k >= data);
    }
    return at + size_t(chars);
  }

  // After an array's last run only white space may come before the next tag: more base64 is
  // more than its header gives, which VTK ignores.
  void checkEnd(size_t end, const std::string& name) const
  {
    while (end < this->Text.size() && isXmlSpace(this->Text[end]))
      ++end;
    if (end < this->Text.size() && this->Text[end] != '<')
      this->fail("array '" + name + "': base64 text past the end of its data at byte offset " +
        std::to_string(end));
  }

  // VTK's writer puts the appended arrays' runs back to back from the '_' on, at the offsets
  // their DataArrays give: a gap, an overlap or text after the last is not what it wrote (a
  // character inserted or lost between runs shows there).
  void checkAppendedRuns(size_t dataStart)
  {
    std::sort(this->AppendedRuns.begin(), this->AppendedRuns.end(),
      [](const Run& x, const Run& y) { return x.Begin < y.Begin; });
    size_t end = dataStart;
    for (const Run& run : this->AppendedRuns)
    {
      if (run.Begin != end)
        this->fail("array '" + run.Name + "': its appended data starts at byte offset " +
          std::to_string(run.Begin) + ", the base64 before it ends at byte offset " +
          std::to_string(end));
      end = run.End;
    }
    this->checkEnd(end, this->AppendedRuns.empty() ? "" : this->AppendedRuns.back().Name);
  }

  // The first `count` header words at `at`, stored raw or as base64.
  std::vector<uint64_t> words(size_t at, bool raw, size_t count, const std::string& name) const
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
      bytes = this->decodeBase64(at, need, name);
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

  // The first `need` bytes of the header run at `at`; its length is checked by checkRun once
  // the header says how long it is.
  std::string decodeBase64(size_t at, size_t need, const std::string& name) const
  {
    std::string out;
    uint32_t group = 0;
    int bits = 0;
    for (size_t i = at; out.size() < need; ++i)
    {
      const int value = i < this->Text.size() ? sextet(this->Text[i]) : -1;
      if (value < 0)
        this->failBase64(i, name, "header", UnknownSize, false);
      group = (group << 6) | uint32_t(value);
      bits += 6;
      if (bits >= 8)
      {
        bits -= 8;
        out.push_back(char((group >> bits) & 0xff));
      }
    }
    return out;
  }

  // Checks the header of an array at `at` (raw bytes or base64 text) against `bytes`, the byte
  // count its extent implies (UnknownSize: the header only has to be consistent and fit in the
  // file), and for base64 its runs; returns where its base64 text ends (npos for raw).
  size_t checkHeader(size_t at, bool raw, uint64_t bytes, const std::string& name) const
  {
    if (!this->Compressed)
    {
      // One word: the array's byte count, then the bytes (base64: one run for both, as VTK
      // writes the word and the data through one vtkBase64OutputStream).
      const uint64_t stored = this->words(at, raw, 1, name)[0];
      if (bytes != UnknownSize && stored != bytes)
        this->fail("array '" + name + "': a header of " + std::to_string(stored) +
          " bytes for an array of " + std::to_string(bytes) + " bytes");
      if (raw)
      {
        if (stored > this->Text.size() - at - this->WordSize)
          this->fail("array data past the end of the file");
        return std::string::npos;
      }
      // (A count past the file's size fails all the same: capped, it cannot wrap.)
      return this->checkRun(at, this->WordSize + std::min<uint64_t>(stored, this->Text.size() + 1),
        name, "header and data");
    }
    const std::vector<uint64_t> h = this->words(at, raw, 3, name);
    const uint64_t blocks = h[0], blockSize = h[1], lastSize = h[2];
    const uint64_t total =
      blocks == 0 ? 0 : (blocks - 1) * blockSize + (lastSize != 0 ? lastSize : blockSize);
    const bool known = bytes != UnknownSize;
    if ((known ? blocks > bytes + 1 || total != bytes : blocks > this->Text.size()) ||
      (blocks > 0 && blockSize == 0) || lastSize > blockSize)
      this->fail("array '" + name + "': a compressed header of " + std::to_string(blocks) +
        " blocks of " + std::to_string(blockSize) + " bytes (last " + std::to_string(lastSize) +
        ")" +
        (known ? " for an array of " + std::to_string(bytes) + " bytes"
               : " in a file of " + std::to_string(this->Text.size()) + " bytes"));
    // The compressed blocks must be there: raw, after the header words; base64, in the run that
    // follows the header's own run (all blocks in one: VTK's reader seeks in them as one stream).
    const std::vector<uint64_t> all = this->words(at, raw, size_t(3 + blocks), name);
    uint64_t compressed = 0;
    for (size_t b = 3; b < all.size(); ++b)
    {
      // A sum past the file's size is as wrong as any: stopping there keeps it from wrapping.
      compressed += std::min<uint64_t>(all[b], this->Text.size() + 1);
      compressed = std::min<uint64_t>(compressed, this->Text.size() + 1);
    }
    if (raw)
    {
      const uint64_t available = this->Text.size() - at - all.size() * this->WordSize;
      if (compressed > available)
        this->fail("array '" + name + "': compressed blocks of " + std::to_string(compressed) +
          " bytes where the file holds " + std::to_string(available));
      return std::string::npos;
    }
    const size_t data = this->checkRun(at, all.size() * this->WordSize, name, "header");
    return this->checkRun(data, compressed, name, "compressed blocks");
  }

  struct Run
  {
    size_t Begin, End;
    std::string Name;
  };

  std::string FileName;
  std::string Text;
  size_t WordSize = 4;
  bool BigEndian = false;
  bool Compressed = false;
  std::vector<Run> AppendedRuns; // the appended arrays' base64 text
};
} // namespace

svdagVTIImageSlabSource::svdagVTIImageSlabSource(const std::string& fileName, bool allowFloat)
  : svdagVTKImageSlabSource(vtkSmartPointer<vtkXMLImageDataReader>::New(), fileName)
{
  HeaderCheck(fileName).run();
  vtkXMLImageDataReader::SafeDownCast(this->reader())->SetFileName(fileName.c_str());
  this->open(allowFloat);
  this->checkGeometry(fileName);
}

bool svdagVTIImageSlabSource::canRead(const std::string& fileName)
{
  vtkNew<vtkXMLImageDataReader> reader;
  return reader->CanReadFile(fileName.c_str()) != 0;
}
