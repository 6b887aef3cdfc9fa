// The .svdag file format: exact round trips, and hostile input (every truncation, thousands of
// random corruptions, absurd header values) that must give FileError, never a crash, an
// out-of-bounds read or a huge allocation.
#include "Bits.h"
#include "CodedVolume.h"
#include "DagStreams.h"
#include "PooledGraph.h"
#include "RangeCoder.h"
#include "svdag/Builder.h"
#include "svdag/Decoder.h"
#include "svdag/Compact.h"
#include "svdag/File.h"
#include "svdag/LeafSymmetry.h"

#include <gtest/gtest.h>
#include <zlib.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <functional>
#include <iterator>
#include <new>
#include <random>
#include <sys/stat.h>
#include <thread>
#include <unistd.h>

// The largest single allocation since the last reset, for the tests proving that absurd header
// values do not make the reader reserve memory. Replacing the global operator new covers the
// core library's vectors too (the program's definition is the one every library uses).
namespace
{
std::atomic<size_t> largestAllocation{ 0 };
void* allocate(size_t n)
{
  size_t seen = largestAllocation.load(std::memory_order_relaxed);
  while (n > seen && !largestAllocation.compare_exchange_weak(seen, n))
  {
  }
  if (void* p = std::malloc(n ? n : 1))
    return p;
  throw std::bad_alloc();
}
} // namespace
void* operator new(size_t n)
{
  return allocate(n);
}
void* operator new[](size_t n)
{
  return allocate(n);
}
void operator delete(void* p) noexcept
{
  std::free(p);
}
void operator delete[](void* p) noexcept
{
  std::free(p);
}
void operator delete(void* p, size_t) noexcept
{
  std::free(p);
}
void operator delete[](void* p, size_t) noexcept
{
  std::free(p);
}

