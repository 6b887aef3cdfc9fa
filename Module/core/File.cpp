// The .svdag file format (the layout is documented in svdag/File.h and IO/README.md).
#include "svdag/File.h"
#include "svdag/Compact.h"

#include "Bits.h"
#include "CodedVolume.h"
#include "DagStreams.h"
#include "FileVersion1.h"
#include "PooledGraph.h"

#include <zlib.h>
#include <zstd.h>

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <functional>
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
  LeavesSection = 5,
  CodedSection = 6,     // format 3: the whole volume, coded (CodedVolume.h)
  DagStreamsSection = 7 // format 4: the DAG as byte streams under zstd (DagStreams.h)
};
constexpr uint32_t FirstSection = LabelsSection, LastSection = DagStreamsSection;
const char* sectionName(uint32_t id)
{
  static const char* names[] = { "labels", "blocks", "roots", "mids", "leaves", "coded volume",
    "DAG streams" };
  return names[id - FirstSection];
}
// The sections a file of a major version must hold: 1-5 up to 2.x, 6 in 3.x, 7 from 4.0 on.
bool requiredSection(uint16_t major, uint32_t id)
{
  return major >= 4 ? id == DagStreamsSection
                    : major == 3 ? id == CodedSection : id <= LeavesSection;
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

using bits::storeLE;

// A 4.0 load on two threads (SplitLoadBytes and up) compacts the volume beside its last checks
// up to this size, from a copy of the pooled form: there a load is too short for its loops'
// halves to pay, and the copy is cheap. Larger volumes split each loop instead and free the
// pooled streams before compacting.
constexpr uint64_t CompactAlongsideBytes = uint64_t(4) << 20;
// A 4.0 load of a smaller streams section runs on the calling thread alone. On a shared machine
// a second thread is sometimes fast and sometimes slower than none, for seconds at a time, and
// below this size the slow phases cost more than the fast ones save: fib25_64's 18.6 KB took
// 0.25 ms or 0.42 ms on two threads and 0.32 ms on one, totalseg_ct's 11 KB 0.17 or 0.26 against
// 0.20; gala_train_gt's 47 KB took 0.66 or 0.98 ms on two and 1.05 ms on one.
constexpr uint64_t SplitLoadBytes = 32768;

// Files are read and written at most this many bytes per call: a single read or write of
// more than 2 GiB fails on some systems (macOS's write, for one).
constexpr size_t IoChunk = size_t(1) << 30;

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

// A section's raw bytes are produced in pieces of at most RawChunk bytes, converted from the
// volume on the fly: checksumming, compressing or writing a section of any size costs no copy of
// it.
constexpr size_t RawChunk = size_t(1) << 20;
using ChunkSink = std::function<void(const uint8_t* data, size_t size)>;

// The elements of an array as little-endian bytes of `size` each, one chunk at a time.
template <typename T, typename Store>
void elementChunks(
  const T* items, size_t count, size_t size, const Store& store, const ChunkSink& sink)
{
  const size_t perChunk = RawChunk / size;
  std::vector<uint8_t> chunk(std::min(count, perChunk) * size);
  for (size_t first = 0; first < count; first += perChunk)
  {
    const size_t n = std::min(count - first, perChunk);
    for (size_t i = 0; i < n; ++i)
      store(&chunk[i * size], items[first + i]);
    sink(chunk.data(), n * size);
  }
}

// Raw bytes of a section (File.h); word streams without their trailing padding word (an
// in-memory convenience, Layout.h, not part of the file).
uint64_t rawSectionSize(const Volume& v, uint32_t id)
{
  auto words = [](const std::vector<uint32_t>& stream) {
    return stream.empty() ? 0 : 4 * uint64_t(stream.size() - 1);
  };
  switch (id)
  {
    case LabelsSection: return LabelRecordSize * v.labels.size();
    case BlocksSection: return words(v.blocks);
    case RootsSection: return words(v.roots);
    case MidsSection: return words(v.mids);
    default: return 8 * uint64_t(v.leaves.size());
  }
}

void rawSectionChunks(const Volume& v, uint32_t id, const ChunkSink& sink)
{
  auto word = [](uint8_t* at, uint32_t w) { storeLE(at, w, 4); };
  auto words = [&](const std::vector<uint32_t>& stream) {
    elementChunks(stream.data(), stream.empty() ? 0 : stream.size() - 1, 4, word, sink);
  };
  switch (id)
  {
    case LabelsSection:
      elementChunks(v.labels.data(), v.labels.size(), size_t(LabelRecordSize),
        [](uint8_t* at, const LabelInfo& l) {
          storeLE(at, l.value, 8);
          storeLE(at + 8, l.voxels, 8);
          for (int b = 0; b < 6; ++b)
            storeLE(at + 16 + 4 * b, uint32_t(l.bounds[b]), 4);
        },
        sink);
      break;
    case BlocksSection: words(v.blocks); break;
    case RootsSection: words(v.roots); break;
    case MidsSection: words(v.mids); break;
    default:
      elementChunks(v.leaves.data(), v.leaves.size(), 8,
        [](uint8_t* at, uint64_t leaf) { storeLE(at, leaf, 8); }, sink);
  }
}

// One section as the file stores it: its table entry, and the zstd frame when that is smaller
// than the raw bytes (which are produced again when the file is written). The frame is written
// into a buffer of raw - 1 bytes that is never initialised, so only the bytes zstd writes are
// touched: a large section costs its compressed size.
struct StoredSection
{
  SectionEntry entry;
  std::unique_ptr<uint8_t[]> packed;
};

// A file as its header (magic, fields, section table and their crc) and its sections, in file
// order; writeFile writes the parts one after the other, without assembling the whole file.
struct EncodedFile
{
  std::vector<uint8_t> header;
  std::vector<StoredSection> sections;
};

// The crc32 of a section's raw bytes and, at a level above 0, its zstd frame (one streaming pass
// over the raw bytes; the frame header holds the raw size, as the reader requires), kept when it
// is smaller than the raw bytes: incompressible sections are stored as they are.
StoredSection storeSection(const Volume& v, uint32_t id, int level)
{
  StoredSection s;
  SectionEntry& e = s.entry;
  e.id = id;
  e.raw = rawSectionSize(v, id);
  e.stored = e.raw;
  uLong crc = crc32(0L, Z_NULL, 0);
  std::unique_ptr<ZSTD_CCtx, size_t (*)(ZSTD_CCtx*)> ctx(nullptr, ZSTD_freeCCtx);
  ZSTD_outBuffer out = { nullptr, 0, 0 };
  bool fits = level > 0 && e.raw > 0;
  auto check = [](size_t r) {
    if (ZSTD_isError(r))
      throw FileError(std::string("zstd compression failed: ") + ZSTD_getErrorName(r));
    return r;
  };
  if (fits)
  {
    ctx.reset(ZSTD_createCCtx());
    if (!ctx)
      throw FileError("cannot create a zstd compression context");
    check(ZSTD_CCtx_setParameter(ctx.get(), ZSTD_c_compressionLevel, level));
    check(ZSTD_CCtx_setPledgedSrcSize(ctx.get(), e.raw));
    s.packed.reset(new uint8_t[size_t(e.raw - 1)]);
    out = { s.packed.get(), size_t(e.raw - 1), 0 };
  }
  rawSectionChunks(v, id, [&](const uint8_t* data, size_t size) {
    crc = crc32(crc, data, uInt(size)); // chunks are at most RawChunk bytes
    ZSTD_inBuffer in = { data, size, 0 };
    while (fits && in.pos < in.size)
    {
      check(ZSTD_compressStream2(ctx.get(), &out, &in, ZSTD_e_continue));
      fits = out.pos < out.size || in.pos == in.size; // a full buffer: not smaller than raw
    }
  });
  e.crc = uint32_t(crc);
  while (fits)
  {
    ZSTD_inBuffer none = { nullptr, 0, 0 };
    if (check(ZSTD_compressStream2(ctx.get(), &out, &none, ZSTD_e_end)) == 0)
    {
      e.codec = CodecZstd;
      e.stored = out.pos;
      break;
    }
    fits = out.pos < out.size;
  }
  if (e.codec != CodecZstd)
    s.packed.reset();
  return s;
}

// Writes a section's stored bytes to a sink: its frame, or its raw bytes produced again.
void storedChunks(const Volume& v, const StoredSection& s, const ChunkSink& sink)
{
  if (s.packed)
    sink(s.packed.get(), size_t(s.entry.stored));
  else
    rawSectionChunks(v, s.entry.id, sink);
}

// The volume a section just made decodes to (decode() returns it), checked against the volume
// written, block by block, so that a writer's bug never reaches a file; `what` names the section
// in the error ("the coded volume does").
template <typename Decode>
Volume decodedAgain(const Volume& v, const char* what, const Decode& decode)
{
  Volume again;
  std::string difference;
  try
  {
    again = decode();
    difference = coded::compareOccupancy(v, again);
  }
  catch (const std::exception& e)
  {
    difference = e.what();
  }
  if (!difference.empty())
    throw FileError(std::string("internal error: ") + what + " not decode to the volume written (" +
      difference + ")");
  return again;
}

// A section of bytes already coded: stored as they are (codec 0).
StoredSection storedAsIs(uint32_t id, const std::vector<uint8_t>& bytes)
{
  StoredSection s;
  s.entry.id = id;
  s.entry.codec = CodecNone;
  s.entry.raw = s.entry.stored = bytes.size();
  s.entry.crc = crc32Of(bytes.data(), bytes.size());
  s.packed.reset(new uint8_t[bytes.size()]);
  std::copy(bytes.begin(), bytes.end(), s.packed.get());
  return s;
}

// Format 3's one section: the coded volume, checked by decoding it again. A volume read from an
// older file may have its pools in another order than a build's first-use order, which loading
// rebuilds, so the header describes the rebuilt volume.
StoredSection storeCoded(const Volume& v, Volume& rebuilt, const ParallelFor& parallel)
{
  const std::vector<uint8_t> bytes = coded::encode(v, parallel);
  rebuilt = decodedAgain(v, "the coded volume does", [&] {
    return coded::decode(bytes.data(), bytes.size(), coded::frameOf(v), parallel);
  });
  return storedAsIs(CodedSection, bytes);
}

// Format 4's zstd level: fixed, as what the format promises in bytes depends on it (level 3 gives
// files about 5% larger); its streams are small, so writing stays within a few builds' time.
constexpr int DagStreamsZstdLevel = 19;

// Format 4's one section: each of the DAG's streams as a zstd frame (as it is where the frame
// would not be smaller), after a table of their stored and raw sizes (varints). Checked by
// decoding it again; the header describes the decoded volume (its pools in first-use order).
StoredSection storeDagStreams(const Volume& v, Volume& rebuilt)
{
  dagstreams::Encoded encoded = dagstreams::encode(v);
  std::vector<uint8_t> table, frames;
  std::unique_ptr<ZSTD_CCtx, size_t (*)(ZSTD_CCtx*)> ctx(ZSTD_createCCtx(), ZSTD_freeCCtx);
  if (!ctx)
    throw FileError("cannot create a zstd compression context");
  for (const std::vector<uint8_t>& stream : encoded.streams)
  {
    std::vector<uint8_t> frame(ZSTD_compressBound(stream.size()));
    size_t size = ZSTD_compressCCtx(ctx.get(), frame.data(), frame.size(), stream.data(),
      stream.size(), DagStreamsZstdLevel);
    if (ZSTD_isError(size))
      throw FileError(std::string("zstd compression failed: ") + ZSTD_getErrorName(size));
    if (size >= stream.size())
    {
      frame = stream;
      size = stream.size();
    }
    bits::putVarint(table, size);
    bits::putVarint(table, stream.size());
    frames.insert(frames.end(), frame.begin(), frame.begin() + std::ptrdiff_t(size));
  }
  rebuilt = decodedAgain(v, "the DAG streams do", [&] {
    // Checked by walking the streams it decoded, which the comparison reads.
    Volume decoded = dagstreams::decode(encoded.streams, encoded.shape);
    decoded.deriveBoundsAndValidate();
    return decoded;
  });
  table.insert(table.end(), frames.begin(), frames.end());
  return storedAsIs(DagStreamsSection, table);
}

EncodedFile encode(const Volume& volume, const WriteOptions& options, const ParallelFor& parallel)
{
  if (options.formatVersion < 2 || options.formatVersion > 4)
    throw FileError("format version must be 2, 3 or 4 (got " + std::to_string(options.formatVersion) + ")");
  if (options.zstdLevel < 0 || options.zstdLevel > MaxZstdLevel)
    throw FileError("zstd level must be in 0..22 (got " + std::to_string(options.zstdLevel) + ")");
  try
  {
    volume.validate(parallel);
  }
  catch (const std::exception& e)
  {
    throw FileError(std::string("cannot write an inconsistent volume: ") + e.what());
  }

  // Sections are prepared first, so that the table can be written before them.
  EncodedFile file;
  Volume rebuilt;
  const Volume& v = options.formatVersion >= 3 ? rebuilt : volume;
  if (options.formatVersion == 4)
    file.sections.push_back(storeDagStreams(volume, rebuilt));
  else if (options.formatVersion == 3)
    file.sections.push_back(storeCoded(volume, rebuilt, parallel));
  else
  {
    for (uint32_t id = LabelsSection; id <= LeavesSection; ++id)
      file.sections.push_back(storeSection(v, id, options.zstdLevel));
  }

  ByteWriter w;
  w.bytes.insert(w.bytes.end(), FileMagic, FileMagic + FileMagicSize);
  w.u16(uint16_t(options.formatVersion));
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
  const uint32_t sectionCount = uint32_t(file.sections.size());
  w.u32(sectionCount);
  uint64_t offset = FixedHeaderSize + SectionEntrySize * sectionCount + 4;
  for (StoredSection& s : file.sections)
  {
    SectionEntry& e = s.entry;
    e.offset = offset;
    offset += e.stored;
    w.u32(e.id);
    w.u32(e.codec);
    w.u64(e.offset);
    w.u64(e.stored);
    w.u64(e.raw);
    w.u32(e.crc);
  }
  w.u32(crc32Of(w.bytes.data(), w.bytes.size()));
  file.header = std::move(w.bytes);
  return file;
}

// Writes every byte, IoChunk at a time; false on a short write (errno says why).
bool writeAll(std::FILE* f, const uint8_t* data, size_t size)
{
  while (size > 0)
  {
    const size_t chunk = std::min(size, IoChunk);
    if (std::fwrite(data, 1, chunk, f) != chunk)
      return false;
    data += chunk;
    size -= chunk;
  }
  return true;
}

// Reads exactly `size` bytes from a descriptor, IoChunk at a time; false on a short read or an
// error (errno says which, 0 for a short read).
bool readAll(int fd, uint8_t* data, size_t size)
{
  while (size > 0)
  {
    const ssize_t got = ::read(fd, data, std::min(size, IoChunk));
    if (got < 0 && errno == EINTR)
      continue;
    if (got <= 0)
    {
      if (got == 0)
        errno = 0;
      return false;
    }
    data += got;
    size -= size_t(got);
  }
  return true;
}

// ---- reading ----

// One per thread, kept between loads: making one costs a small file's load a twentieth of its
// time. inflate() starts each frame afresh.
using DecompressionContext = ZSTD_DCtx*;
DecompressionContext decompressionContext()
{
  thread_local const std::unique_ptr<ZSTD_DCtx, size_t (*)(ZSTD_DCtx*)> ctx(
    ZSTD_createDCtx(), ZSTD_freeDCtx);
  if (!ctx)
    throw FileError("cannot create a zstd decompression context");
  return ctx.get();
}

// Decompresses one zstd frame that must yield exactly `raw` bytes into `out`, as the raw
// little-endian bytes of its elements (raw is a multiple of their size), followed by `padding`
// zero elements. The output grows with what the frame actually produces, so a false raw size
// cannot make us reserve memory up front; decompressing into the elements themselves costs a
// section its size once, not twice.
template <typename T>
void inflate(DecompressionContext ctx, const uint8_t* src, size_t stored, uint64_t raw,
  const std::string& part, std::vector<T>& out, size_t padding)
{
  const unsigned long long declared = ZSTD_getFrameContentSize(src, stored);
  if (declared == ZSTD_CONTENTSIZE_ERROR)
    fail(part + " is not a valid zstd frame");
  if (declared == ZSTD_CONTENTSIZE_UNKNOWN || declared != raw)
    fail(part + ": the zstd frame's size does not match the declared raw size");

  const uint64_t rawElements = raw / sizeof(T);
  // Reserving the padding with each step makes the last step's allocation the final one.
  auto grow = [&](uint64_t elements) {
    out.reserve(size_t(elements) + padding);
    out.resize(size_t(elements));
  };
  grow(std::min<uint64_t>(
    rawElements, std::max<uint64_t>(4 * uint64_t(stored), 1 << 16) / sizeof(T)));
  if (out.size() == rawElements)
  {
    // All of it fits the first step: one call (a streaming pass costs a small section's frame
    // about a third more), which fails where the frame would yield more.
    const size_t frame = ZSTD_findFrameCompressedSize(src, stored);
    if (!ZSTD_isError(frame) && frame != stored)
      fail(part + ": data after the end of the zstd frame");
    const size_t produced = ZSTD_decompressDCtx(ctx, out.data(), size_t(raw), src, stored);
    if (ZSTD_isError(produced))
      fail(part + ": corrupt zstd data (" + ZSTD_getErrorName(produced) + ")");
    if (produced != raw)
      fail(part + " decompresses to fewer bytes than declared");
    out.resize(out.size() + padding); // inside the capacity reserved
    return;
  }
  ZSTD_DCtx_reset(ctx, ZSTD_reset_session_only); // one call above starts afresh by itself
  size_t produced = 0; // bytes
  uint8_t scratch = 0; // catches a frame that goes on past the declared size
  ZSTD_inBuffer in = { src, stored, 0 };
  for (;;)
  {
    if (produced == out.size() * sizeof(T) && out.size() < rawElements)
      grow(std::min<uint64_t>(rawElements, 2 * uint64_t(out.size())));
    const size_t capacity = out.size() * sizeof(T);
    const bool full = produced == capacity;
    ZSTD_outBuffer o = full
      ? ZSTD_outBuffer{ &scratch, 1, 0 }
      : ZSTD_outBuffer{ reinterpret_cast<uint8_t*>(out.data()), capacity, produced };
    const size_t inBefore = in.pos, outBefore = o.pos;
    const size_t r = ZSTD_decompressStream(ctx, &o, &in);
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
  out.resize(out.size() + padding); // inside the capacity reserved with the last step
}

// The elements of a known section (raw little-endian values of type T) in host order, followed
// by `padding` zero elements: decompressed in place, or decoded straight from the file's bytes;
// checked against the section's crc32 either way.
template <typename T>
std::vector<T> sectionElements(
  const SectionEntry& e, const uint8_t* stored, const std::string& name, size_t padding)
{
  const size_t count = size_t(e.raw / sizeof(T));
  std::vector<T> out;
  const uint8_t* raw = stored;
  if (e.codec == CodecZstd)
  {
    inflate(decompressionContext(), stored, size_t(e.stored), e.raw, name, out, padding);
    raw = reinterpret_cast<const uint8_t*>(out.data());
  }
  if (crc32Of(raw, size_t(e.raw)) != e.crc)
    fail(name + " checksum mismatch (the data is corrupt)");
  if (e.codec != CodecZstd)
    out.assign(count + padding, T(0));
  // In place for a decompressed section (each element is read whole before it is written).
  for (size_t i = 0; i < count; ++i)
    out[i] = T(bits::loadLE(raw + sizeof(T) * i, int(sizeof(T))));
  return out;
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
// A format 3 file's volume, rebuilt from its coded section; `header` holds what the file's header
// says (geometry, type, background, widths and counts), which the rebuilt volume must match.
Volume readCoded(const SectionEntry& e, const uint8_t* data, uint64_t labelCount,
  uint64_t leafCount, const Volume& header, const ParallelFor& parallel)
{
  const uint8_t* stored = data + e.offset;
  if (crc32Of(stored, size_t(e.stored)) != e.crc)
    fail("coded volume section checksum mismatch (the data is corrupt)");
  coded::Frame frame;
  frame.geometry = header.geometry;
  frame.scalarType = header.scalarType;
  frame.background = header.background;
  frame.labelCount = labelCount;
  frame.blockCount = header.blockCount;
  Volume v;
  try
  {
    v = coded::decode(stored, size_t(e.stored), frame, parallel);
  }
  catch (const std::bad_alloc&)
  {
    throw;
  }
  catch (const std::exception& error) // a corrupt stream, or pools beyond the layout's widths
  {
    fail(std::string("coded volume section: ") + error.what());
  }
  if (!(v.widths == header.widths) || v.rootCount != header.rootCount ||
    v.midCount != header.midCount || v.leaves.size() != leafCount)
    fail("the header's field widths or node counts do not match the coded volume");
  return v;
}

// A format 4 file's volume from its DAG streams section; `header` holds what the file's header
// says (geometry, type, background, widths and counts).
Volume readDagStreams(const SectionEntry& e, const uint8_t* data, uint64_t labelCount,
  uint64_t leafCount, const Volume& header, const ParallelFor& given)
{
  const bool split = e.stored >= SplitLoadBytes;
  const ParallelFor parallel = split ? given : ParallelFor(sequentialFor);
  const uint8_t* stored = data + e.offset;
  if (crc32Of(stored, size_t(e.stored)) != e.crc)
    fail("DAG streams section checksum mismatch (the data is corrupt)");
  dagstreams::Shape shape;
  shape.frame = header; // its labels, blocks and pools are not read yet
  shape.labelCount = labelCount;
  shape.leafCount = leafCount;
  const uint8_t* at = stored;
  const uint8_t* const end = stored + e.stored;
  uint64_t storedSizes[dagstreams::StreamCount], rawSizes[dagstreams::StreamCount];
  uint64_t total = 0;
  for (uint32_t i = 0; i < dagstreams::StreamCount; ++i)
  {
    const std::string name = std::string(dagstreams::streamName(i)) + " stream";
    if (!bits::getVarint(at, end, storedSizes[i]) || !bits::getVarint(at, end, rawSizes[i]))
      fail("DAG streams section: its table of stream sizes is truncated or corrupt");
    if (rawSizes[i] > dagstreams::maxStreamBytes(i, shape))
      fail(name + ": larger than its volume's counts allow");
    if (storedSizes[i] > e.stored || (storedSizes[i] != rawSizes[i] &&
          (storedSizes[i] == 0 || rawSizes[i] / ZstdMaxExpansion > storedSizes[i])))
      fail(name + ": declared raw size impossible for its compressed size");
    total += storedSizes[i];
    if (total > uint64_t(end - at))
      fail(name + " lies outside its section (the file may be truncated)");
  }
  if (total != uint64_t(end - at))
    fail("DAG streams section: bytes after its last stream");
  // The streams side by side (each frame's tables cost a small stream as much as its bytes);
  // the error is the first stream's, as in order.
  const uint8_t* starts[dagstreams::StreamCount];
  for (uint32_t i = 0; i < dagstreams::StreamCount; ++i)
  {
    starts[i] = at;
    at += storedSizes[i];
  }
  dagstreams::Streams streams;
  parallelTasks(parallel, dagstreams::StreamCount, [&](uint64_t i) {
    if (storedSizes[i] == rawSizes[i])
      streams[i].assign(starts[i], starts[i] + storedSizes[i]);
    else
      inflate(decompressionContext(), starts[i], size_t(storedSizes[i]), rawSizes[i],
        std::string(dagstreams::streamName(uint32_t(i))) + " stream", streams[i], 0);
  });
  try
  {
    PooledGraph graph; // what validation reads, compaction needs: the streams are read once
    Volume v = dagstreams::decode(streams, shape, &graph);
    if (!split || v.memory().total() > CompactAlongsideBytes)
    {
      v.deriveBoundsAndValidate(parallel, &graph);
      return compacted(std::move(v), std::move(graph));
    }
    // Compacted beside the last checks, from copies (the checks read the pooled form and the
    // graph): the labels' counts and bounds come from the checks.
    Volume compact;
    v.deriveBoundsAndValidate(parallel, &graph, [&] { compact = compacted(v, graph); });
    compact.labels = std::move(v.labels);
    return compact;
  }
  catch (const std::bad_alloc&)
  {
    throw;
  }
  catch (const std::exception& error)
  {
    fail(std::string("DAG streams section: ") + error.what());
  }
}
} // namespace

namespace
{
// What a file stores: the pooled form of the volume (Compact.h: pooledView), a malformed compact
// volume refused as a FileError.
const Volume& pooledForWriting(const Volume& volume, Volume& holder)
{
  try
  {
    return pooledView(volume, holder);
  }
  catch (const std::bad_alloc&)
  {
    throw;
  }
  catch (const std::exception& e)
  {
    throw FileError(std::string("cannot write an inconsistent volume: ") + e.what());
  }
}
} // namespace

std::vector<uint8_t> serialize(const Volume& volume, const WriteOptions& options, const ParallelFor& parallel)
{
  Volume holder;
  const Volume& v = pooledForWriting(volume, holder);
  EncodedFile file = encode(v, options, parallel);
  std::vector<uint8_t> bytes = std::move(file.header);
  size_t total = bytes.size();
  for (const StoredSection& s : file.sections)
    total += size_t(s.entry.stored);
  bytes.reserve(total);
  for (StoredSection& s : file.sections)
  {
    storedChunks(v, s,
      [&](const uint8_t* data, size_t size) { bytes.insert(bytes.end(), data, data + size); });
    s.packed.reset(); // each frame goes as soon as it is copied
  }
  return bytes;
}

namespace
{
// The validated volume a file holds: compact from a 4.0 file, pooled from older ones.
Volume deserializeValidated(const uint8_t* data, size_t size, const ParallelFor& parallel)
{
  if (size < FileMagicSize || std::memcmp(data, FileMagic, FileMagicSize) != 0)
    throw FileError("not an .svdag file (the file does not start with the .svdag signature)");
  ByteReader h(data, size, "header");
  h.skip(FileMagicSize);
  const uint16_t major = h.u16(), minor = h.u16();
  if (major < 1 || major > FileMajorVersion)
    throw FileError("unsupported .svdag format version " + std::to_string(major) + "." +
      std::to_string(minor) + " (this reader reads versions 1.x to " +
      std::to_string(FileMajorVersion) + ".x)");

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
  if (v.blockCount > g.voxelCount())
    fail("header: more blocks than voxels");

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
    const bool isKnown = e.id >= FirstSection && e.id <= LastSection && requiredSection(major, e.id);
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
    if (!requiredSection(major, id))
      continue;
    if (!known[id])
      fail(std::string(sectionName(id)) + " section missing");
    const uint64_t raw = known[id]->raw;
    if (id == CodedSection || id == DagStreamsSection)
    {
      if (known[id]->codec != CodecNone)
        fail(std::string(sectionName(id)) + " section: compressed, but it is coded already");
      continue;
    }
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

  if (major >= 4)
    return readDagStreams(*known[DagStreamsSection], data, labelCount, leafCount, v, parallel);
  if (major >= 3)
    return readCoded(*known[CodedSection], data, labelCount, leafCount, v, parallel);

  // Sections, one pass: decompress, checksum, decode (the padding words re-added). The sizes
  // were checked against the counts above, so each is a whole number of its elements.
  for (uint32_t id = LabelsSection; id <= LeavesSection; ++id)
  {
    const SectionEntry& e = *known[id];
    const std::string name = std::string(sectionName(id)) + " section";
    const uint8_t* stored = data + e.offset;
    switch (id)
    {
      case LabelsSection:
        readLabels(sectionElements<uint8_t>(e, stored, name, 0), labelCount, v);
        break;
      case BlocksSection: v.blocks = sectionElements<uint32_t>(e, stored, name, 1); break;
      case RootsSection: v.roots = sectionElements<uint32_t>(e, stored, name, 1); break;
      case MidsSection: v.mids = sectionElements<uint32_t>(e, stored, name, 1); break;
      default: v.leaves = sectionElements<uint64_t>(e, stored, name, 0);
    }
  }

  try
  {
    if (major == 1)
      file::upgradeVersion1(v);
    v.validate(parallel); // every reference, offset and bound of the structure
  }
  catch (const std::exception& e)
  {
    fail(e.what());
  }
  return v;
}
} // namespace

Volume deserialize(const uint8_t* data, size_t size, const ParallelFor& parallel)
{
  // In the compact form a volume in memory holds.
  return compacted(deserializeValidated(data, size, parallel));
}

void writeFile(const Volume& compactOrPooled, const std::string& path, const WriteOptions& options,
  const ParallelFor& parallel)
{
  Volume holder;
  const Volume& volume = pooledForWriting(compactOrPooled, holder);
  const EncodedFile file = encode(volume, options, parallel);
  // A temporary name next to the target: a failed write leaves the old file (if any) intact.
  const std::string temporary = path + ".partial";
  std::FILE* f = std::fopen(temporary.c_str(), "wb");
  if (!f)
    throw FileOpenError("cannot create '" + path + "': " + std::strerror(errno));
  bool written = writeAll(f, file.header.data(), file.header.size());
  for (const StoredSection& s : file.sections)
  {
    storedChunks(volume, s, [&](const uint8_t* data, size_t size) {
      written = written && writeAll(f, data, size); // nothing more once a write failed
    });
  }
  const int writeErrno = errno;
  const bool flushed = std::fflush(f) == 0;
  const bool closed = std::fclose(f) == 0;
  if (!written || !flushed || !closed)
  {
    std::remove(temporary.c_str());
    throw FileWriteError(
      "cannot write '" + path + "': " + std::strerror(!written ? writeErrno : errno));
  }
  if (std::rename(temporary.c_str(), path.c_str()) != 0)
  {
    const int renameErrno = errno;
    std::remove(temporary.c_str());
    throw FileOpenError("cannot create '" + path + "': " + std::strerror(renameErrno));
  }
}

namespace
{
// The whole file. A descriptor and no stdio buffer: a small file's load is a few system calls.
// Non-blocking, so that a FIFO is refused below rather than waited on by open(); a regular file
// reads the same either way.
std::vector<uint8_t> fileBytes(const std::string& path)
{
  const int fd = ::open(path.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC);
  if (fd < 0)
    throw FileError("cannot open '" + path + "': " + std::strerror(errno));
  const std::unique_ptr<const int, void (*)(const int*)> closer(
    &fd, [](const int* f) { ::close(*f); });
  // The size the file has once opened, then one read; a file that changes meanwhile shows up as
  // a short read or is caught by the checksums.
  struct stat info;
  if (::fstat(fd, &info) != 0)
    throw FileError("cannot read '" + path + "': " + std::strerror(errno));
  if (!S_ISREG(info.st_mode))
    throw FileError("cannot read '" + path + "': not a regular file");
  if (info.st_size < 0 || uint64_t(info.st_size) > uint64_t(SIZE_MAX))
    throw FileError("cannot read '" + path + "': larger than this system can address");
  std::vector<uint8_t> bytes(static_cast<size_t>(info.st_size));
  if (!readAll(fd, bytes.data(), bytes.size()))
    throw FileError("cannot read '" + path + "': " + (errno ? std::strerror(errno) : "short read"));
  return bytes;
}
} // namespace

Volume readFile(const std::string& path, const ParallelFor& parallel)
{
  const std::vector<uint8_t> bytes = fileBytes(path);
  try
  {
    return deserialize(bytes.data(), bytes.size(), parallel);
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
