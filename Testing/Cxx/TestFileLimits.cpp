// The .svdag format past 4 GiB, on procedurally generated volumes (BigVolume.h): a volume whose
// blocks section alone exceeds 4 GiB round-trips through writeFile / readFile uncompressed (the
// file, the stored sizes and the offsets of the sections after the blocks all pass 2^32) and
// through serialize / deserialize with zstd (a frame of more than 4 GiB each way). It needs about
// 10 GB of memory and 5 GB of disk in the test's temporary directory, and is skipped, naming what
// is missing, without them. A fast test checks the generator itself against its definition.
#include "BigVolume.h"

#include "CodedVolume.h"
#include "svdag/Decoder.h"
#include "svdag/Compact.h"
#include "svdag/File.h"

#include <gtest/gtest.h>

#include <sys/stat.h>
#include <sys/statvfs.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <string>

#if defined(__SANITIZE_ADDRESS__)
#define SVDAG_TEST_ASAN 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define SVDAG_TEST_ASAN 1
#endif
#endif

namespace
{
using bigvolume::availableMemory;
using bigvolume::Clock;
using bigvolume::secondsSince;

uint64_t freeDiskSpace(const std::string& dir)
{
  struct statvfs s;
  return statvfs(dir.c_str(), &s) == 0 ? uint64_t(s.f_bavail) * uint64_t(s.f_frsize) : 0;
}

// The largest single allocation AddressSanitizer allows (ASAN_OPTIONS max_allocation_size_mb;
// 0 or absent: no limit).
uint64_t sanitizerAllocationLimit()
{
  const char* options = std::getenv("ASAN_OPTIONS");
  const std::string key = "max_allocation_size_mb=";
  const std::string s = options ? options : "";
  const size_t at = s.find(key);
  if (at == std::string::npos)
    return UINT64_MAX;
  const uint64_t mib = std::strtoull(s.c_str() + at + key.size(), nullptr, 10);
  return mib == 0 ? UINT64_MAX : mib << 20;
}

// One section table entry of a file (File.h: id, codec, offset, stored size, raw size, crc).
struct Entry
{
  uint32_t codec = 0;
  uint64_t offset = 0, stored = 0, raw = 0;
};

// Removes a file (and writeFile's temporary) when the test ends, however it ends.
struct RemovedAtExit
{
  std::string path;
  ~RemovedAtExit()
  {
    std::remove(path.c_str());
    std::remove((path + ".partial").c_str());
  }
};

uint64_t le(const uint8_t* p, int n)
{
  uint64_t v = 0;
  for (int i = 0; i < n; ++i)
    v |= uint64_t(p[i]) << (8 * i);
  return v;
}

Entry entryOf(const uint8_t* header, uint32_t id)
{
  const uint32_t sections = uint32_t(le(header + 216, 4));
  for (uint32_t s = 0; s < sections; ++s)
  {
    const uint8_t* e = header + 220 + 36 * s;
    if (le(e, 4) == id)
      return { uint32_t(le(e + 4, 4)), le(e + 8, 8), le(e + 16, 8), le(e + 24, 8) };
  }
  ADD_FAILURE() << "no section " << id;
  return {};
}

// Independent definitions of the generator's shapes (cell-local voxel x, y, z in 0..15).
bool inMid0(int x, int y, int z) // the mid node of Notched, node-local 0..7
{
  const bool child1 = x >= 4 && y < 4 && z < 4;
  const bool leafCube = x >= 5 && x <= 6 && y >= 5 && y <= 6 && z >= 5 && z <= 6;
  return child1 || leafCube;
}
bool shapeHolds(uint32_t shape, int x, int y, int z)
{
  const bool highCube = x >= 8 && y >= 8 && z >= 8;
  const bool notched = (x < 8 && y >= 8 && z >= 8) || (x < 8 && y < 8 && z < 8 && inMid0(x, y, z));
  switch (shape)
  {
    case bigvolume::HighCube: return highCube;
    case bigvolume::AllButHighCube: return !highCube;
    case bigvolume::Notched: return notched;
    case bigvolume::NotchedInverse: return !notched;
    default: return highCube && !inMid0(x - 8, y - 8, z - 8);
  }
}
} // namespace