namespace
{
using svdag::FileError;
using svdag::ScalarType;
using Bytes = std::vector<uint8_t>;

// Offsets of header fields (File.h documents the layout).
constexpr size_t DimsAt = 12, TypeAt = 144, WidthsAt = 156, CountsAt = 176, SectionCountAt = 216,
                 TableAt = 220, EntrySize = 36;
enum Count
{
  Labels = 0,
  Blocks,
  Roots,
  Mids,
  Leaves
};
enum Section
{
  LabelsSection = 1,
  BlocksSection,
  RootsSection,
  MidsSection,
  LeavesSection
};
enum EntryField
{
  Id = 0,
  Codec = 4,
  Offset = 8,
  Stored = 16,
  Raw = 24,
  Crc = 32
};

uint64_t getLE(const Bytes& b, size_t at, int n)
{
  uint64_t v = 0;
  for (int i = 0; i < n; ++i)
    v |= uint64_t(b.at(at + size_t(i))) << (8 * i);
  return v;
}
void putLE(Bytes& b, size_t at, uint64_t v, int n)
{
  for (int i = 0; i < n; ++i)
    b.at(at + size_t(i)) = uint8_t(v >> (8 * i));
}
size_t sectionCount(const Bytes& b)
{
  return size_t(getLE(b, SectionCountAt, 4));
}
size_t headerCrcAt(const Bytes& b)
{
  return TableAt + EntrySize * sectionCount(b);
}
// Re-seals the header after a test edits it, so the edit reaches the checks behind the checksum.
void resealHeader(Bytes& b)
{
  const size_t at = headerCrcAt(b);
  putLE(b, at, crc32(0, b.data(), uInt(at)), 4);
}
// One edit of a file's bytes: `bytes` little-endian bytes at `at` set to `value`.
struct HeaderEdit
{
  const char* name;
  size_t at;
  uint64_t value;
  int bytes;
};
// Each edit of a good file, behind a resealed header checksum (but for the section count, whose
// edit moves where the checksum is), fails to load, and none makes the reader allocate more
// than 16 MiB.
void expectHeaderEditsFail(const Bytes& good, const std::vector<HeaderEdit>& edits)
{
  for (const HeaderEdit& e : edits)
  {
    SCOPED_TRACE(e.name);
    Bytes bad = good;
    putLE(bad, e.at, e.value, e.bytes);
    if (e.at != SectionCountAt)
      resealHeader(bad);
    largestAllocation = 0;
    EXPECT_THROW(svdag::deserialize(bad), FileError);
    EXPECT_LT(largestAllocation.load(), size_t(16) << 20);
  }
}

size_t entryOf(const Bytes& b, uint32_t id)
{
  for (size_t i = 0; i < sectionCount(b); ++i)
  {
    if (getLE(b, TableAt + EntrySize * i, 4) == id)
      return TableAt + EntrySize * i;
  }
  ADD_FAILURE() << "section " << id << " not in the table";
  return 0;
}

svdag::Geometry geometry(int x, int y, int z)
{
  svdag::Geometry g;
  g.dims = { { x, y, z } };
  g.spacing = { { 0.5, 1.25, 3.0 } };
  g.origin = { { -10.5, 7.0, 1e6 } };
  g.direction = { { 0, 1, 0, -1, 0, 0, 0, 0, 1 } };
  return g;
}

template <typename F>
svdag::Volume build(ScalarType t, const svdag::Geometry& g, F valueAt, uint64_t background = 0)
{
  std::vector<uint8_t> data(size_t(g.voxelCount()) * size_t(svdag::scalarSize(t)));
  size_t i = 0;
  for (int z = 0; z < g.dims[2]; ++z)
    for (int y = 0; y < g.dims[1]; ++y)
      for (int x = 0; x < g.dims[0]; ++x)
        svdag::scalarStore(t, data.data(), i++, valueAt(x, y, z));
  svdag::BuildOptions options;
  options.background = background;
  return svdag::Builder::build(g, t, data.data(), options);
}

// Nested spheres with labels at the type's extremes, plus noise: every part of the format used.
svdag::Volume spheres(ScalarType t, int size = 37)
{
  std::mt19937 rng(11);
  return build(t, geometry(size, size - 5, size - 11), [&](int x, int y, int z) -> uint64_t {
    const int d2 = (x - 15) * (x - 15) + (y - 13) * (y - 13) + (z - 9) * (z - 9);
    if (rng() % 23 == 0)
      return 1 + rng() % 5;
    return d2 < 40 ? svdag::scalarMax(t) : d2 < 120 ? svdag::scalarMin(t) : d2 < 200 ? 7 : 0;
  });
}

struct Named
{
  std::string name;
  svdag::Volume volume;
};

std::vector<Named> volumes()
{
  std::vector<Named> out;
  for (int t = 0; t < svdag::ScalarTypeCount; ++t)
  {
    const ScalarType type = ScalarType(t);
    out.push_back({ std::string("spheres ") + svdag::scalarName(type), spheres(type) });
  }
  out.push_back({ "1x1x1 label", build(ScalarType::UInt8, geometry(1, 1, 1), [](int, int, int) {
                   return uint64_t(200);
                 }) });
  out.push_back({ "1x1x1 background", build(ScalarType::Int16, geometry(1, 1, 1), [](int, int, int) {
                   return uint64_t(0);
                 }) });
  out.push_back({ "all background 33x17x20",
    build(ScalarType::UInt32, geometry(33, 17, 20), [](int, int, int) { return uint64_t(0); }) });
  out.push_back({ "full, background -1", build(ScalarType::Int64, geometry(20, 20, 20),
                                           [](int, int, int) { return uint64_t(3); },
                                           ~uint64_t(0)) });
  std::mt19937 rng(3);
  out.push_back({ "random 300 labels 40x24x33",
    build(ScalarType::UInt16, geometry(40, 24, 33), [&](int, int, int) { return uint64_t(rng() % 300); }) });
  return out;
}

TEST(File, RoundTripIsExactAndDeterministic)
{
  for (const Named& n : volumes())
  {
    SCOPED_TRACE(n.name);
    ASSERT_NO_THROW(n.volume.validate());
    for (int level : { 0, 1, 3, 19 })
    {
      SCOPED_TRACE("zstd level " + std::to_string(level));
      const Bytes bytes = svdag::serialize(n.volume, { level, 2 });
      const svdag::Volume back = svdag::deserialize(bytes);
      EXPECT_TRUE(back == n.volume);
      EXPECT_EQ(svdag::serialize(back, { level, 2 }), bytes); // same volume, same bytes
    }
  }
}

TEST(File, CompressionShrinksAndUncompressedIsExactlyTheData)
{
  const svdag::Volume v = svdag::pooled(spheres(ScalarType::UInt32, 70)); // what the file holds
  const Bytes plain = svdag::serialize(v, { 0, 2 });
  const Bytes packed = svdag::serialize(v, { 3, 2 });
  EXPECT_LT(packed.size(), plain.size());
  const svdag::MemoryUsage m = v.memory();
  // Uncompressed: header + table + crc, then the data words (no padding words) and labels at
  // 40 bytes each.
  const uint64_t data = ((v.blockCount * v.widths.blockBits() + 31) / 32) * 4 + m.roots + m.mids +
    m.leaves + v.labels.size() * 40;
  EXPECT_EQ(plain.size(), TableAt + EntrySize * 5 + 4 + data);
  for (uint32_t id = LabelsSection; id <= LeavesSection; ++id)
    EXPECT_EQ(getLE(plain, entryOf(plain, id) + Codec, 4), 0u);
}

TEST(File, WritesAndReadsFiles)
{
  const std::string dir = ::testing::TempDir();
  const std::string path = dir + "/svdag_file_test_" + std::to_string(::getpid()) + ".svdag";
  const svdag::Volume v = spheres(ScalarType::Int32);
  svdag::writeFile(v, path);
  EXPECT_TRUE(svdag::isSVDAGFile(path));
  EXPECT_TRUE(svdag::readFile(path) == v);
  std::FILE* partial = std::fopen((path + ".partial").c_str(), "rb");
  EXPECT_EQ(partial, nullptr) << "temporary file left behind";
  if (partial)
    std::fclose(partial);

  // Overwriting keeps working; a text file and a missing file are not .svdag files.
  svdag::writeFile(v, path, { 0, 2 });
  EXPECT_TRUE(svdag::readFile(path) == v);
  const std::string text = dir + "/svdag_file_test_text_" + std::to_string(::getpid()) + ".txt";
  std::ofstream(text) << "SVDAG but not really\n";
  EXPECT_FALSE(svdag::isSVDAGFile(text));
  EXPECT_THROW(svdag::readFile(text), FileError);
  EXPECT_FALSE(svdag::isSVDAGFile(dir + "/does-not-exist.svdag"));
  EXPECT_THROW(svdag::readFile(dir + "/does-not-exist.svdag"), FileError);
  // A directory and a FIFO are refused; the FIFO is not waited on (nothing writes to it).
  const std::string fifo = dir + "/svdag_file_test_fifo_" + std::to_string(::getpid());
  std::remove(fifo.c_str()); // left by a run that stopped here
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  for (const std::string& notAFile : { dir, fifo })
  {
    try
    {
      svdag::readFile(notAFile);
      ADD_FAILURE() << notAFile << " was read";
    }
    catch (const FileError& e)
    {
      EXPECT_NE(std::string(e.what()).find("not a regular file"), std::string::npos) << e.what();
    }
  }
  std::remove(fifo.c_str());
  EXPECT_THROW(svdag::writeFile(v, dir + "/no-such-dir/x.svdag"), svdag::FileOpenError);
  EXPECT_THROW(svdag::writeFile(v, path, { 23, 2 }), FileError);
  EXPECT_THROW(svdag::writeFile(v, path, { -1, 2 }), FileError);
  std::remove(path.c_str());
  std::remove(text.c_str());
}

TEST(File, RefusesToWriteAnInconsistentVolume)
{
  svdag::Volume v = spheres(ScalarType::UInt8);
  v.leaves.pop_back(); // a mid node now refers past the leaves
  EXPECT_THROW(svdag::serialize(v), FileError);
}

TEST(File, EveryTruncationFails)
{
  const svdag::Volume v = spheres(ScalarType::UInt16, 20);
  for (int level : { 0, 3 })
  {
    const Bytes bytes = svdag::serialize(v, { level, 2 });
    for (size_t n = 0; n < bytes.size(); ++n)
    {
      EXPECT_THROW(svdag::deserialize(bytes.data(), n), FileError) << "prefix of " << n << " bytes";
    }
    Bytes longer = bytes; // trailing bytes after the last section are not the file's
    longer.push_back(0);
    EXPECT_NO_THROW(svdag::deserialize(longer));
  }
}

// Corrupt files either fail with FileError or (a change the format does not depend on) still
// give a volume that validates and decodes.
void expectFailsOrValid(const Bytes& bytes, size_t& failed, size_t& loaded)
{
  try
  {
    const svdag::Volume v = svdag::deserialize(bytes);
    v.validate();
    std::vector<uint8_t> out(size_t(v.geometry.voxelCount()) * size_t(svdag::scalarSize(v.scalarType)));
    svdag::decode(v, out.data());
    ++loaded;
  }
  catch (const FileError&)
  {
    ++failed;
  }
}

TEST(File, RandomCorruptionFailsCleanly)
{
  const svdag::Volume v = spheres(ScalarType::UInt64, 24);
  std::mt19937_64 rng(2024);
  for (int level : { 0, 3 })
  {
    const Bytes bytes = svdag::serialize(v, { level, 2 });
    size_t failed = 0, loaded = 0;
    for (int i = 0; i < 3000; ++i)
    {
      Bytes bad = bytes;
      const size_t at = rng() % bad.size();
      if (i % 2 == 0)
        bad[at] ^= uint8_t(1u << (rng() % 8)); // bit flip
      else
        bad[at] = uint8_t(bad[at] + 1 + rng() % 255); // byte changed to another value
      expectFailsOrValid(bad, failed, loaded);
    }
    // Every byte is covered by a checksum, so a change that loads can only sit where the zstd
    // decoder ignores it; that must be rare.
    EXPECT_EQ(failed + loaded, 3000u);
    EXPECT_GT(failed, 2900u) << "level " << level;
    if (level == 0)
      EXPECT_EQ(loaded, 0u);
  }
}

// Header corruption that a checksum cannot catch because the header was re-sealed (a buggy or
// hostile writer): the checks behind the checksum must still reject every change to the field
// widths, the counts and the section table, since each one disagrees with the data.
TEST(File, ResealedCorruptionOfWidthsCountsAndTableFails)
{
  const svdag::Volume v = spheres(ScalarType::Int8, 24);
  const Bytes bytes = svdag::serialize(v, { 3, 2 });
  std::mt19937_64 rng(99);
  size_t failed = 0, loaded = 0;
  for (int i = 0; i < 3000; ++i)
  {
    Bytes bad = bytes;
    size_t at = WidthsAt + rng() % (headerCrcAt(bad) - WidthsAt);
    if (at >= SectionCountAt && at < TableAt)
      at += TableAt - SectionCountAt; // a new section count would move the checksum itself
    bad[at] ^= uint8_t(1u << (rng() % 8));
    resealHeader(bad);
    const size_t loadedBefore = loaded;
    expectFailsOrValid(bad, failed, loaded);
    EXPECT_EQ(loaded, loadedBefore) << "change at byte " << at << " went unnoticed";
  }
  EXPECT_EQ(failed, 3000u);
}

TEST(File, RejectsWrongMagicAndUnknownMajorVersion)
{
  const Bytes good = svdag::serialize(spheres(ScalarType::UInt8, 20));
  Bytes bad = good;
  bad[0] = 'S';
  EXPECT_THROW(svdag::deserialize(bad), FileError);
  bad = good;
  bad[6] = '\n'; // CR LF conversion
  EXPECT_THROW(svdag::deserialize(bad), FileError);
  bad = good;
  putLE(bad, 8, 5, 2);
  try
  {
    svdag::deserialize(bad);
    ADD_FAILURE() << "version 5 accepted";
  }
  catch (const FileError& e)
  {
    EXPECT_NE(std::string(e.what()).find("version 5.0"), std::string::npos) << e.what();
  }
  bad = good;
  putLE(bad, 10, 7, 2); // a newer minor version is readable (checksum re-sealed)
  resealHeader(bad);
  EXPECT_NO_THROW(svdag::deserialize(bad));
}

// A 1.x reader skips sections it does not know (a later minor version may add some), but still
// checks where they lie.
TEST(File, UnknownSectionsAreSkippedButChecked)
{
  const svdag::Volume v = spheres(ScalarType::UInt16, 20);
  const Bytes good = svdag::serialize(v, { 3, 2 });
  const size_t oldEnd = headerCrcAt(good) + 4;
  const Bytes extra = { 'n', 'e', 'w' };
  auto withExtraSection = [&](uint64_t extraOffset) {
    Bytes b(good.begin(), good.begin() + SectionCountAt);
    b.resize(oldEnd + EntrySize);
    putLE(b, SectionCountAt, 6, 4);
    for (size_t i = 0; i < 5; ++i) // the known entries, their data moved by one entry
    {
      std::copy(good.begin() + TableAt + EntrySize * i, good.begin() + TableAt + EntrySize * (i + 1),
        b.begin() + TableAt + EntrySize * i);
      const size_t at = TableAt + EntrySize * i + Offset;
      putLE(b, at, getLE(b, at, 8) + EntrySize, 8);
    }
    const size_t e = TableAt + EntrySize * 5;
    putLE(b, e + Id, 100, 4);
    putLE(b, e + Codec, 0, 4);
    putLE(b, e + Offset, extraOffset, 8);
    putLE(b, e + Stored, extra.size(), 8);
    putLE(b, e + Raw, extra.size(), 8);
    putLE(b, e + Crc, crc32(0, extra.data(), uInt(extra.size())), 4);
    resealHeader(b);
    b.insert(b.end(), good.begin() + long(oldEnd), good.end());
    b.insert(b.end(), extra.begin(), extra.end());
    return b;
  };
  const Bytes newer = withExtraSection(good.size() + EntrySize);
  EXPECT_TRUE(svdag::deserialize(newer) == v);
  EXPECT_THROW(svdag::deserialize(withExtraSection(newer.size() - 1)), FileError); // past the end
  EXPECT_THROW(svdag::deserialize(withExtraSection(oldEnd + EntrySize)), FileError); // overlaps
}

// Absurd values behind a valid header checksum: each one fails, and none makes the reader
// allocate more than a few megabytes.
TEST(File, AbsurdHeaderValuesFailWithoutHugeAllocations)
{
  const Bytes good = svdag::serialize(spheres(ScalarType::UInt32, 30), { 3, 2 });
  const size_t leaves = entryOf(good, LeavesSection), labels = entryOf(good, LabelsSection);
  const size_t blocks = entryOf(good, BlocksSection);
  largestAllocation = 0; // the tracker sees the library's allocations
  svdag::deserialize(good);
  ASSERT_GT(largestAllocation.load(), size_t(1000));
  const std::vector<HeaderEdit> edits = {
    { "dims x 2^31-1", DimsAt, 0x7FFFFFFF, 4 },
    { "dims y 2^31-1", DimsAt + 4, 0x7FFFFFFF, 4 },
    { "dims z 2^31-1", DimsAt + 8, 0x7FFFFFFF, 4 },
    { "dims 0", DimsAt, 0, 4 },
    { "dims negative", DimsAt + 4, uint64_t(-5), 4 },
    { "scalar type 8", TypeAt, 8, 4 },
    { "width 33", WidthsAt + 8, 33, 4 },
    { "width 2^32-1", WidthsAt + 16, 0xFFFFFFFF, 4 },
    { "label count 2^60", CountsAt + 8 * Labels, uint64_t(1) << 60, 8 },
    { "block count 2^63", CountsAt + 8 * Blocks, uint64_t(1) << 63, 8 },
    { "root count 2^40", CountsAt + 8 * Roots, uint64_t(1) << 40, 8 },
    { "mid count max", CountsAt + 8 * Mids, ~uint64_t(0), 8 },
    { "leaf count 2^61", CountsAt + 8 * Leaves, uint64_t(1) << 61, 8 },
    { "section count 2^32-1", SectionCountAt, 0xFFFFFFFF, 4 },
    { "leaves raw size 2^40", leaves + Raw, uint64_t(1) << 40, 8 },
    { "leaves raw size 1 GiB", leaves + Raw, uint64_t(1) << 30, 8 },
    { "labels stored size huge", labels + Stored, uint64_t(1) << 62, 8 },
    { "labels offset past the end", labels + Offset, uint64_t(1) << 40, 8 },
    { "labels offset into the header", labels + Offset, 16, 8 },
    { "blocks overlap the labels", blocks + Offset, getLE(good, labels + Offset, 8), 8 },
    { "unknown codec", blocks + Codec, 9, 4 },
    { "duplicate section id", blocks + Id, LabelsSection, 4 },
    { "missing section", leaves + Id, 77, 4 },
    { "section crc", leaves + Crc, 12345, 4 },
  };
  expectHeaderEditsFail(good, edits);
  // Counts and sizes that agree with each other but not with the data: a leaf count of 2^27
  // (1 GiB of leaves) with the raw size to match must fail on the zstd frame, not allocate 1 GiB.
  Bytes bad = good;
  putLE(bad, CountsAt + 8 * Leaves, uint64_t(1) << 27, 8);
  putLE(bad, leaves + Raw, uint64_t(1) << 30, 8);
  resealHeader(bad);
  largestAllocation = 0;
  EXPECT_THROW(svdag::deserialize(bad), FileError);
  EXPECT_LT(largestAllocation.load(), size_t(16) << 20);
}

// Each failure says what is wrong, so a user can tell a damaged file from a wrong one.
TEST(File, ErrorMessagesNameTheProblem)
{
  const Bytes good = svdag::serialize(spheres(ScalarType::UInt32, 20), { 0, 2 });
  auto message = [](const Bytes& b) -> std::string {
    try
    {
      svdag::deserialize(b);
    }
    catch (const FileError& e)
    {
      return e.what();
    }
    return "no error";
  };
  Bytes bad = good;
  bad[headerCrcAt(bad) - 1] ^= 1;
  EXPECT_NE(message(bad).find("header checksum"), std::string::npos) << message(bad);
  bad = good;
  bad.back() ^= 1;
  EXPECT_NE(message(bad).find("checksum mismatch"), std::string::npos) << message(bad);
  bad = good;
  putLE(bad, DimsAt, 0x7FFFFFFF, 4);
  putLE(bad, DimsAt + 4, 0x7FFFFFFF, 4);
  putLE(bad, DimsAt + 8, 0x7FFFFFFF, 4);
  resealHeader(bad);
  EXPECT_NE(message(bad).find("too large"), std::string::npos) << message(bad);
  bad = good;
  bad.resize(bad.size() - 3);
  EXPECT_NE(message(bad).find("outside the file"), std::string::npos) << message(bad);
}

} // namespace

