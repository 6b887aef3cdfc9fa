// The .svdag file format (the layout is documented in svdag/File.h and IO/README.md).
#include "svdag/File.h"

#include <zlib.h>
#include <zstd.h>

#include <sys/stat.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <memory>

namespace svdag
{

const uint8_t FileMagic[FileMagicSize] = { 0x89, 'S', 'V', 'D', 'A', 'G', '\r', '\n' };

namespace
{
enum SectionId : uint32_t
{
  LabelsSection = 1,
  BlocksSection = 2,
  RootsSection = 3,
  MidsSection = 4,
  LeavesSection = 5
};
constexpr uint32_t FirstSection = LabelsSection, LastSection = LeavesSection;
const char* sectionName(uint32_t id)
{
  static const char* names[] = { "labels", "blocks", "roots", "mids", "leaves" };
  return names[id - FirstSection];
}

enum Codec : uint32_t
{
  CodecNone = 0,
  CodecZstd = 1
};

constexpr size_t FixedHeaderSize = 220; // up to and including the section count
constexpr size_t SectionEntrySize = 36;
constexpr uint32_t MaxSections = 64;
constexpr uint64_t LabelRecordSize = 40;
constexpr int MaxZstdLevel = 22;
// A zstd block yields at most 128 KiB and takes at least 4 bytes (an RLE block: 3-byte header,
// 1 byte), so no frame expands by more than this; a larger declared raw size is a lie.
constexpr uint64_t ZstdMaxExpansion = (128 * 1024) / 4;

[[noreturn]] void fail(const std::string& what)
{
  throw FileError("invalid .svdag file: " + what);
}

uint32_t crc32Of(const uint8_t* data, size_t size)
{
  uLong crc = crc32(0L, Z_NULL, 0);
  while (size > 0) // zlib's length is 32-bit: feed large sections in chunks
  {
    const uInt chunk = uInt(std::min<size_t>(size, size_t(1) << 30));
    crc = crc32(crc, data, chunk);
    data += chunk;
    size -= chunk;
  }
  return uint32_t(crc);
}

// Appends fields in little-endian order, byte by byte, whatever the host's byte order.
class ByteWriter
{
public:
  std::vector<uint8_t> bytes;

  void u16(uint16_t v) { put(v, 2); }
  void u32(uint32_t v) { put(v, 4); }
  void u64(uint64_t v) { put(v, 8); }
  void i32(int32_t v) { put(uint32_t(v), 4); }
  void f64(double v)
  {
    uint64_t bits;
    std::memcpy(&bits, &v, sizeof bits);
    put(bits, 8);
  }
  void append(const std::vector<uint8_t>& more) { bytes.insert(bytes.end(), more.begin(), more.end()); }

private:
  void put(uint64_t v, int n)
  {
    for (int i = 0; i < n; ++i)
      bytes.push_back(uint8_t(v >> (8 * i)));
  }
};

// Reads little-endian fields from a bounded range; reading past its end is a FileError that names
// the part being read.
class ByteReader
{
public:
  ByteReader(const uint8_t* data, size_t size, std::string part)
    : Data(data)
    , Size(size)
    , Part(std::move(part))
  {
  }
  size_t position() const { return Pos; }
  void skip(size_t n)
  {
    if (n > Size - Pos)
      fail(Part + " is truncated");
    Pos += n;
  }