TEST(BigVolume, ValidatesAndHoldsWhatItsCellsSay)
{
  const uint64_t n = 100000;
  const uint32_t labels = 3;
  const svdag::Volume v = bigvolume::bigVolume(n, labels, 3);
  ASSERT_NO_THROW(v.validate());
  EXPECT_EQ(v.blockCount, n);
  const auto cells = bigvolume::cubicGrid(n);
  EXPECT_EQ(v.geometry.dims[0], 16 * cells[0]);
  EXPECT_EQ(v.widths.blockBits(), bigvolume::recordBits(cells, labels));
  // Each cell's voxels are its shape's, in its label: the first cell of every shape, and the
  // last cells; past the last block the cells are empty.
  std::vector<uint64_t> probes;
  std::vector<bool> seen(bigvolume::ShapeCount, false);
  for (uint64_t i = 0; probes.size() < bigvolume::ShapeCount && i < n; ++i)
  {
    const uint32_t shape = bigvolume::hashedBlock(i, labels).shape;
    if (!seen[shape])
      probes.push_back(i);
    seen[shape] = true;
  }
  ASSERT_EQ(probes.size(), size_t(bigvolume::ShapeCount));
  probes.insert(probes.end(), { n - 2, n - 1, n, n + 1 });
  for (uint64_t i : probes)
  {
    SCOPED_TRACE("cell " + std::to_string(i));
    const bigvolume::CellBlock c =
      i < n ? bigvolume::hashedBlock(i, labels) : bigvolume::CellBlock();
    const int32_t cx = int32_t(i % uint64_t(cells[0])), cy = int32_t(i / cells[0] % cells[1]),
                  cz = int32_t(i / (uint64_t(cells[0]) * cells[1]));
    size_t wrong = 0, solid = 0;
    for (int z = 0; z < 16; ++z)
      for (int y = 0; y < 16; ++y)
        for (int x = 0; x < 16; ++x)
        {
          const uint64_t expected = c.present && shapeHolds(c.shape, x, y, z) ? c.label + 1 : 0;
          wrong += v.labelAt(16 * cx + x, 16 * cy + y, 16 * cz + z) != expected;
          solid += expected != 0;
        }
    EXPECT_EQ(wrong, 0u);
    EXPECT_EQ(solid > 0, c.present);
  }
  // A loaded volume is compact (Compact.h); this hand-made one is pooled.
  const svdag::Volume compact = svdag::compacted(v);
  for (int level : { 0, 1 })
    EXPECT_TRUE(svdag::deserialize(svdag::serialize(v, { level, 2 })) == compact);
  // Format 3 rebuilds the DAG in a build's order, which this hand-made volume need not have.
  EXPECT_EQ(svdag::coded::compareOccupancy(v, svdag::deserialize(svdag::serialize(v))), "");
}

// What the two tests below need: 560M blocks of 63 bits with 3 labels (30 cell, 24 bounds,
// 2 label, 7 root bits): 4.41e9 bytes of blocks, past 2^32 by 0.1 GB, so the sections after the
// blocks start past 4 GiB too.
struct BigFileTest
{
  static constexpr uint64_t BlockCount = 560000000;
  static constexpr uint32_t Labels = 3;
  uint64_t blockBytes = 0;
  std::string dir = ::testing::TempDir();
  Clock::time_point t = Clock::now();

  // Empty if the machine can run the test, else what is missing.
  std::string missing(bool needsDisk)
  {
    const uint64_t bits = bigvolume::recordBits(bigvolume::cubicGrid(BlockCount), Labels);
    blockBytes = (BlockCount * bits + 31) / 32 * 4;
    // Two volumes at once (or one and the file's bytes), and the rest.
    const uint64_t memoryNeeded = 2 * blockBytes + (uint64_t(1) << 30);
    const uint64_t diskNeeded = blockBytes + (uint64_t(1) << 27);
    const uint64_t memory = availableMemory(), disk = freeDiskSpace(dir);
    if (memory < memoryNeeded)
      return "needs " + svdag::formatBytes(memoryNeeded) + " of available memory, " +
        "/proc/meminfo's MemAvailable says " + svdag::formatBytes(memory);
    if (needsDisk && disk < diskNeeded)
      return "needs " + svdag::formatBytes(diskNeeded) + " free in the temporary directory " + dir +
        ", which has " + svdag::formatBytes(disk);
#ifdef SVDAG_TEST_ASAN
    // The blocks are one allocation of more than 4 GiB (and zstd's output buffer another).
    const uint64_t limit = sanitizerAllocationLimit();
    if (limit < blockBytes)
      return "needs single allocations of " + svdag::formatBytes(blockBytes) +
        ", more than ASAN_OPTIONS max_allocation_size_mb allows (" + svdag::formatBytes(limit) +
        ")";
#endif
    return "";
  }
  std::unique_ptr<svdag::Volume> generate()
  {
    auto v = std::make_unique<svdag::Volume>(bigvolume::bigVolume(BlockCount, Labels));
    phase("generate");
    EXPECT_EQ(v->blockCount, BlockCount);
    EXPECT_EQ(v->memory().blocks, blockBytes);
    return v;
  }
  void phase(const char* what)
  {
    std::printf("[ phase    ] %-28s %7.1f s\n", what, secondsSince(t));
    std::fflush(stdout);
    t = Clock::now();
  }
};