// ---- content checks: files whose checksums are valid but whose content is impossible ----
namespace
{
// Writes the sections of `edited` (same section sizes as the volume `original` was written from)
// over an uncompressed file, then recomputes every section CRC and the header CRC: the edit
// reaches the content checks behind the checksums.
Bytes rewriteSections(const Bytes& original, const svdag::Volume& edited)
{
  Bytes b = original;
  auto put = [&](uint32_t id, const Bytes& raw) {
    const size_t e = entryOf(b, id);
    EXPECT_EQ(getLE(b, e + Codec, 4), 0u) << "rewriteSections needs an uncompressed file";
    EXPECT_EQ(getLE(b, e + Raw, 8), raw.size()) << "section " << id << " changed size";
    const size_t at = size_t(getLE(b, e + Offset, 8));
    std::copy(raw.begin(), raw.end(), b.begin() + long(at));
    putLE(b, e + Crc, crc32(0, raw.data(), uInt(raw.size())), 4);
  };
  auto words = [](const std::vector<uint32_t>& stream) {
    Bytes raw(4 * (stream.size() - 1));
    for (size_t i = 0; i + 1 < stream.size(); ++i)
      putLE(raw, 4 * i, stream[i], 4);
    return raw;
  };
  Bytes labels(40 * edited.labels.size());
  for (size_t l = 0; l < edited.labels.size(); ++l)
  {
    putLE(labels, 40 * l, edited.labels[l].value, 8);
    putLE(labels, 40 * l + 8, edited.labels[l].voxels, 8);
    for (int k = 0; k < 6; ++k)
      putLE(labels, 40 * l + 16 + 4 * size_t(k), uint32_t(edited.labels[l].bounds[size_t(k)]), 4);
  }
  Bytes leaves(8 * edited.leaves.size());
  for (size_t l = 0; l < edited.leaves.size(); ++l)
    putLE(leaves, 8 * l, edited.leaves[l], 8);
  put(LabelsSection, labels);
  put(BlocksSection, words(edited.blocks));
  put(RootsSection, words(edited.roots));
  put(MidsSection, words(edited.mids));
  put(LeavesSection, leaves);
  resealHeader(b);
  return b;
}

void writeBits(std::vector<uint32_t>& stream, uint64_t offset, uint32_t width, uint32_t value)
{
  for (uint32_t k = 0; k < width; ++k, ++offset)
  {
    const uint32_t bit = 1u << (offset & 31);
    if ((value >> k) & 1u)
      stream[size_t(offset >> 5)] |= bit;
    else
      stream[size_t(offset >> 5)] &= ~bit;
  }
}

// Field setters of block i (Layout.h's record layout).
void setBlockBox(svdag::Volume& v, uint64_t i, const svdag::Block& b)
{
  uint32_t box = 0;
  for (int a = 0; a < 3; ++a)
    box |= (uint32_t(b.lo[size_t(a)]) << (4 * a)) | (uint32_t(b.hi[size_t(a)]) << (12 + 4 * a));
  writeBits(v.blocks, i * v.widths.blockBits() + svdag::layout::blockBoundsOffset(v.widths.cellBits),
    24, box);
}
void setBlockRoot(svdag::Volume& v, uint64_t i, uint32_t ref)
{
  writeBits(v.blocks,
    i * v.widths.blockBits() + svdag::layout::blockRootOffset(v.widths.cellBits, v.widths.labelBits),
    v.widths.rootRefBits, ref);
}
void setBlockCell(svdag::Volume& v, uint64_t i, uint32_t cell)
{
  writeBits(v.blocks, i * v.widths.blockBits(), v.widths.cellBits, cell);
}
void setBlockLabel(svdag::Volume& v, uint64_t i, uint32_t label)
{
  writeBits(v.blocks, i * v.widths.blockBits() + svdag::layout::blockLabelOffset(v.widths.cellBits),
    v.widths.labelBits, label);
}

std::string loadError(const Bytes& b)
{
  try
  {
    svdag::deserialize(b);
  }
  catch (const FileError& e)
  {
    return e.what();
  }
  return "loaded without an error";
}

// Three labels in a 37 x 32 x 26 volume (partial cells on x and z): nested spheres and a slab,
// so that cells hold one, two and three blocks.
svdag::Volume threeLabels()
{
  return svdag::pooled(build(ScalarType::UInt16, geometry(37, 32, 26), [](int x, int y, int z) -> uint64_t {
    const int d2 = (x - 16) * (x - 16) + (y - 14) * (y - 14) + (z - 12) * (z - 12);
    return d2 < 30 ? 5 : d2 < 100 ? 9 : y > 25 ? 40 : 0;
  })); // as files hold it: the edits below are to the pooled sections
}
// First index of a cell holding at least `count` blocks.
uint64_t cellWith(const svdag::Volume& v, uint64_t count)
{
  for (uint64_t i = 0; i + count <= v.blockCount; ++i)
  {
    if (v.block(i).cell == v.block(i + count - 1).cell)
      return i;
  }
  ADD_FAILURE() << "no cell with " << count << " blocks";
  return 0;
}
} // namespace

// The untouched file loads: the helper itself changes nothing.
TEST(FileContent, RewritingUnchangedSectionsLoads)
{
  const svdag::Volume v = threeLabels();
  const Bytes good = svdag::serialize(v, { 0, 2 });
  EXPECT_EQ(rewriteSections(good, v), good);
  EXPECT_TRUE(svdag::deserialize(rewriteSections(good, v)) == svdag::compacted(v));
}

TEST(FileContent, ImpossibleBlocksAreRefusedNamingTheRule)
{
  const svdag::Volume v = threeLabels();
  const Bytes good = svdag::serialize(v, { 0, 2 });
  ASSERT_GE(v.blockCount, 4u);
  auto expectRefused = [&](const svdag::Volume& bad, const std::string& rule) {
    const std::string message = loadError(rewriteSections(good, bad));
    EXPECT_NE(message.find(rule), std::string::npos) << "expected '" << rule << "', got: " << message;
    EXPECT_THROW(bad.validate(), std::runtime_error) << rule;
  };

  { // bounds past the volume's edge in a partial cell (x: 37 = 2 * 16 + 5)
    svdag::Volume bad = v;
    const auto n = v.geometry.cellCounts();
    uint64_t i = 0;
    while (i < v.blockCount && v.block(i).cell % uint32_t(n[0]) != uint32_t(n[0] - 1))
      ++i;
    ASSERT_LT(i, v.blockCount);
    svdag::Block b = v.block(i);
    b.hi[0] = 15;
    setBlockBox(bad, i, b);
    expectRefused(bad, "bounds outside the volume");
  }
  { // inverted bounds
    svdag::Volume bad = v;
    uint64_t i = 0;
    while (i < v.blockCount && v.block(i).lo[1] == v.block(i).hi[1])
      ++i;
    ASSERT_LT(i, v.blockCount);
    svdag::Block b = v.block(i);
    std::swap(b.lo[1], b.hi[1]);
    setBlockBox(bad, i, b);
    expectRefused(bad, "bounds inverted");
  }
  { // occupancy outside the declared bounds: label_at would see voxels that decode() does not
    svdag::Volume bad = v;
    uint64_t i = 0;
    while (i < v.blockCount && v.block(i).lo[0] == v.block(i).hi[0])
      ++i;
    ASSERT_LT(i, v.blockCount);
    svdag::Block b = v.block(i);
    b.hi[0] = uint8_t(b.hi[0] - 1);
    setBlockBox(bad, i, b);
    expectRefused(bad, "occupancy outside its declared bounds");
  }
  auto swapBlocks = [&](svdag::Volume& volume, uint64_t i, uint64_t j) {
    const svdag::Block a = v.block(i), b = v.block(j);
    setBlockBox(volume, i, b);
    setBlockLabel(volume, i, b.label);
    setBlockRoot(volume, i, b.root);
    setBlockBox(volume, j, a);
    setBlockLabel(volume, j, a.label);
    setBlockRoot(volume, j, a.root);
  };
  { // two blocks of one cell swapped: files written before blocks were sorted by label within a
    // cell hold them in scan order; they load and decode to the same voxels
    svdag::Volume swapped = v;
    const uint64_t i = cellWith(v, 2);
    swapBlocks(swapped, i, i + 1);
    EXPECT_NO_THROW(swapped.validate());
    const svdag::Volume loaded = svdag::deserialize(rewriteSections(good, swapped));
    EXPECT_EQ(svdag::decode(loaded), svdag::decode(v));
  }
  { // blocks of two cells out of order: the last block moved to a cell before the others'
    svdag::Volume bad = v;
    const uint64_t last = v.blockCount - 1;
    ASSERT_GT(v.block(last).cell, v.block(0).cell);
    setBlockCell(bad, last, v.block(0).cell);
    expectRefused(bad, "blocks not sorted by cell");
  }
  { // a cell with two blocks of one label
    svdag::Volume bad = v;
    const uint64_t i = cellWith(v, 2);
    setBlockLabel(bad, i + 1, v.block(i).label);
    expectRefused(bad, "holds two blocks of one label");
  }
  { // root reference into the middle of a root node
    svdag::Volume bad = v;
    setBlockRoot(bad, 0, (svdag::layout::refTarget(v.block(0).root) + 3) << 1);
    expectRefused(bad, "root reference does not point at a root node");
  }
  { // two blocks of one cell overlapping: the second takes the first's occupancy and bounds
    svdag::Volume bad = v;
    const uint64_t i = cellWith(v, 2);
    const svdag::Block a = v.block(i);
    setBlockBox(bad, i + 1, a);
    setBlockRoot(bad, i + 1, a.root);
    expectRefused(bad, "overlap (a voxel has one label)");
  }
  { // in a cell of three blocks, the third takes the second's occupancy
    svdag::Volume bad = v;
    const uint64_t i = cellWith(v, 3);
    const svdag::Block a = v.block(i + 1);
    setBlockBox(bad, i + 2, a);
    setBlockRoot(bad, i + 2, a.root);
    expectRefused(bad, "overlap (a voxel has one label)");
  }
}

// Tight bounds validate and any one side moved in by a voxel does not: the check bounds each
// block from its leaves' projections moved by their references' symmetries, so a projection
// moved the wrong way would let a voxel outside the bounds through (or refuse tight ones).
TEST(FileContent, EveryBoundMovedInIsRefused)
{
  const svdag::Volume v = svdag::pooled(spheres(ScalarType::UInt16, 45)); // as files hold it
  ASSERT_NO_THROW(v.validate());
  std::array<bool, svdag::layout::LEAF_SYMMETRY_COUNT> symmetrySeen{};
  uint64_t offset = 0;
  for (uint64_t n = 0; n < v.midCount; ++n)
  {
    const uint32_t mixed = svdag::layout::nodeMixedMask(svdag::Volume::nodeHeader(v.mids, offset));
    for (uint32_t k = 0; k < uint32_t(__builtin_popcount(mixed)); ++k)
      symmetrySeen[svdag::layout::leafRefSymmetry(
        svdag::Volume::nodeChildRef(v.mids, offset, k, v.widths.leafRefBits))] = true;
    offset += svdag::Volume::nodeBits(v.mids, offset, v.widths.leafRefBits);
  }
  EXPECT_GE(std::count(symmetrySeen.begin(), symmetrySeen.end(), true), 24)
    << "the volume should reach leaves under most symmetries";
  int refused = 0;
  for (uint64_t i = 0; i < v.blockCount; ++i)
    for (int side = 0; side < 6; ++side)
    {
      svdag::Block b = v.block(i);
      const int a = side / 2;
      if (b.lo[a] == b.hi[a])
        continue;
      if (side % 2)
        --b.hi[a];
      else
        ++b.lo[a];
      svdag::Volume bad = v;
      setBlockBox(bad, i, b);
      EXPECT_THROW(bad.validate(), std::runtime_error) << "block " << i << " side " << side;
      ++refused;
    }
  EXPECT_GT(refused, 100);
}