  uint16_t u16() { return uint16_t(get(2)); }
  uint32_t u32() { return uint32_t(get(4)); }
  uint64_t u64() { return get(8); }
  int32_t i32() { return int32_t(uint32_t(get(4))); }
  double f64()
  {
    const uint64_t bits = get(8);
    double v;
    std::memcpy(&v, &bits, sizeof v);
    return v;
  }

private:
  uint64_t get(int n)
  {
    if (size_t(n) > Size - Pos)
      fail(Part + " is truncated");
    uint64_t v = 0;
    for (int i = 0; i < n; ++i)
      v |= uint64_t(Data[Pos + i]) << (8 * i);
    Pos += size_t(n);
    return v;
  }
  const uint8_t* Data;
  size_t Size;
  size_t Pos = 0;
  std::string Part;
};

struct SectionEntry
{
  uint32_t id = 0;
  uint32_t codec = CodecNone;
  uint64_t offset = 0;
  uint64_t stored = 0;
  uint64_t raw = 0;
  uint32_t crc = 0;
};

// Bytes of a packed bit field of `count` records of `bits` each, as whole 32-bit words; false on
// overflow.
bool packedWordBytes(uint64_t count, uint64_t bits, uint64_t& bytes)
{
  uint64_t total;
  if (__builtin_mul_overflow(count, bits, &total))
    return false;
  bytes = (total / 32 + (total % 32 ? 1 : 0)) * 4;
  return true;
}

// ---- writing ----

std::vector<uint8_t> wordBytes(const std::vector<uint32_t>& stream)
{
  // The trailing padding word is an in-memory convenience (Layout.h), not part of the file.
  ByteWriter w;
  w.bytes.reserve(stream.empty() ? 0 : (stream.size() - 1) * 4);
  for (size_t i = 0; i + 1 < stream.size(); ++i)
    w.u32(stream[i]);
  return std::move(w.bytes);
}

std::vector<uint8_t> rawSection(const Volume& v, uint32_t id)
{
  ByteWriter w;
  switch (id)
  {
    case LabelsSection:
      w.bytes.reserve(v.labels.size() * LabelRecordSize);
      for (const LabelInfo& l : v.labels)
      {
        w.u64(l.value);
        w.u64(l.voxels);
        for (int32_t b : l.bounds)
          w.i32(b);
      }
      return std::move(w.bytes);
    case BlocksSection: return wordBytes(v.blocks);
    case RootsSection: return wordBytes(v.roots);
    case MidsSection: return wordBytes(v.mids);
    default:
      w.bytes.reserve(v.leaves.size() * 8);
      for (uint64_t leaf : v.leaves)
        w.u64(leaf);
      return std::move(w.bytes);
  }
}

// ---- reading ----

// Decompresses one zstd frame that must yield exactly `raw` bytes. The output grows with what the
// frame actually produces, so a false raw size cannot make us reserve memory up front.
std::vector<uint8_t> inflate(const uint8_t* src, size_t stored, uint64_t raw, const std::string& part)
{
  const unsigned long long declared = ZSTD_getFrameContentSize(src, stored);
  if (declared == ZSTD_CONTENTSIZE_ERROR)
    fail(part + " is not a valid zstd frame");
  if (declared == ZSTD_CONTENTSIZE_UNKNOWN || declared != raw)
    fail(part + ": the zstd frame's size does not match the declared raw size");
  std::unique_ptr<ZSTD_DCtx, size_t (*)(ZSTD_DCtx*)> ctx(ZSTD_createDCtx(), ZSTD_freeDCtx);
  if (!ctx)
    throw FileError("cannot create a zstd decompression context");

  std::vector<uint8_t> out(size_t(std::min<uint64_t>(raw, std::max<uint64_t>(4 * uint64_t(stored), 1 << 16))));
  size_t produced = 0;
  uint8_t scratch = 0; // catches a frame that goes on past the declared size
  ZSTD_inBuffer in = { src, stored, 0 };
  for (;;)
  {
    if (produced == out.size() && out.size() < raw)
      out.resize(size_t(std::min<uint64_t>(raw, 2 * uint64_t(out.size()))));
    const bool full = produced == out.size();
    ZSTD_outBuffer o = full ? ZSTD_outBuffer{ &scratch, 1, 0 }
                            : ZSTD_outBuffer{ out.data(), out.size(), produced };
    const size_t inBefore = in.pos, outBefore = o.pos;
    const size_t r = ZSTD_decompressStream(ctx.get(), &o, &in);
    if (ZSTD_isError(r))
      fail(part + ": corrupt zstd data (" + ZSTD_getErrorName(r) + ")");
    if (full && o.pos > 0)
      fail(part + " decompresses to more than its declared raw size");
    if (!full)
      produced = o.pos;
    if (r == 0)
      break;
    if (in.pos == inBefore && o.pos == outBefore)
      fail(part + ": truncated zstd frame");
  }
  if (in.pos != in.size)
    fail(part + ": data after the end of the zstd frame");
  if (produced != raw)
    fail(part + " decompresses to fewer bytes than declared");
  return out;
}

std::vector<uint32_t> paddedWords(const std::vector<uint8_t>& bytes)
{
  ByteReader r(bytes.data(), bytes.size(), "word stream");
  std::vector<uint32_t> words(bytes.size() / 4 + 1, 0u); // + the zero padding word
  for (size_t i = 0; i + 1 < words.size(); ++i)
    words[i] = r.u32();
  return words;
}

bool validPattern(ScalarType t, uint64_t v)
{
  uint64_t tmp = 0;
  scalarStore(t, &tmp, 0, v);
  return scalarLoad(t, &tmp, 0) == v;
}

void readLabels(const std::vector<uint8_t>& bytes, uint64_t count, Volume& v)
{
  ByteReader r(bytes.data(), bytes.size(), "labels section");
  const auto& d = v.geometry.dims;
  v.labels.resize(size_t(count));
  for (LabelInfo& l : v.labels)
  {
    l.value = r.u64();
    l.voxels = r.u64();
    for (int32_t& b : l.bounds)
      b = r.i32();
    if (!validPattern(v.scalarType, l.value))
      fail("label value outside the range of " + std::string(scalarName(v.scalarType)));
    if (l.value == v.background)
      fail("the label table holds the background value");
    uint64_t boxVoxels = 1;
    for (int a = 0; a < 3; ++a)
    {
      const int32_t lo = l.bounds[2 * a], hi = l.bounds[2 * a + 1];
      if (lo < 0 || lo > hi || hi >= d[a])
        fail("label bounds outside the volume");
      boxVoxels *= uint64_t(hi - lo) + 1; // <= voxelCount <= 2^44 (checkGeometry), no overflow
    }
    if (l.voxels == 0 || l.voxels > boxVoxels)
      fail("label voxel count inconsistent with its bounds");
  }
}
} // namespace

std::vector<uint8_t> serialize(const Volume& v, const WriteOptions& options)
{
  if (options.zstdLevel < 0 || options.zstdLevel > MaxZstdLevel)
    throw FileError("zstd level must be in 0..22 (got " + std::to_string(options.zstdLevel) + ")");
  try
  {
    v.validate();
  }
  catch (const std::exception& e)
  {
    throw FileError(std::string("cannot write an inconsistent volume: ") + e.what());
  }

  ByteWriter w;
  w.bytes.insert(w.bytes.end(), FileMagic, FileMagic + FileMagicSize);
  w.u16(FileMajorVersion);
  w.u16(FileMinorVersion);
  const Geometry& g = v.geometry;
  for (int32_t d : g.dims)
    w.i32(d);
  for (double s : g.spacing)
    w.f64(s);
  for (double o : g.origin)
    w.f64(o);
  for (double d : g.direction)
    w.f64(d);
  w.u32(uint32_t(v.scalarType));
  w.u64(v.background);
  for (uint32_t width : { v.widths.cellBits, v.widths.labelBits, v.widths.rootRefBits,
         v.widths.midRefBits, v.widths.leafRefBits })
    w.u32(width);
  for (uint64_t count : { uint64_t(v.labels.size()), v.blockCount, v.rootCount, v.midCount,
         uint64_t(v.leaves.size()) })
    w.u64(count);
  const uint32_t sectionCount = LastSection - FirstSection + 1;
  w.u32(sectionCount);

  // Sections are compressed first, so that the table can be written before them.
  std::vector<SectionEntry> table;
  std::vector<std::vector<uint8_t>> payloads;
  uint64_t offset = FixedHeaderSize + SectionEntrySize * sectionCount + 4;
  for (uint32_t id = FirstSection; id <= LastSection; ++id)
  {
    std::vector<uint8_t> raw = rawSection(v, id);
    SectionEntry e;
    e.id = id;
    e.raw = raw.size();
    e.crc = crc32Of(raw.data(), raw.size());
    if (options.zstdLevel > 0 && !raw.empty())
    {
      std::vector<uint8_t> packed(ZSTD_compressBound(raw.size()));
      const size_t n =
        ZSTD_compress(packed.data(), packed.size(), raw.data(), raw.size(), options.zstdLevel);
      if (ZSTD_isError(n))
        throw FileError(std::string("zstd compression failed: ") + ZSTD_getErrorName(n));
      if (n < raw.size()) // incompressible sections are stored as they are
      {
        packed.resize(n);
        raw.swap(packed);
        e.codec = CodecZstd;
      }
    }
    e.offset = offset;
    e.stored = raw.size();
    offset += e.stored;
    table.push_back(e);
    payloads.push_back(std::move(raw));
  }
  for (const SectionEntry& e : table)
  {
    w.u32(e.id);
    w.u32(e.codec);
    w.u64(e.offset);
    w.u64(e.stored);
    w.u64(e.raw);
    w.u32(e.crc);
  }
  w.u32(crc32Of(w.bytes.data(), w.bytes.size()));
  w.bytes.reserve(size_t(offset));
  for (const auto& p : payloads)
    w.append(p);
  return std::move(w.bytes);
}

Volume deserialize(const uint8_t* data, size_t size)
{
  if (size < FileMagicSize || std::memcmp(data, FileMagic, FileMagicSize) != 0)
    throw FileError("not an .svdag file (the file does not start with the .svdag signature)");
  ByteReader h(data, size, "header");
  h.skip(FileMagicSize);
  const uint16_t major = h.u16(), minor = h.u16();
  if (major != FileMajorVersion)
    throw FileError("unsupported .svdag format version " + std::to_string(major) + "." +
      std::to_string(minor) + " (this reader reads version " + std::to_string(FileMajorVersion) +
      ".x)");

  Volume v;
  Geometry& g = v.geometry;
  for (int32_t& d : g.dims)
    d = h.i32();
  for (double& s : g.spacing)
    s = h.f64();
  for (double& o : g.origin)
    o = h.f64();
  for (double& d : g.direction)
    d = h.f64();
  const uint32_t type = h.u32();
  v.background = h.u64();
  FieldWidths& fw = v.widths;
  for (uint32_t* width :
    { &fw.cellBits, &fw.labelBits, &fw.rootRefBits, &fw.midRefBits, &fw.leafRefBits })
    *width = h.u32();
  uint64_t labelCount = h.u64(), leafCount;
  v.blockCount = h.u64();
  v.rootCount = h.u64();
  v.midCount = h.u64();
  leafCount = h.u64();
  const uint32_t sectionCount = h.u32();
  if (sectionCount > MaxSections)
    fail("header: " + std::to_string(sectionCount) + " sections (at most " +
      std::to_string(MaxSections) + ")");
  std::vector<SectionEntry> table(sectionCount);
  for (SectionEntry& e : table)
  {
    e.id = h.u32();
    e.codec = h.u32();
    e.offset = h.u64();
    e.stored = h.u64();
    e.raw = h.u64();
    e.crc = h.u32();
  }
  const size_t headerBytes = h.position();
  if (h.u32() != crc32Of(data, headerBytes))
    fail("header checksum mismatch (the header or section table is corrupt)");
  const uint64_t headerEnd = h.position();

  // Header fields. The checksum matched, so these are what a writer wrote; still check them, a
  // buggy or hostile writer must not get past this point.
  const std::string geometryProblem = checkGeometry(g);
  if (!geometryProblem.empty())
    fail("header: " + geometryProblem);
  if (type >= uint32_t(ScalarTypeCount))
    fail("header: unknown scalar type " + std::to_string(type));
  v.scalarType = ScalarType(type);
  if (!validPattern(v.scalarType, v.background))
    fail("header: background value outside the range of " + std::string(scalarName(v.scalarType)));
  for (uint32_t width : { fw.cellBits, fw.labelBits, fw.rootRefBits, fw.midRefBits, fw.leafRefBits })
  {
    if (width > 32)
      fail("header: field width " + std::to_string(width) + " above 32 bits");
  }
  if (labelCount > g.voxelCount())
    fail("header: more labels than voxels");

  // Raw sizes the counts imply (node streams: between 16 and 16 + 8 * refBits bits per node).
  uint64_t expected[LastSection + 1] = {};
  if (__builtin_mul_overflow(labelCount, LabelRecordSize, &expected[LabelsSection]))
    fail("header: label count too large");
  if (!packedWordBytes(v.blockCount, fw.blockBits(), expected[BlocksSection]))
    fail("header: block count too large");
  if (__builtin_mul_overflow(leafCount, uint64_t(8), &expected[LeavesSection]))
    fail("header: leaf count too large");
  auto checkNodeStream = [&](uint64_t raw, uint64_t count, uint32_t refBits, const char* name) {
    const unsigned __int128 bits = (unsigned __int128)raw * 8;
    const unsigned __int128 minBits = (unsigned __int128)count * layout::NODE_HEADER_BITS;
    const unsigned __int128 maxBits =
      (unsigned __int128)count * (layout::NODE_HEADER_BITS + 8 * refBits);
    if (raw % 4 != 0 || bits < minBits || bits >= maxBits + 32)
      fail(std::string(name) + " section size does not match its node count");
  };

  // Section table: each known section once, inside the file, after the header, no overlaps.
  const SectionEntry* known[LastSection + 1] = {};
  std::vector<const SectionEntry*> byOffset;
  for (const SectionEntry& e : table)
  {
    const bool isKnown = e.id >= FirstSection && e.id <= LastSection;
    const std::string name =
      isKnown ? std::string(sectionName(e.id)) + " section" : "section " + std::to_string(e.id);
    if (e.offset < headerEnd || e.offset > size || e.stored > size - e.offset)
      fail(name + " lies outside the file (the file may be truncated)");
    if (e.codec == CodecNone)
    {
      if (e.raw != e.stored)
        fail(name + ": stored and raw sizes differ for an uncompressed section");
    }
    else if (e.codec == CodecZstd)
    {
      if (e.stored == 0 || e.raw / ZstdMaxExpansion > e.stored)
        fail(name + ": declared raw size impossible for its compressed size");
    }
    else
      fail(name + ": unknown codec " + std::to_string(e.codec));
    if (isKnown)
    {
      if (known[e.id])
        fail(name + " appears twice");
      known[e.id] = &e;
    }
    byOffset.push_back(&e);
  }
  for (uint32_t id = FirstSection; id <= LastSection; ++id)
  {
    if (!known[id])
      fail(std::string(sectionName(id)) + " section missing");
    const uint64_t raw = known[id]->raw;
    if (id == RootsSection)
      checkNodeStream(raw, v.rootCount, fw.midRefBits, "roots");
    else if (id == MidsSection)
      checkNodeStream(raw, v.midCount, fw.leafRefBits, "mids");
    else if (raw != expected[id])
      fail(std::string(sectionName(id)) + " section size does not match the header's count");
  }
  std::sort(byOffset.begin(), byOffset.end(),
    [](const SectionEntry* a, const SectionEntry* b) { return a->offset < b->offset; });
  for (size_t i = 1; i < byOffset.size(); ++i)
  {
    if (byOffset[i - 1]->offset + byOffset[i - 1]->stored > byOffset[i]->offset)
      fail("sections overlap");
  }

  // Sections, one pass: decompress, checksum, decode.
  for (uint32_t id = FirstSection; id <= LastSection; ++id)
  {
    const SectionEntry& e = *known[id];
    const std::string name = std::string(sectionName(id)) + " section";
    const uint8_t* stored = data + e.offset;
    std::vector<uint8_t> raw = e.codec == CodecZstd
      ? inflate(stored, size_t(e.stored), e.raw, name)
      : std::vector<uint8_t>(stored, stored + e.stored);
    if (crc32Of(raw.data(), raw.size()) != e.crc)
      fail(name + " checksum mismatch (the data is corrupt)");
    switch (id)
    {
      case LabelsSection: readLabels(raw, labelCount, v); break;
      case BlocksSection: v.blocks = paddedWords(raw); break;
      case RootsSection: v.roots = paddedWords(raw); break;
      case MidsSection: v.mids = paddedWords(raw); break;
      default:
      {
        ByteReader r(raw.data(), raw.size(), name);
        v.leaves.resize(size_t(leafCount));
        for (uint64_t& leaf : v.leaves)
          leaf = r.u64();
      }
    }
  }

  try
  {
    v.validate(); // every reference, offset and bound of the structure
  }
  catch (const std::exception& e)
  {
    fail(e.what());
  }
  return v;
}

void writeFile(const Volume& volume, const std::string& path, const WriteOptions& options)
{
  const std::vector<uint8_t> bytes = serialize(volume, options);
  // A temporary name next to the target: a failed write leaves the old file (if any) intact.
  const std::string temporary = path + ".partial";
  std::FILE* f = std::fopen(temporary.c_str(), "wb");
  if (!f)
    throw FileOpenError("cannot create '" + path + "': " + std::strerror(errno));
  const size_t written = std::fwrite(bytes.data(), 1, bytes.size(), f);
  const int writeErrno = errno;
  const bool flushed = std::fflush(f) == 0;
  const bool closed = std::fclose(f) == 0;
  if (written != bytes.size() || !flushed || !closed)
  {
    std::remove(temporary.c_str());
    throw FileWriteError("cannot write '" + path + "': " +
      std::strerror(written != bytes.size() ? writeErrno : errno));
  }
  if (std::rename(temporary.c_str(), path.c_str()) != 0)
  {
    const int renameErrno = errno;
    std::remove(temporary.c_str());
    throw FileOpenError("cannot create '" + path + "': " + std::strerror(renameErrno));
  }
}

Volume readFile(const std::string& path)
{
  struct stat info;
  if (::stat(path.c_str(), &info) != 0)
    throw FileError("cannot open '" + path + "': " + std::strerror(errno));
  if (!S_ISREG(info.st_mode))
    throw FileError("cannot read '" + path + "': not a regular file");
  std::unique_ptr<std::FILE, int (*)(std::FILE*)> f(std::fopen(path.c_str(), "rb"), std::fclose);
  if (!f)
    throw FileError("cannot open '" + path + "': " + std::strerror(errno));
  // Read the size the file has once opened, then one read; a file that changes meanwhile shows
  // up as a short read or is caught by the checksums.
  if (std::fseek(f.get(), 0, SEEK_END) != 0)
    throw FileError("cannot read '" + path + "': " + std::strerror(errno));
  const long size = std::ftell(f.get());
  if (size < 0 || std::fseek(f.get(), 0, SEEK_SET) != 0)
    throw FileError("cannot read '" + path + "': " + std::strerror(errno));
  std::vector<uint8_t> bytes(static_cast<size_t>(size));
  if (std::fread(bytes.data(), 1, bytes.size(), f.get()) != bytes.size())
    throw FileError("cannot read '" + path + "': short read");
  try
  {
    return deserialize(bytes.data(), bytes.size());
  }
  catch (const FileError& e)
  {
    throw FileError(path + ": " + e.what());
  }
}

bool isSVDAGFile(const std::string& path)
{
  std::unique_ptr<std::FILE, int (*)(std::FILE*)> f(std::fopen(path.c_str(), "rb"), std::fclose);
  uint8_t magic[FileMagicSize];
  return f && std::fread(magic, 1, FileMagicSize, f.get()) == FileMagicSize &&
    std::memcmp(magic, FileMagic, FileMagicSize) == 0;
}

} // namespace svdag