// Uncompressed through a file: the file, the blocks section's stored and raw sizes and the
// offsets of the sections after it pass 2^32. Peak memory is about twice the blocks: the volume
// is dropped before the file is read back (the file's bytes and the loaded volume), and
// generated again to compare.
TEST(FileLimits, FileOver4GiBRoundTrips)
{
  BigFileTest test;
  const std::string missing = test.missing(true);
  if (!missing.empty())
    GTEST_SKIP() << missing;
  ASSERT_GT(test.blockBytes, uint64_t(1) << 32);
  const std::string path = test.dir + "/svdag_file_limits_" + std::to_string(::getpid()) + ".svdag";
  const RemovedAtExit removed{ path };

  auto volume = test.generate();
  svdag::writeFile(*volume, path, { 0, 2 });
  test.phase("writeFile (uncompressed)");
  struct stat info;
  ASSERT_EQ(::stat(path.c_str(), &info), 0);
  const svdag::MemoryUsage m = volume->memory();
  EXPECT_EQ(uint64_t(info.st_size),
    220 + 36 * 5 + 4 + 40 * BigFileTest::Labels + test.blockBytes + m.roots + m.mids + m.leaves);
  EXPECT_GT(uint64_t(info.st_size), uint64_t(1) << 32);
  {
    uint8_t header[404];
    std::ifstream in(path, std::ios::binary);
    ASSERT_TRUE(in.read(reinterpret_cast<char*>(header), sizeof header));
    const Entry blocks = entryOf(header, 2), roots = entryOf(header, 3);
    const Entry leaves = entryOf(header, 5);
    EXPECT_EQ(blocks.codec, 0u);
    EXPECT_EQ(blocks.stored, test.blockBytes);
    EXPECT_EQ(blocks.raw, test.blockBytes);
    EXPECT_GT(roots.offset, uint64_t(1) << 32);
    EXPECT_EQ(leaves.offset + leaves.stored, uint64_t(info.st_size));
  }

  volume.reset();
  const svdag::Volume loaded = svdag::readFile(path);
  test.phase("readFile (uncompressed)");
  std::remove(path.c_str());
  volume = test.generate();
  EXPECT_TRUE(loaded == svdag::compacted(std::move(*volume))) << "the file round trip changed the volume";
  test.phase("compare");
}

// zstd in memory: one frame of more than 4 GiB of raw bytes, compressed in one streaming pass and
// decompressed in place. Peak memory is about twice the blocks plus the compressed bytes.
TEST(FileLimits, ZstdSectionOver4GiBRoundTrips)
{
  BigFileTest test;
  const std::string missing = test.missing(false);
  if (!missing.empty())
    GTEST_SKIP() << missing;
  auto volume = test.generate();
  std::vector<uint8_t> bytes = svdag::serialize(*volume, { 1, 2 });
  test.phase("serialize (zstd 1)");
  ASSERT_GE(bytes.size(), 404u);
  const Entry blocks = entryOf(bytes.data(), 2);
  EXPECT_EQ(blocks.codec, 1u);
  EXPECT_EQ(blocks.raw, test.blockBytes);
  EXPECT_GT(blocks.raw, uint64_t(1) << 32);
  std::printf("[ info     ] zstd level 1: %s of blocks in %s\n",
    svdag::formatBytes(blocks.raw).c_str(), svdag::formatBytes(blocks.stored).c_str());

  volume.reset();
  const svdag::Volume back = svdag::deserialize(bytes);
  test.phase("deserialize (zstd 1)");
  std::vector<uint8_t>().swap(bytes); // (bytes = {} would keep the capacity)
  volume = test.generate();
  EXPECT_TRUE(back == svdag::compacted(std::move(*volume))) << "the zstd round trip changed the volume";
  test.phase("compare");
}