TEST(FileContent, EmptyBlockOccupancyIsRefused)
{
  // A 20^3 volume of one label: cell 0 is solid, its root is the empty node complemented.
  const svdag::Volume v = svdag::pooled(
    build(ScalarType::Int64, geometry(20, 20, 20), [](int, int, int) { return uint64_t(3); }));
  const Bytes good = svdag::serialize(v, { 0, 2 });
  ASSERT_EQ(v.block(0).cell, 0u);
  ASSERT_TRUE(svdag::layout::refComplement(v.block(0).root));
  svdag::Volume bad = v;
  setBlockRoot(bad, 0, v.block(0).root ^ 1u);
  const std::string message = loadError(rewriteSections(good, bad));
  EXPECT_NE(message.find("empty occupancy"), std::string::npos) << message;
}

TEST(FileContent, ImpossibleNodeReferencesAreRefused)
{
  const svdag::Volume v = threeLabels();
  const Bytes good = svdag::serialize(v, { 0, 2 });
  // The first mixed child reference of the first root and of the first mid node with one.
  auto firstRef = [](const std::vector<uint32_t>& stream, uint64_t count, uint32_t refBits) {
    uint64_t offset = 0;
    for (uint64_t n = 0; n < count; ++n)
    {
      const uint32_t mixed = svdag::layout::nodeMixedMask(svdag::Volume::nodeHeader(stream, offset));
      if (mixed)
        return int64_t(offset + svdag::layout::NODE_HEADER_BITS);
      offset += svdag::Volume::nodeBits(stream, offset, refBits);
    }
    return int64_t(-1);
  };
  {
    svdag::Volume bad = v;
    const int64_t at = firstRef(v.roots, v.rootCount, v.widths.midRefBits);
    ASSERT_GE(at, 0);
    writeBits(bad.roots, uint64_t(at), v.widths.midRefBits, 3u << 1); // bit 3 of the mid stream
    const std::string message = loadError(rewriteSections(good, bad));
    EXPECT_NE(message.find("root node at bit"), std::string::npos) << message;
    EXPECT_NE(message.find("child reference does not point at a node"), std::string::npos) << message;
  }
  {
    svdag::Volume bad = v;
    const int64_t at = firstRef(v.mids, v.midCount, v.widths.leafRefBits);
    ASSERT_GE(at, 0);
    const uint32_t past = uint32_t(v.leaves.size()) << 1;
    ASSERT_EQ(past >> v.widths.leafRefBits, 0u) << "the leaf field cannot hold an index past the end";
    writeBits(bad.mids, uint64_t(at), v.widths.leafRefBits, past);
    const std::string message = loadError(rewriteSections(good, bad));
    EXPECT_NE(message.find("mid node at bit"), std::string::npos) << message;
  }
}

// Runs a range as `pieces` chunks, each on a thread of its own, all at once: what a thread pool
// does at worst (the nodes of one pool checked side by side, none of them in order).
svdag::ParallelFor onThreads(uint64_t pieces)
{
  return [pieces](uint64_t begin, uint64_t end, uint64_t, const svdag::RangeFunction& f) {
    std::vector<std::thread> running;
    for (uint64_t p = 0; p < pieces; ++p)
    {
      const uint64_t b = begin + (end - begin) * p / pieces, e = begin + (end - begin) * (p + 1) / pieces;
      if (b < e)
        running.emplace_back([&f, b, e]() { f(b, e); });
    }
    for (std::thread& t : running)
      t.join();
  };
}

std::string loadError(const Bytes& b, const svdag::ParallelFor& parallel)
{
  try
  {
    svdag::deserialize(b.data(), b.size(), parallel);
  }
  catch (const FileError& e)
  {
    return e.what();
  }
  return "loaded without an error";
}

// Validation checks the nodes of a pool and the cells in parallel: the same volume as in order,
// and for a file with two bad references or two overlapping cells the same error (the first's).
TEST(FileContent, ParallelValidationAgreesWithTheOrderedOne)
{
  std::mt19937 rng(41);
  const svdag::Volume v = svdag::pooled(build(ScalarType::UInt16, geometry(64, 48, 40),
    [&](int x, int y, int z) { return uint64_t((x / 5 + y / 7 + z / 3 + (rng() % 9 == 0)) % 40); }));
  ASSERT_GT(v.midCount, 1024u) << "fewer nodes than one of the validation's grains";
  for (const svdag::WriteOptions options : { svdag::WriteOptions{}, svdag::WriteOptions{ 0, 2 } })
  {
    SCOPED_TRACE("format " + std::to_string(options.formatVersion));
    const Bytes good = svdag::serialize(v, options);
    const svdag::Volume ordered = svdag::deserialize(good);
    EXPECT_TRUE(ordered == svdag::compacted(v));
    for (uint64_t pieces : { 2u, 7u })
      EXPECT_TRUE(svdag::deserialize(good.data(), good.size(), onThreads(pieces)) == ordered);
  }
  // Two mid nodes' first references moved past the last leaf, one early in the stream, one late.
  const Bytes good = svdag::serialize(v, { 0, 2 });
  svdag::Volume bad = v;
  uint64_t offset = 0;
  std::vector<uint64_t> refs; // the first reference of each mid node that has one
  for (uint64_t n = 0; n < v.midCount; ++n)
  {
    if (svdag::layout::nodeMixedMask(svdag::Volume::nodeHeader(v.mids, offset)))
      refs.push_back(offset + svdag::layout::NODE_HEADER_BITS);
    offset += svdag::Volume::nodeBits(v.mids, offset, v.widths.leafRefBits);
  }
  ASSERT_GT(refs.size(), 100u);
  const uint32_t past = uint32_t(v.leaves.size()) << (svdag::layout::LEAF_SYMMETRY_BITS + 1);
  ASSERT_EQ(past >> v.widths.leafRefBits, 0u) << "the leaf field cannot hold an index past the end";
  for (uint64_t at : { refs[refs.size() - 3], refs[refs.size() / 5] })
    writeBits(bad.mids, at, v.widths.leafRefBits, past);
  const Bytes edited = rewriteSections(good, bad);
  const std::string message = loadError(edited);
  EXPECT_NE(message.find("mid node at bit " + std::to_string(refs[refs.size() / 5] -
              svdag::layout::NODE_HEADER_BITS)), std::string::npos) << message;
  for (uint64_t pieces : { 2u, 7u })
    EXPECT_EQ(loadError(edited, onThreads(pieces)), message);

  // Two cells, one early and one late, whose second block becomes a copy of their first (its
  // root and bounds, its own label): blocks that overlap, found by cells checked side by side.
  std::vector<uint64_t> pairs; // the first block of each cell with two or more
  for (uint64_t i = 0; i + 1 < v.blockCount; ++i)
    if (v.block(i).cell == v.block(i + 1).cell && (pairs.empty() || v.block(pairs.back()).cell != v.block(i).cell))
      pairs.push_back(i);
  ASSERT_GT(pairs.size(), 20u);
  svdag::Volume overlapping = v;
  for (uint64_t i : { pairs[pairs.size() - 2], pairs[pairs.size() / 4] })
  {
    setBlockRoot(overlapping, i + 1, v.block(i).root);
    setBlockBox(overlapping, i + 1, v.block(i));
  }
  const Bytes twice = rewriteSections(good, overlapping);
  const std::string overlap = loadError(twice);
  EXPECT_NE(overlap.find("blocks " + std::to_string(pairs[pairs.size() / 4]) + " and "),
    std::string::npos) << overlap;
  EXPECT_NE(overlap.find("overlap"), std::string::npos) << overlap;
  for (uint64_t pieces : { 2u, 7u })
    EXPECT_EQ(loadError(twice, onThreads(pieces)), overlap);
}

// Blocks that share a leaf's space are compared voxel by voxel: a leaf reference given another
// symmetry (the same voxel count, other voxels) is refused as an overlap exactly where two blocks
// of a cell then hold one voxel, by a brute-force look at every block's occupancy.
TEST(FileContent, LeavesUnderAnotherSymmetryOverlapWhereTheirVoxelsDo)
{
  std::mt19937 noise(7); // labels in slabs, some voxels flipped: leaves shared by several blocks
  const svdag::Volume v = svdag::pooled(build(ScalarType::UInt16, geometry(40, 36, 32),
    [&](int x, int y, int z) { return uint64_t((x / 3 + y / 4 + z / 5 + (noise() % 7 == 0)) % 9); }));
  std::vector<uint64_t> refAt; // where each mid's leaf references lie in the mid stream
  uint64_t offset = 0;
  for (uint64_t n = 0; n < v.midCount; ++n)
  {
    const uint32_t mixed = svdag::layout::nodeMixedMask(svdag::Volume::nodeHeader(v.mids, offset));
    for (uint32_t k = 0; k < uint32_t(__builtin_popcount(mixed)); ++k)
      refAt.push_back(offset + svdag::layout::NODE_HEADER_BITS + uint64_t(k) * v.widths.leafRefBits);
    offset += svdag::Volume::nodeBits(v.mids, offset, v.widths.leafRefBits);
  }
  ASSERT_GT(refAt.size(), 200u);
  auto collides = [](const svdag::Volume& volume) {
    std::vector<uint8_t> held(4096), occupancy(4096);
    for (uint64_t first = 0; first < volume.blockCount;)
    {
      const uint32_t cell = volume.block(first).cell;
      std::fill(held.begin(), held.end(), uint8_t(0));
      uint64_t i = first;
      for (; i < volume.blockCount && volume.block(i).cell == cell; ++i)
      {
        volume.occupancy(i, occupancy.data());
        for (size_t x = 0; x < held.size(); ++x)
        {
          if (held[x] && occupancy[x])
            return true;
          held[x] |= occupancy[x];
        }
      }
      first = i;
    }
    return false;
  };
  std::mt19937_64 rng(5);
  size_t overlaps = 0, accepted = 0;
  for (int trial = 0; trial < 300; ++trial)
  {
    svdag::Volume edited = v;
    const uint64_t at = refAt[rng() % refAt.size()];
    const uint32_t ref = uint32_t(svdag::bits::readBits(edited.mids, at, edited.widths.leafRefBits));
    const uint32_t symmetry = uint32_t(rng() % svdag::layout::LEAF_SYMMETRY_COUNT);
    writeBits(edited.mids, at, edited.widths.leafRefBits,
      svdag::layout::leafRef(svdag::layout::leafRefIndex(ref), symmetry, ref & 1u));
    const bool bruteForce = collides(edited);
    std::string error;
    try
    {
      svdag::Volume checked = edited;
      checked.deriveBoundsAndValidate();
    }
    catch (const std::runtime_error& e)
    {
      error = e.what();
    }
    EXPECT_EQ(error.find("overlap") != std::string::npos, bruteForce) << error;
    EXPECT_TRUE(error.empty() || error.find("overlap") != std::string::npos) << error;
    overlaps += bruteForce;
    accepted += error.empty();
  }
  EXPECT_GT(overlaps, 30u);
  EXPECT_GT(accepted, 10u);
}

TEST(FileContent, LabelTableMustMatchTheBlocks)
{
  const svdag::Volume v = threeLabels();
  ASSERT_EQ(v.labels.size(), 3u);
  const Bytes good = svdag::serialize(v, { 0, 2 });
  auto expectRefused = [&](const svdag::Volume& bad, const std::string& rule) {
    const std::string message = loadError(rewriteSections(good, bad));
    EXPECT_NE(message.find(rule), std::string::npos) << "expected '" << rule << "', got: " << message;
  };
  {
    svdag::Volume bad = v;
    bad.labels[1].voxels -= 1;
    expectRefused(bad, "voxel count");
  }
  {
    svdag::Volume bad = v;
    bad.labels[1].voxels += 1;
    expectRefused(bad, "voxel count");
  }
  {
    svdag::Volume bad = v;
    ASSERT_GT(bad.labels[0].bounds[0], 0);
    bad.labels[0].bounds[0] -= 1; // still inside the volume, no longer tight
    expectRefused(bad, "bounds in the label table differ");
  }
  {
    svdag::Volume bad = v;
    std::swap(bad.labels[0].value, bad.labels[1].value);
    expectRefused(bad, "not sorted by value or not unique");
  }
  {
    svdag::Volume bad = v;
    bad.labels[1].value = bad.labels[0].value;
    expectRefused(bad, "not sorted by value or not unique");
  }
  {
    svdag::Volume bad = v;
    bad.labels[0].value = v.background;
    expectRefused(bad, "background");
  }
}

// A valid 404-byte file of an empty 4096^3 volume loads (it is tiny), but a dense decode needs
// 256 GiB: refused before allocating, with the byte count, never std::bad_alloc.
TEST(FileContent, HugeEmptyVolumeLoadsButRefusesADenseDecode)
{
  const svdag::Volume small =
    build(ScalarType::UInt32, geometry(17, 17, 17), [](int, int, int) { return uint64_t(0); });
  Bytes b = svdag::serialize(small, { 0, 2 });
  for (int a = 0; a < 3; ++a)
    putLE(b, DimsAt + 4 * size_t(a), 4096, 4);
  putLE(b, WidthsAt, 24, 4); // 256^3 cells
  resealHeader(b);
  EXPECT_EQ(b.size(), 404u);
  const svdag::Volume v = svdag::deserialize(b);
  EXPECT_EQ(v.geometry.voxelCount(), uint64_t(1) << 36);
  EXPECT_EQ(svdag::decodedBytes(v), uint64_t(1) << 38);
  if (svdag::physicalMemoryBytes() == 0 || svdag::physicalMemoryBytes() >= (uint64_t(1) << 38))
    GTEST_SKIP() << "this machine could hold the decoded volume";
  largestAllocation = 0;
  for (int allocating = 0; allocating < 2; ++allocating)
  {
    try
    {
      if (allocating)
        svdag::decode(v);
      else
        svdag::checkDecodeMemory(v);
      ADD_FAILURE() << "a 256 GiB decode was not refused";
    }
    catch (const std::length_error& e)
    {
      const std::string message = e.what();
      EXPECT_NE(message.find("decoding 4096 x 4096 x 4096 uint32 voxels needs 274877906944 bytes (256 GiB)"),
        std::string::npos) << message;
    }
  }
  EXPECT_LT(largestAllocation.load(), size_t(1) << 20);
  // One slab of 16 slices (1 GiB) is a decode this machine can do, as far as the check goes.
  EXPECT_NO_THROW(svdag::checkDecodeMemory(v, 1));
}

TEST(FileContent, FormatBytes)
{
  EXPECT_EQ(svdag::formatBytes(0), "0 bytes");
  EXPECT_EQ(svdag::formatBytes(1), "1 byte");
  EXPECT_EQ(svdag::formatBytes(1536), "1.5 KiB");
  EXPECT_EQ(svdag::formatBytes(uint64_t(256) << 30), "256 GiB");
}

// Format 1.0 files (Testing/Data/format1, written by the last 1.0 build) load into today's
// layout: every voxel as the file's own 1.0 decode gave it is checked in
// Testing/Python/test_svdag_format1.py; here, the upgraded volume validates, writes as 2.0 and
// reads back equal, and corruption of a 1.0 file (bit flips anywhere; header fields changed
// behind a resealed checksum) fails cleanly or loads a valid volume, never anything else.
TEST(File, Format1FilesLoadAndTheirCorruptionFailsCleanly)
{
  for (const char* name : { "cells_uint16", "noise_uint8_uncompressed", "wide_int64", "empty_uint8" })
  {
    const std::string path = std::string(SVDAG_FORMAT1_DIR) + "/" + name + ".svdag";
    std::ifstream in(path, std::ios::binary);
    ASSERT_TRUE(in) << path;
    const Bytes bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    ASSERT_EQ(bytes[8], 1u) << "not a 1.0 file: " << path;
    const svdag::Volume v = svdag::deserialize(bytes);
    EXPECT_EQ(v.widths.leafRefBits >= 1 + svdag::layout::LEAF_SYMMETRY_BITS, true) << name;
    const Bytes again = svdag::serialize(v, { 3, 2 });
    EXPECT_EQ(again[8], 2u);
    // The 1.0 file's leaves were not shared up to symmetry; written again they are: the same
    // voxels, and after one more round the same bytes.
    EXPECT_EQ(svdag::coded::compareOccupancy(svdag::deserialize(again), v), "") << name;
    const Bytes settled = svdag::serialize(svdag::deserialize(again), { 3, 2 });
    EXPECT_EQ(svdag::serialize(svdag::deserialize(settled), { 3, 2 }), settled) << name;
    // The default format (4) lays the DAG out in first-use order: the same blocks and voxels.
    const Bytes coded = svdag::serialize(v);
    EXPECT_EQ(coded[8], svdag::FileMajorVersion);
    EXPECT_EQ(svdag::coded::compareOccupancy(svdag::deserialize(coded), v), "") << name;

    std::mt19937_64 rng(5);
    size_t failed = 0, loaded = 0;
    for (int i = 0; i < 600; ++i)
    {
      Bytes bad = bytes;
      if (i % 2 == 0)
      {
        bad[rng() % bad.size()] ^= uint8_t(1u << (rng() % 8));
      }
      else
      {
        const size_t at = WidthsAt + rng() % (headerCrcAt(bad) - WidthsAt);
        if (at >= SectionCountAt && at < TableAt)
          continue; // a new section count would move the checksum itself
        bad[at] ^= uint8_t(1u << (rng() % 8));
        resealHeader(bad);
      }
      expectFailsOrValid(bad, failed, loaded);
    }
    EXPECT_GT(failed, 250u) << name;
  }
}

// ---- format 3: the coded volume ----

namespace
{
// Volumes that reach every path of the coded form beyond volumes(): a cell of 4096 labels,
// labels that skip cells, labels at the type's extremes in cells of their own, excluded labels.
std::vector<Named> codedVolumes()
{
  std::vector<Named> out = volumes();
  uint64_t next = 0;
  out.push_back({ "4096 labels in one cell", build(ScalarType::Int32, geometry(16, 16, 16),
                                               [&](int, int, int) { return next++; }, ~uint64_t(0)) });
  out.push_back({ "sparse labels, empty cells 70x9x50",
    build(ScalarType::UInt64, geometry(70, 9, 50), [](int x, int y, int z) -> uint64_t {
      if ((x / 16 + z / 16) % 3 != 0)
        return 0;
      return (x * 7 + y * 3 + z) % 11 == 0 ? (uint64_t(1) << 63) + uint64_t(z) : uint64_t(x / 5) + 1;
    }) });
  out.push_back({ "checkerboard 19x21x18", build(ScalarType::Int8, geometry(19, 21, 18),
                                             [](int x, int y, int z) -> uint64_t {
                                               return (x + y + z) % 2 ? uint64_t(-128) : 127;
                                             }) });
  std::vector<uint8_t> labels(31 * 17 * 40);
  std::mt19937 rng(8);
  for (uint8_t& l : labels)
    l = uint8_t(rng() % 6);
  svdag::BuildOptions options;
  options.background = 2;
  options.excluded = { 4 };
  out.push_back({ "noise with background 2 and label 4 excluded",
    svdag::Builder::build(geometry(31, 17, 40), ScalarType::UInt8, labels.data(), options) });
  return out;
}

// Format 3 written explicitly (4 is the default).
const svdag::WriteOptions Coded{ 3, 3 };

// Re-seals the checksums of section `id` (6: format 3's coded volume) after a test edits its
// bytes in place.
void resealCoded(Bytes& b, uint32_t id = 6)
{
  const size_t e = entryOf(b, id);
  const size_t at = size_t(getLE(b, e + Offset, 8)), n = size_t(getLE(b, e + Stored, 8));
  putLE(b, e + Crc, crc32(0, b.data() + at, uInt(n)), 4);
  resealHeader(b);
}

// Random damage to section `id` of a good file: a bit flip fails on the section's checksum;
// resealed (a buggy or hostile writer), with a second change every third round, it fails cleanly
// or loads a valid volume, without allocating 64 MiB; more than `minFailed` of the rounds fail.
void expectSectionCorruptionFailsCleanly(
  const Bytes& good, uint32_t id, std::mt19937_64& rng, int rounds, size_t minFailed)
{
  const size_t e = entryOf(good, id);
  const size_t at = size_t(getLE(good, e + Offset, 8)), size = size_t(getLE(good, e + Stored, 8));
  size_t failed = 0, loaded = 0;
  for (int i = 0; i < rounds; ++i)
  {
    Bytes bad = good;
    bad[at + rng() % size] ^= uint8_t(1u << (rng() % 8));
    EXPECT_THROW(svdag::deserialize(bad), FileError);
    if (i % 3 == 0)
      bad[at + rng() % size] = uint8_t(rng()); // and a second change
    resealCoded(bad, id);
    largestAllocation = 0;
    expectFailsOrValid(bad, failed, loaded);
    EXPECT_LT(largestAllocation.load(), size_t(64) << 20);
  }
  EXPECT_GT(failed, minFailed);
}
} // namespace

TEST(CodedFile, RoundTripIsExactDeterministicAndSmaller)
{
  for (const Named& n : codedVolumes())
  {
    SCOPED_TRACE(n.name);
    ASSERT_NO_THROW(n.volume.validate());
    const Bytes bytes = svdag::serialize(n.volume, Coded);
    EXPECT_EQ(getLE(bytes, 8, 2), 3u);
    ASSERT_EQ(sectionCount(bytes), 1u);
    const svdag::Volume back = svdag::deserialize(bytes);
    // A built volume's DAG is in first-use order, so the rebuild is bit-identical.
    EXPECT_TRUE(back == n.volume);
    EXPECT_EQ(svdag::serialize(back, Coded), bytes);
    EXPECT_LE(bytes.size(), svdag::serialize(n.volume, { 19, 2 }).size() + 64);
  }
}

// A volume whose DAG is laid out otherwise (a 1.0 file's, a hand-made one) is written as the
// build of its voxels: the same blocks and voxels, and a file that then round-trips exactly.
TEST(CodedFile, AVolumeInAnotherLayoutIsWrittenAsItsBuild)
{
  svdag::Volume v = svdag::pooled(spheres(ScalarType::UInt16, 40)); // as files hold it
  // Swap the first two leaves and fix every reference to them.
  ASSERT_GE(v.leaves.size(), 2u);
  std::swap(v.leaves[0], v.leaves[1]);
  for (uint64_t offset = 0, m = 0; m < v.midCount; ++m)
  {
    const uint32_t mixed = svdag::layout::nodeMixedMask(svdag::Volume::nodeHeader(v.mids, offset));
    for (uint32_t r = 0; r < uint32_t(__builtin_popcount(mixed)); ++r)
    {
      const uint64_t at = offset + svdag::layout::NODE_HEADER_BITS + uint64_t(r) * v.widths.leafRefBits;
      uint32_t ref = svdag::Volume::nodeChildRef(v.mids, offset, r, v.widths.leafRefBits);
      const uint32_t index = svdag::layout::leafRefIndex(ref);
      if (index < 2)
      {
        ref = svdag::layout::leafRef(1 - index, svdag::layout::leafRefSymmetry(ref), ref & 1u);
        const uint64_t word = at >> 5;
        const uint32_t shift = uint32_t(at & 31);
        uint64_t pair = v.mids[word] | (uint64_t(v.mids[word + 1]) << 32);
        const uint64_t fieldMask = ((uint64_t(1) << v.widths.leafRefBits) - 1) << shift;
        pair = (pair & ~fieldMask) | (uint64_t(ref) << shift);
        v.mids[word] = uint32_t(pair);
        v.mids[word + 1] = uint32_t(pair >> 32);
      }
    }
    offset += svdag::Volume::nodeBits(v.mids, offset, v.widths.leafRefBits);
  }
  ASSERT_NO_THROW(v.validate());
  const svdag::Volume built = spheres(ScalarType::UInt16, 40);
  ASSERT_FALSE(v == svdag::pooled(built));
  const Bytes bytes = svdag::serialize(v, Coded);
  const svdag::Volume back = svdag::deserialize(bytes);
  EXPECT_EQ(svdag::coded::compareOccupancy(back, v), "");
  EXPECT_TRUE(back == built);
  EXPECT_EQ(bytes, svdag::serialize(built, Coded));
}

// Chunks are coded and decoded apart (in parallel where the caller runs them so) and one builder
// takes their blocks: the one volume, whatever their number; corrupt chunk tables fail.
TEST(CodedFile, ChunksDecodeToTheOneVolume)
{
  std::mt19937 rng(4);
  const svdag::Volume v = build(ScalarType::UInt16, geometry(40, 30, 100), [&](int x, int y, int z) {
    return rng() % 97 == 0 ? uint64_t(rng() % 50) : uint64_t((x / 7 + y / 9 + z / 11) % 13);
  });
  ASSERT_EQ(svdag::coded::maxChunkCount(v.geometry), 7u);
  ASSERT_EQ(svdag::coded::chunkCount(v.geometry), 1u);
  const svdag::coded::Frame frame = svdag::coded::frameOf(v);
  svdag::ParallelFor pairs = [](uint64_t begin, uint64_t end, uint64_t, const svdag::RangeFunction& f) {
    for (uint64_t i = begin; i < end; i += 2) // out of order and in pairs, as a thread pool might
      f(i, std::min(end, i + 2));
  };
  for (uint32_t chunks : { 1u, 2u, 3u, 7u })
  {
    SCOPED_TRACE(std::to_string(chunks) + " chunks");
    const Bytes coded = svdag::coded::encode(v, pairs, chunks);
    EXPECT_EQ(getLE(coded, 0, 4), chunks);
    // The decoder's builder gives the pooled form.
    EXPECT_TRUE(svdag::compacted(svdag::coded::decode(coded.data(), coded.size(), frame)) == v);
    EXPECT_TRUE(svdag::compacted(svdag::coded::decode(coded.data(), coded.size(), frame, pairs)) == v);
    if (chunks == 3)
    {
      Bytes bad = coded;
      putLE(bad, 0, 8, 4); // more chunks than slabs
      EXPECT_THROW(svdag::coded::decode(bad.data(), bad.size(), frame), svdag::coding::CorruptStream);
      bad = coded;
      putLE(bad, 0, 2, 4); // fewer: the table no longer fills the section
      EXPECT_THROW(svdag::coded::decode(bad.data(), bad.size(), frame), svdag::coding::CorruptStream);
      bad = coded;
      putLE(bad, 12 + 8, getLE(coded, 12 + 8, 8) + 1, 8); // a chunk's block count
      EXPECT_THROW(svdag::coded::decode(bad.data(), bad.size(), frame), svdag::coding::CorruptStream);
      bad = coded;
      putLE(bad, 12, getLE(coded, 12, 8) - 1, 8); // a chunk's bytes
      EXPECT_THROW(svdag::coded::decode(bad.data(), bad.size(), frame), svdag::coding::CorruptStream);
      // A chunk that fails while others decode beside it: its error, on the caller's thread.
      bad = coded;
      const size_t secondChunk = size_t(12 + 16 * 3 + getLE(coded, 4, 8) + getLE(coded, 12, 8));
      bad[secondChunk] = 0x55; // not a range coder's first byte
      EXPECT_THROW(svdag::coded::decode(bad.data(), bad.size(), frame, pairs), svdag::coding::CorruptStream);
    }
  }
  EXPECT_THROW(svdag::coded::encode(v, svdag::sequentialFor, 8), std::invalid_argument);
}

TEST(CodedFile, EveryTruncationFails)
{
  const Bytes bytes = svdag::serialize(spheres(ScalarType::UInt16, 20), Coded);
  for (size_t n = 0; n < bytes.size(); ++n)
    EXPECT_THROW(svdag::deserialize(bytes.data(), n), FileError) << "prefix of " << n << " bytes";
}

// Corruption anywhere fails on a checksum; corruption of the coded bytes behind resealed
// checksums (a buggy or hostile writer) fails cleanly or loads a valid volume, never a crash, a
// hang or a huge allocation.
TEST(CodedFile, CorruptionFailsCleanly)
{
  std::mt19937_64 rng(21);
  const std::vector<Named> all = codedVolumes();
  for (const Named& n : { Named{ "spheres", spheres(ScalarType::UInt32, 30) }, all[all.size() - 4] })
  {
    SCOPED_TRACE(n.name);
    expectSectionCorruptionFailsCleanly(svdag::serialize(n.volume, Coded), 6, rng, 300, 250);
  }
}

TEST(CodedFile, HeaderValuesThatDisagreeWithTheCodedVolumeFail)
{
  const Bytes good = svdag::serialize(spheres(ScalarType::UInt32, 30), Coded);
  const svdag::Volume v = svdag::deserialize(good);
  const std::vector<HeaderEdit> edits = {
    { "label count + 1", CountsAt + 8 * Labels, v.labels.size() + 1, 8 },
    { "label count - 1", CountsAt + 8 * Labels, v.labels.size() - 1, 8 },
    { "block count + 1", CountsAt + 8 * Blocks, v.blockCount + 1, 8 },
    { "block count - 1", CountsAt + 8 * Blocks, v.blockCount - 1, 8 },
    { "block count 2^40", CountsAt + 8 * Blocks, uint64_t(1) << 40, 8 },
    { "root count", CountsAt + 8 * Roots, v.rootCount + 1, 8 },
    { "mid count", CountsAt + 8 * Mids, v.midCount - 1, 8 },
    { "leaf count", CountsAt + 8 * Leaves, v.leaves.size() + 3, 8 },
    { "leaf width", WidthsAt + 16, v.widths.leafRefBits + 1, 4 },
    { "dims x", DimsAt, 200, 4 },
    { "dims x 2^31-1", DimsAt, 0x7FFFFFFF, 4 },
    { "dims z", DimsAt + 8, 5, 4 },
    { "scalar type int8", TypeAt, 0, 4 },
    { "background", TypeAt + 4, 7, 8 },
    { "coded section compressed", entryOf(good, 6) + Codec, 1, 4 },
  };
  expectHeaderEditsFail(good, edits);
  // A 3.0 file needs its coded section; format 2's sections do not stand in for it.
  Bytes noCoded = good;
  putLE(noCoded, entryOf(good, 6) + Id, 2, 4);
  resealHeader(noCoded);
  EXPECT_THROW(svdag::deserialize(noCoded), FileError);
  EXPECT_THROW(svdag::serialize(v, { 3, 5 }), FileError);
  EXPECT_THROW(svdag::serialize(v, { 3, 1 }), FileError);
}

TEST(CodedFile, HugeSparseVolumeStaysSmallAndFast)
{
  // 2^40 voxels, two small labelled boxes far apart: the empty cells between them cost a
  // number, not a bit each (64 chunks of a few bytes each, the two blocks and the table).
  svdag::Geometry g = geometry(1 << 14, 1 << 13, 1 << 13);
  svdag::Builder builder(g, ScalarType::UInt8);
  svdag::CellOccupancy a;
  a.value = 9;
  for (uint32_t l = 0; l < 64; ++l)
  {
    a.masks[l] = l == 0 ? 0x1ull : 0;
    a.codes[l] = 0;
  }
  a.codes[0] = uint8_t((svdag::canonicalLeaf(1).symmetry << 1) | svdag::canonicalLeaf(1).complement);
  builder.addBlock(5, a);
  svdag::CellOccupancy b = a;
  b.value = 200;
  builder.addBlock(uint32_t(g.cellCount() - 1), b);
  const svdag::Volume v = builder.finish();
  ASSERT_NO_THROW(v.validate());
  const Bytes bytes = svdag::serialize(v, Coded);
  EXPECT_EQ(svdag::coded::chunkCount(g), svdag::coded::MaxChunks);
  EXPECT_LT(bytes.size(), 2000u);
  const svdag::Volume back = svdag::deserialize(bytes);
  EXPECT_TRUE(back == v);
  EXPECT_EQ(back.labelAt(0, 0, 0), 0u);
  EXPECT_EQ(back.labelAt(80, 0, 0), 9u);
  EXPECT_EQ(back.labelAt(g.dims[0] - 16, g.dims[1] - 16, g.dims[2] - 16), 200u);
}

TEST(CodedFile, BuilderTakesBlocksOnlyInOrderAndAlone)
{
  const svdag::Geometry g = geometry(40, 20, 20);
  svdag::CellOccupancy block;
  block.value = 3;
  for (uint32_t l = 0; l < 64; ++l)
  {
    block.masks[l] = ~uint64_t(0);
    block.codes[l] = 0;
  }
  {
    svdag::Builder b(g, ScalarType::UInt16);
    b.addBlock(1, block);
    EXPECT_THROW(b.addBlock(0, block), std::logic_error);
    EXPECT_THROW(b.addBlock(1, block), std::logic_error); // the same label again
    block.value = 2;
    EXPECT_THROW(b.addBlock(1, block), std::logic_error); // a smaller label in the same cell
    block.value = 3;
    EXPECT_THROW(b.addBlock(uint32_t(g.cellCount()), block), std::logic_error);
    std::vector<uint16_t> slab(40 * 20 * 16, 0);
    EXPECT_THROW(b.addSlab(0, 16, slab.data()), std::logic_error);
    EXPECT_NO_THROW(b.finish().validate());
  }
  {
    svdag::Builder b(g, ScalarType::UInt16);
    std::vector<uint16_t> slab(40 * 20 * 16, 0);
    b.addSlab(0, 16, slab.data());
    EXPECT_THROW(b.addBlock(0, block), std::logic_error);
  }
}

// ---- format 4: the DAG streams (DagStreams.h) ----

TEST(StreamsFile, RoundTripIsExactDeterministicAndSmallerThanFormat2)
{
  for (const Named& n : codedVolumes())
  {
    SCOPED_TRACE(n.name);
    const Bytes bytes = svdag::serialize(n.volume);
    EXPECT_EQ(getLE(bytes, 8, 2), 4u);
    ASSERT_EQ(sectionCount(bytes), 1u);
    EXPECT_EQ(getLE(bytes, TableAt, 4), 7u);
    const svdag::Volume back = svdag::deserialize(bytes);
    // A built volume's DAG is in first-use order: decoded, with its bounds and label totals
    // derived, it is the same volume bit for bit.
    EXPECT_TRUE(back == n.volume);
    EXPECT_EQ(svdag::serialize(back), bytes);
    EXPECT_LE(bytes.size(), svdag::serialize(n.volume, { 19, 2 }).size() + 64);
  }
}

// A volume laid out otherwise is written in first-use order: the build's layout here.
TEST(StreamsFile, AVolumeInAnotherLayoutIsWrittenInFirstUseOrder)
{
  const svdag::Volume built = spheres(ScalarType::UInt16, 40);
  const svdag::Volume v = svdag::deserialize(svdag::serialize(built, Coded));
  ASSERT_TRUE(v == built);
  // The format 3 test above swaps two leaves by hand; here the root pool is reversed, which
  // also moves every offset a block refers to.
  const svdag::Volume pool = svdag::pooled(built); // as files hold it
  svdag::Volume reversed = pool;
  std::vector<uint64_t> starts;
  for (uint64_t offset = 0, n = 0; n < pool.rootCount; ++n)
  {
    starts.push_back(offset);
    offset += svdag::Volume::nodeBits(pool.roots, offset, pool.widths.midRefBits);
  }
  ASSERT_GE(starts.size(), 2u);
  std::fill(reversed.roots.begin(), reversed.roots.end(), 0u);
  std::vector<uint64_t> moved(starts.size());
  uint64_t at = 0;
  for (size_t k = starts.size(); k-- > 0;)
  {
    moved[k] = at;
    const uint64_t bits = svdag::Volume::nodeBits(pool.roots, starts[k], pool.widths.midRefBits);
    for (uint64_t b = 0; b < bits; ++b)
      if ((pool.roots[size_t((starts[k] + b) >> 5)] >> ((starts[k] + b) & 31)) & 1u)
        reversed.roots[size_t((at + b) >> 5)] |= 1u << ((at + b) & 31);
    at += bits;
  }
  reversed.widths.rootRefBits = 32;
  const uint64_t blockBits = reversed.blockCount * reversed.widths.blockBits();
  reversed.blocks.assign(size_t((blockBits + 31) / 32 + 1), 0u);
  for (uint64_t i = 0; i < pool.blockCount; ++i)
  {
    svdag::Block b = pool.block(i);
    const size_t k = size_t(std::lower_bound(starts.begin(), starts.end(),
      uint64_t(svdag::layout::refTarget(b.root))) - starts.begin());
    b.root = uint32_t((moved[k] << 1) | (b.root & 1u));
    setBlockCell(reversed, i, b.cell);
    setBlockBox(reversed, i, b);
    setBlockLabel(reversed, i, b.label);
    setBlockRoot(reversed, i, b.root);
  }
  ASSERT_NO_THROW(reversed.validate());
  ASSERT_FALSE(reversed == pool);
  const Bytes bytes = svdag::serialize(reversed);
  const svdag::Volume back = svdag::deserialize(bytes);
  EXPECT_EQ(svdag::coded::compareOccupancy(back, reversed), "");
  EXPECT_EQ(back.roots, built.roots);
  EXPECT_EQ(back.mids, built.mids);
  EXPECT_EQ(back.leaves, built.leaves);
  EXPECT_TRUE(back.widths == built.widths); // the compact form's widths follow its content
  EXPECT_EQ(svdag::serialize(back), svdag::serialize(built));
}

TEST(StreamsFile, EveryTruncationFails)
{
  const Bytes bytes = svdag::serialize(spheres(ScalarType::UInt16, 20));
  for (size_t n = 0; n < bytes.size(); ++n)
    EXPECT_THROW(svdag::deserialize(bytes.data(), n), FileError) << "prefix of " << n << " bytes";
}

// Corruption anywhere fails on a checksum; behind resealed checksums (a buggy or hostile
// writer), a corrupt section (its size table and zstd frames) fails cleanly or loads a valid
// volume, never a crash, a hang or a huge allocation. The streams' own bytes are edited in
// CorruptStreamsFailCleanly below.
TEST(StreamsFile, CorruptionFailsCleanly)
{
  std::mt19937_64 rng(23);
  const std::vector<Named> all = codedVolumes();
  for (const Named& n : { Named{ "spheres", spheres(ScalarType::UInt32, 30) }, all[all.size() - 4],
         all[all.size() - 2] })
  {
    SCOPED_TRACE(n.name);
    expectSectionCorruptionFailsCleanly(svdag::serialize(n.volume), 7, rng, 400, 300);
  }
}

namespace
{
// What a load makes of DAG streams: their volume, compacted, or the error. `decodersGraph`: the
// checks read the graph the decoder gives (as a file's load does), else a walk of the node
// streams the decoder wrote.
struct StreamsOutcome
{
  std::string error;
  svdag::Volume volume;
};
StreamsOutcome loadStreams(const svdag::dagstreams::Streams& streams,
  const svdag::dagstreams::Shape& shape, bool decodersGraph)
{
  StreamsOutcome out;
  try
  {
    svdag::PooledGraph graph;
    svdag::Volume back =
      svdag::dagstreams::decode(streams, shape, decodersGraph ? &graph : nullptr);
    back.deriveBoundsAndValidate(svdag::sequentialFor, &graph);
    out.volume = svdag::compacted(std::move(back), std::move(graph));
  }
  catch (const std::runtime_error& e)
  {
    out.error = e.what();
  }
  return out;
}
} // namespace

// The streams' bytes themselves, edited one at a time: every decision the decoder reads is
// checked (a wrong flag, index, symmetry, cell or label fails or gives a valid volume). The
// checks reach the same verdict on the decoder's graph as on a walk of the streams it wrote.
TEST(StreamsFile, CorruptStreamsFailCleanly)
{
  const svdag::Volume v = svdag::pooled(spheres(ScalarType::UInt16, 30)); // as files hold it
  const svdag::dagstreams::Encoded encoded = svdag::dagstreams::encode(v);
  std::mt19937_64 rng(29);
  size_t failed = 0, decoded = 0;
  for (uint32_t s = 0; s < svdag::dagstreams::StreamCount; ++s)
  {
    SCOPED_TRACE(svdag::dagstreams::streamName(s));
    ASSERT_FALSE(encoded.streams[s].empty() && s != svdag::dagstreams::RootIndices);
    for (int i = 0; i < 60 && !encoded.streams[s].empty(); ++i)
    {
      svdag::dagstreams::Streams bad = encoded.streams;
      std::vector<uint8_t>& stream = bad[s];
      switch (i % 4)
      {
        case 0: stream[rng() % stream.size()] ^= uint8_t(1u << (rng() % 8)); break;
        case 1: stream[rng() % stream.size()] = uint8_t(rng()); break;
        case 2: stream.pop_back(); break;
        default: stream.push_back(uint8_t(rng()));
      }
      const StreamsOutcome walked = loadStreams(bad, encoded.shape, false);
      const StreamsOutcome read = loadStreams(bad, encoded.shape, true);
      EXPECT_EQ(read.error, walked.error);
      EXPECT_TRUE(read.volume == walked.volume);
      if (walked.error.empty())
      {
        std::vector<uint8_t> out(size_t(walked.volume.geometry.voxelCount()) * 2);
        svdag::decode(walked.volume, out.data());
        ++decoded;
      }
      else
        ++failed;
    }
  }
  EXPECT_GT(failed, 4 * decoded);
  // Unchanged, they decode to the volume, either way.
  for (bool decodersGraph : { false, true })
  {
    const StreamsOutcome back = loadStreams(encoded.streams, encoded.shape, decodersGraph);
    EXPECT_EQ(back.error, "");
    EXPECT_TRUE(back.volume == svdag::compacted(v));
  }
}

namespace
{
// A 4.0 file whose DAG streams section holds `streams` uncompressed (as a writer stores a stream
// that zstd would not make smaller), checksums resealed: edits reach the decoder and the checks.
Bytes withStreams(const Bytes& good, const svdag::dagstreams::Streams& streams)
{
  Bytes section;
  for (const std::vector<uint8_t>& stream : streams)
  {
    svdag::bits::putVarint(section, stream.size()); // stored
    svdag::bits::putVarint(section, stream.size()); // raw
  }
  for (const std::vector<uint8_t>& stream : streams)
    section.insert(section.end(), stream.begin(), stream.end());
  Bytes b = good;
  const size_t e = entryOf(b, 7);
  const size_t at = size_t(getLE(b, e + Offset, 8));
  EXPECT_EQ(at + getLE(b, e + Stored, 8), b.size()) << "the streams section ends the file";
  b.resize(at);
  b.insert(b.end(), section.begin(), section.end());
  putLE(b, e + Stored, section.size(), 8);
  putLE(b, e + Raw, section.size(), 8);
  putLE(b, e + Crc, crc32(0, section.data(), uInt(section.size())), 4);
  resealHeader(b);
  return b;
}
} // namespace

// A small volume's load checks its blocks and cells beside its compaction (File.cpp): on two
// threads, edited streams load as they do in order, to the same volume or the same error.
TEST(StreamsFile, CorruptStreamsLoadAlikeInOrderAndOnThreads)
{
  std::mt19937 noise(41); // labels in slabs, some voxels flipped: blocks that meet in every cell
  const svdag::Volume v = svdag::pooled(build(ScalarType::UInt16, geometry(64, 48, 40),
    [&](int x, int y, int z) { return uint64_t((x / 5 + y / 7 + z / 3 + (noise() % 9 == 0)) % 40); }));
  const Bytes good = svdag::serialize(v);
  const svdag::dagstreams::Encoded encoded = svdag::dagstreams::encode(v);
  const Bytes asIs = withStreams(good, encoded.streams); // what the edits below load
  ASSERT_GE(getLE(asIs, entryOf(asIs, 7) + Stored, 8), 32768u)
    << "a smaller streams section loads on one thread (File.cpp: SplitLoadBytes)";
  ASSERT_TRUE(svdag::deserialize(withStreams(good, encoded.streams)) == svdag::deserialize(good));
  std::mt19937_64 rng(31);
  size_t failed = 0, loaded = 0, overlaps = 0;
  for (uint32_t s = 0; s < svdag::dagstreams::StreamCount; ++s)
  {
    SCOPED_TRACE(svdag::dagstreams::streamName(s));
    for (int i = 0; i < 40 && !encoded.streams[s].empty(); ++i)
    {
      svdag::dagstreams::Streams bad = encoded.streams;
      std::vector<uint8_t>& stream = bad[s];
      stream[rng() % stream.size()] ^= uint8_t(1u << (rng() % 8));
      const Bytes file = withStreams(good, bad);
      std::string inOrder, onTwo;
      svdag::Volume a, b;
      try
      {
        a = svdag::deserialize(file);
      }
      catch (const FileError& e)
      {
        inOrder = e.what();
      }
      try
      {
        b = svdag::deserialize(file.data(), file.size(), onThreads(2));
      }
      catch (const FileError& e)
      {
        onTwo = e.what();
      }
      EXPECT_EQ(onTwo, inOrder);
      if (inOrder.empty())
      {
        EXPECT_TRUE(a == b);
        ++loaded;
      }
      else
        ++failed;
      overlaps += inOrder.find("overlap") != std::string::npos;
    }
  }
  EXPECT_GT(failed, 100u);
  EXPECT_GT(overlaps, 0u) << "no edit reached the cell checks that run beside the compaction";

  // The streams' zstd frames, decompressed side by side: the first bad stream's error.
  const size_t e = entryOf(good, 7);
  const size_t at = size_t(getLE(good, e + Offset, 8)), size = size_t(getLE(good, e + Stored, 8));
  size_t frameErrors = 0;
  for (int i = 0; i < 200; ++i)
  {
    Bytes bad = good;
    for (int k = 0; k < 3; ++k) // three frames or three places in one
      bad[at + rng() % size] ^= uint8_t(1u << (rng() % 8));
    resealCoded(bad, 7);
    const std::string inOrder = loadError(bad, svdag::sequentialFor);
    EXPECT_EQ(loadError(bad, onThreads(3)), inOrder);
    frameErrors += inOrder.find("zstd") != std::string::npos;
  }
  EXPECT_GT(frameErrors, 20u);
  // Two broken frames: the error names the first of them on any schedule.
  const uint8_t* table = good.data() + at;
  const uint8_t* const end = good.data() + at + size;
  uint64_t stored[svdag::dagstreams::StreamCount], raw[svdag::dagstreams::StreamCount];
  for (uint32_t s = 0; s < svdag::dagstreams::StreamCount; ++s)
    ASSERT_TRUE(svdag::bits::getVarint(table, end, stored[s]) && svdag::bits::getVarint(table, end, raw[s]));
  std::vector<uint32_t> compressed; // streams held as zstd frames, and where each starts
  std::vector<size_t> frameAt;
  size_t offset = size_t(table - good.data());
  for (uint32_t s = 0; s < svdag::dagstreams::StreamCount; offset += size_t(stored[s]), ++s)
    if (stored[s] != raw[s])
    {
      compressed.push_back(s);
      frameAt.push_back(offset);
    }
  ASSERT_GE(compressed.size(), 3u);
  Bytes twoBad = good;
  for (size_t k : { size_t(1), compressed.size() - 1 })
    twoBad[frameAt[k]] ^= 0xFF; // the frame's magic number
  resealCoded(twoBad, 7);
  const std::string first = svdag::dagstreams::streamName(compressed[1]);
  for (const svdag::ParallelFor& parallel : { svdag::ParallelFor(svdag::sequentialFor), onThreads(3), onThreads(12) })
  {
    const std::string message = loadError(twoBad, parallel);
    EXPECT_NE(message.find(first + " stream is not a valid zstd frame"), std::string::npos) << message;
  }
}

// A graph handed to the checks (a decoder's) is checked against its volume too: no node, child
// or block it names can be outside its pool, and its nodes' children match their masks.
TEST(StreamsFile, AGraphThatDoesNotFitItsVolumeIsRefused)
{
  const svdag::Volume v = svdag::pooled(spheres(ScalarType::UInt16, 30));
  const svdag::dagstreams::Encoded encoded = svdag::dagstreams::encode(v);
  svdag::PooledGraph good;
  const svdag::Volume decoded = svdag::dagstreams::decode(encoded.streams, encoded.shape, &good);
  ASSERT_FALSE(good.mids.empty());
  ASSERT_FALSE(good.roots.empty());
  const uint32_t leaves = uint32_t(decoded.leaves.size());
  const std::vector<std::pair<std::string, std::function<void(svdag::PooledGraph&)>>> edits = {
    { "mid graph: a node's children do not match its masks",
      [](svdag::PooledGraph& g) { g.mids[0].count += 1; } },
    { "root graph: a node's children do not match its masks",
      [](svdag::PooledGraph& g) { g.roots.back().first += 1; } },
    { "mid graph does not hold the node count", [](svdag::PooledGraph& g) { g.mids.pop_back(); } },
    { "root graph: references beyond its nodes'",
      [](svdag::PooledGraph& g) { g.midRefs.push_back(0); } },
    { "the graph does not hold a root per block",
      [](svdag::PooledGraph& g) { g.blockRoots.pop_back(); } },
    { "mid node 0: child reference outside its pool",
      [&](svdag::PooledGraph& g) { g.leafRefs[0] = svdag::layout::leafRef(leaves, 0, 0); } },
    { "root node 0: child reference outside its pool",
      [](svdag::PooledGraph& g) { g.midRefs[0] = uint32_t(g.mids.size() << 1); } },
    { "block 0: root outside its pool",
      [](svdag::PooledGraph& g) { g.blockRoots[0] = uint32_t(g.roots.size() << 1); } },
  };
  for (const auto& edit : edits)
  {
    SCOPED_TRACE(edit.first);
    svdag::PooledGraph graph = good;
    edit.second(graph);
    svdag::Volume volume = decoded;
    try
    {
      volume.deriveBoundsAndValidate(svdag::sequentialFor, &graph);
      ADD_FAILURE() << "accepted";
    }
    catch (const std::runtime_error& e)
    {
      EXPECT_EQ(std::string(e.what()), "invalid SVDAG: " + edit.first);
    }
  }
  svdag::PooledGraph graph = good;
  svdag::Volume volume = decoded;
  volume.deriveBoundsAndValidate(svdag::sequentialFor, &graph);
  EXPECT_TRUE(svdag::compacted(std::move(volume), std::move(graph)) == svdag::compacted(v));
}

// deriveBoundsAndValidate's `alongside` runs once the graph and bounds are there, beside the
// last checks; their error comes first, its own otherwise.
TEST(StreamsFile, ChecksBesideATaskKeepTheirErrorFirst)
{
  const svdag::Volume v = svdag::pooled(spheres(ScalarType::UInt16, 30));
  svdag::Volume overlapping = v;
  uint64_t pair = 0;
  while (pair + 1 < v.blockCount && v.block(pair).cell != v.block(pair + 1).cell)
    ++pair;
  ASSERT_LT(pair + 1, v.blockCount) << "no cell with two blocks";
  setBlockRoot(overlapping, pair + 1, v.block(pair).root);
  auto error = [](svdag::Volume volume, const svdag::ParallelFor& parallel,
                 const std::function<void()>& alongside) -> std::string {
    try
    {
      svdag::PooledGraph graph;
      volume.deriveBoundsAndValidate(parallel, &graph, alongside);
    }
    catch (const std::runtime_error& e)
    {
      return e.what();
    }
    return "";
  };
  const auto fails = [] { throw std::runtime_error("beside"); };
  for (const svdag::ParallelFor& parallel : { svdag::ParallelFor(svdag::sequentialFor), onThreads(2) })
  {
    EXPECT_NE(error(overlapping, parallel, fails).find("overlap"), std::string::npos);
    EXPECT_EQ(error(overlapping, parallel, {}), error(overlapping, parallel, fails));
    EXPECT_EQ(error(v, parallel, fails), "beside");
    // What it sees: the graph complete, the blocks with their bounds.
    svdag::Volume checked = v, beside;
    svdag::PooledGraph graph;
    checked.deriveBoundsAndValidate(parallel, &graph, [&] { beside = svdag::compacted(checked, graph); });
    beside.labels = checked.labels;
    EXPECT_TRUE(beside == svdag::compacted(v));
  }
}

TEST(StreamsFile, HeaderValuesThatDisagreeWithTheStreamsFail)
{
  const Bytes good = svdag::serialize(spheres(ScalarType::UInt32, 30));
  const svdag::Volume v = svdag::deserialize(good);
  const std::vector<HeaderEdit> edits = {
    { "label count + 1", CountsAt + 8 * Labels, v.labels.size() + 1, 8 },
    { "label count - 1", CountsAt + 8 * Labels, v.labels.size() - 1, 8 },
    { "block count + 1", CountsAt + 8 * Blocks, v.blockCount + 1, 8 },
    { "block count - 1", CountsAt + 8 * Blocks, v.blockCount - 1, 8 },
    { "block count 2^40", CountsAt + 8 * Blocks, uint64_t(1) << 40, 8 },
    { "root count", CountsAt + 8 * Roots, v.rootCount + 1, 8 },
    { "mid count", CountsAt + 8 * Mids, v.midCount - 1, 8 },
    { "mid count 2^40", CountsAt + 8 * Mids, uint64_t(1) << 40, 8 },
    { "leaf count", CountsAt + 8 * Leaves, v.leaves.size() + 3, 8 },
    { "leaf width - 1", WidthsAt + 16, v.widths.leafRefBits - 1, 4 },
    { "root width 1", WidthsAt + 8, 1, 4 },
    { "dims x", DimsAt, 200, 4 },
    { "dims z", DimsAt + 8, 5, 4 },
    { "scalar type int8", TypeAt, 0, 4 },
    { "background", TypeAt + 4, 7, 8 },
    { "streams section compressed", entryOf(good, 7) + Codec, 1, 4 },
  };
  expectHeaderEditsFail(good, edits);
  // A 4.0 file needs its streams; a coded volume does not stand in for them, nor they for it.
  Bytes other = good;
  putLE(other, entryOf(good, 7) + Id, 6, 4);
  resealHeader(other);
  EXPECT_THROW(svdag::deserialize(other), FileError);
  other = good;
  putLE(other, 8, 3, 2);
  resealHeader(other);
  EXPECT_THROW(svdag::deserialize(other), FileError);
}

TEST(StreamsFile, VarintsRoundTripAndRefuseOverlongOrTruncatedNumbers)
{
  for (uint64_t v : { uint64_t(0), uint64_t(127), uint64_t(128), uint64_t(300), ~uint64_t(0),
         uint64_t(1) << 63, (uint64_t(1) << 56) - 1 })
  {
    std::vector<uint8_t> bytes;
    svdag::bits::putVarint(bytes, v);
    EXPECT_EQ(bytes.size(), size_t(v ? (64 - __builtin_clzll(v) + 6) / 7 : 1)) << v;
    const uint8_t* at = bytes.data();
    uint64_t back = 0;
    ASSERT_TRUE(svdag::bits::getVarint(at, bytes.data() + bytes.size(), back)) << v;
    EXPECT_EQ(back, v);
    EXPECT_EQ(at, bytes.data() + bytes.size());
    at = bytes.data(); // cut short by a byte
    EXPECT_FALSE(svdag::bits::getVarint(at, bytes.data() + bytes.size() - 1, back)) << v;
    EXPECT_EQ(at, bytes.data());
  }
  // 2^64 (bit 64 set in the tenth byte) and an eleventh byte.
  const std::vector<uint8_t> above = { 0x80, 0x80, 0x80, 0x80, 0x80, 0x80, 0x80, 0x80, 0x80, 0x02 };
  const std::vector<uint8_t> eleven = { 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0x81,
    0x00 };
  for (const auto* bytes : { &above, &eleven })
  {
    const uint8_t* at = bytes->data();
    uint64_t v = 0;
    EXPECT_FALSE(svdag::bits::getVarint(at, bytes->data() + bytes->size(), v));
  }
}
