// The persistent pipeline cache's file and the shader binaries' files (PipelineCacheFile.h),
// without a device: what is saved loads back byte for byte, and every kind of bad file
// (truncated, extended, flipped bits in the header or the data, another key, a foreign driver
// header, the other kind of file, not a file at all) is ignored with a reason instead of reaching
// the driver.
#include <svdag_render/PipelineCacheFile.h>

#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <unistd.h>

namespace
{
using svdag::render::PipelineCacheKey;

PipelineCacheKey testKey()
{
  PipelineCacheKey key;
  key.vendorId = 0x10de;
  key.deviceId = 0x2335;
  key.driverVersion = 0x87654321;
  for (size_t i = 0; i < key.cacheUuid.size(); ++i)
    key.cacheUuid[i] = uint8_t(17 * i + 3);
  key.shaderHash = 0x0123456789abcdefull;
  return key;
}

void put32(std::vector<uint8_t>& v, size_t at, uint32_t x)
{
  for (int i = 0; i < 4; ++i)
    v[at + i] = uint8_t(x >> (8 * i));
}

// Driver data as Vulkan lays it out: VkPipelineCacheHeaderVersionOne, then the driver's payload.
std::vector<uint8_t> driverData(const PipelineCacheKey& key, size_t payload)
{
  std::vector<uint8_t> data(32 + payload);
  put32(data, 0, 32);
  put32(data, 4, 1); // VK_PIPELINE_CACHE_HEADER_VERSION_ONE
  put32(data, 8, key.vendorId);
  put32(data, 12, key.deviceId);
  std::copy(key.cacheUuid.begin(), key.cacheUuid.end(), data.begin() + 16);
  for (size_t i = 0; i < payload; ++i)
    data[32 + i] = uint8_t(i * 7 + 1);
  return data;
}

std::vector<uint8_t> readFile(const std::string& path)
{
  std::ifstream in(path, std::ios::binary);
  return std::vector<uint8_t>(std::istreambuf_iterator<char>(in), {});
}

void writeFile(const std::string& path, const std::vector<uint8_t>& bytes)
{
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char*>(bytes.data()), std::streamsize(bytes.size()));
}

class PipelineCacheFile : public ::testing::Test
{
protected:
  void SetUp() override
  {
    this->Directory = (std::filesystem::temp_directory_path() /
      ("svdag-pipeline-cache-" + std::to_string(::getpid()) + "-" +
        ::testing::UnitTest::GetInstance()->current_test_info()->name()))
                        .string();
    std::filesystem::remove_all(this->Directory);
    this->Path = svdag::render::pipelineCacheFileName(this->Directory, testKey());
  }
  void TearDown() override { std::filesystem::remove_all(this->Directory); }
  std::string Directory;
  std::string Path;
};
} // namespace

TEST_F(PipelineCacheFile, SavedDataLoadsBackExactly)
{
  const PipelineCacheKey key = testKey();
  const std::vector<uint8_t> data = driverData(key, 1000);
  std::string why;
  ASSERT_TRUE(svdag::render::savePipelineCache(this->Path, key, data, why)) << why;
  EXPECT_EQ(readFile(this->Path).size(), 64 + data.size());
  EXPECT_EQ(svdag::render::loadPipelineCache(this->Path, key, why), data);
  EXPECT_EQ(why, "");
  // No temporary file is left beside it.
  size_t files = 0;
  for (const auto& entry : std::filesystem::directory_iterator(this->Directory))
    files += entry.is_regular_file();
  EXPECT_EQ(files, 1u);
  // A save replaces the file.
  const std::vector<uint8_t> more = driverData(key, 3000);
  ASSERT_TRUE(svdag::render::savePipelineCache(this->Path, key, more, why)) << why;
  EXPECT_EQ(svdag::render::loadPipelineCache(this->Path, key, why), more);
}

TEST_F(PipelineCacheFile, AMissingFileIsNoProblem)
{
  std::string why = "stale";
  EXPECT_TRUE(svdag::render::loadPipelineCache(this->Path, testKey(), why).empty());
  EXPECT_EQ(why, "");
}

TEST_F(PipelineCacheFile, BadFilesAreIgnoredWithAReason)
{
  const PipelineCacheKey key = testKey();
  const std::vector<uint8_t> data = driverData(key, 200);
  std::string why;
  ASSERT_TRUE(svdag::render::savePipelineCache(this->Path, key, data, why)) << why;
  const std::vector<uint8_t> good = readFile(this->Path);

  struct Case
  {
    const char* what;
    std::vector<uint8_t> bytes;
    const char* reason;
  };
  std::vector<Case> cases;
  cases.push_back({ "empty", {}, "size" });
  cases.push_back({ "header only", std::vector<uint8_t>(good.begin(), good.begin() + 64),
    "truncated" });
  cases.push_back({ "truncated", std::vector<uint8_t>(good.begin(), good.end() - 1), "truncated" });
  std::vector<uint8_t> extended = good;
  extended.push_back(0);
  cases.push_back({ "extended", extended, "truncated" });
  std::vector<uint8_t> magic = good;
  magic[0] ^= 1;
  cases.push_back({ "magic", magic, "not a vtkSVDAG pipeline cache" });
  std::vector<uint8_t> version = good;
  version[8] = 99;
  cases.push_back({ "format version", version, "not a vtkSVDAG pipeline cache" });
  for (size_t at : { size_t(12), size_t(16), size_t(20), size_t(30), size_t(45) })
  {
    std::vector<uint8_t> key = good;
    key[at] ^= 0x40;
    cases.push_back({ "key byte", key, "another device" });
  }
  std::vector<uint8_t> size = good;
  size[48] ^= 1;
  cases.push_back({ "size field", size, "truncated" });
  std::vector<uint8_t> hugeSize = good;
  hugeSize[55] = 0x7f;
  cases.push_back({ "absurd size field", hugeSize, "truncated" });
  for (size_t at : { size_t(64), size_t(64 + 40), good.size() - 1 })
  {
    std::vector<uint8_t> flipped = good;
    flipped[at] ^= 0x80;
    cases.push_back({ "data bit", flipped, "checksum" });
  }
  std::vector<uint8_t> checksum = good;
  checksum[60] ^= 4;
  cases.push_back({ "checksum field", checksum, "checksum" });
  std::vector<uint8_t> garbage(5000);
  for (size_t i = 0; i < garbage.size(); ++i)
    garbage[i] = uint8_t((i * 2654435761u) >> 13);
  cases.push_back({ "garbage", garbage, "" });

  for (const Case& c : cases)
  {
    writeFile(this->Path, c.bytes);
    why.clear();
    EXPECT_TRUE(svdag::render::loadPipelineCache(this->Path, key, why).empty()) << c.what;
    EXPECT_NE(why, "") << c.what;
    EXPECT_NE(why.find(c.reason), std::string::npos) << c.what << ": " << why;
  }

  // Another build's shaders (the key in the file differs from the one asked for).
  ASSERT_TRUE(svdag::render::savePipelineCache(this->Path, key, data, why)) << why;
  PipelineCacheKey otherBuild = key;
  otherBuild.shaderHash ^= 1;
  EXPECT_TRUE(svdag::render::loadPipelineCache(this->Path, otherBuild, why).empty());
  EXPECT_NE(why.find("another device, driver or build"), std::string::npos) << why;

  // Sound file and checksum, but the driver data names another device (written by something
  // else than this device's driver): never handed to the driver.
  PipelineCacheKey other = key;
  other.deviceId += 1;
  ASSERT_TRUE(svdag::render::savePipelineCache(this->Path, key, driverData(other, 50), why));
  EXPECT_TRUE(svdag::render::loadPipelineCache(this->Path, key, why).empty());
  EXPECT_NE(why.find("driver's header"), std::string::npos) << why;
  std::vector<uint8_t> shortData(10, 1);
  ASSERT_TRUE(svdag::render::savePipelineCache(this->Path, key, shortData, why));
  EXPECT_TRUE(svdag::render::loadPipelineCache(this->Path, key, why).empty());
  EXPECT_NE(why.find("driver's header"), std::string::npos) << why;

  // A directory where the file should be.
  std::filesystem::remove(this->Path);
  std::filesystem::create_directories(this->Path);
  EXPECT_TRUE(svdag::render::loadPipelineCache(this->Path, key, why).empty());
  EXPECT_NE(why.find("not a regular file"), std::string::npos) << why;
  EXPECT_FALSE(svdag::render::savePipelineCache(this->Path, key, data, why));
  EXPECT_NE(why, "");
}

// Shader binaries: opaque driver data (no driver header to check), in files named and marked
// apart from the pipeline cache's, so that neither is ever read as the other.
TEST_F(PipelineCacheFile, ShaderBinariesLoadBackAndAreNeverTakenForACache)
{
  const PipelineCacheKey key = testKey();
  const std::string binaryPath = svdag::render::shaderBinaryFileName(this->Directory, key);
  EXPECT_NE(binaryPath, this->Path);
  EXPECT_EQ(std::filesystem::path(binaryPath).filename().string().rfind("shader-", 0), 0u)
    << binaryPath;
  std::vector<uint8_t> binary(777);
  for (size_t i = 0; i < binary.size(); ++i)
    binary[i] = uint8_t(i * 13 + 7);
  std::string why = "stale";
  EXPECT_TRUE(svdag::render::loadShaderBinary(binaryPath, key, why).empty());
  EXPECT_EQ(why, "") << "a missing binary is no problem";
  ASSERT_TRUE(svdag::render::saveShaderBinary(binaryPath, key, binary, why)) << why;
  EXPECT_EQ(svdag::render::loadShaderBinary(binaryPath, key, why), binary);
  EXPECT_EQ(why, "");
  const std::vector<uint8_t> goodBinary = readFile(binaryPath);

  // A pipeline cache where a binary is expected, and the other way round.
  const std::vector<uint8_t> cache = driverData(key, 100);
  ASSERT_TRUE(svdag::render::savePipelineCache(this->Path, key, cache, why)) << why;
  const std::vector<uint8_t> goodCache = readFile(this->Path);
  writeFile(binaryPath, goodCache);
  EXPECT_TRUE(svdag::render::loadShaderBinary(binaryPath, key, why).empty());
  EXPECT_NE(why.find("not a vtkSVDAG shader binary"), std::string::npos) << why;
  writeFile(this->Path, goodBinary);
  EXPECT_TRUE(svdag::render::loadPipelineCache(this->Path, key, why).empty());
  EXPECT_NE(why.find("not a vtkSVDAG pipeline cache"), std::string::npos) << why;

  // The checks of the shared form apply.
  std::vector<uint8_t> flipped = goodBinary;
  flipped[64 + 500] ^= 1;
  writeFile(binaryPath, flipped);
  EXPECT_TRUE(svdag::render::loadShaderBinary(binaryPath, key, why).empty());
  EXPECT_NE(why.find("checksum"), std::string::npos) << why;
  writeFile(binaryPath, std::vector<uint8_t>(goodBinary.begin(), goodBinary.end() - 3));
  EXPECT_TRUE(svdag::render::loadShaderBinary(binaryPath, key, why).empty());
  EXPECT_NE(why.find("truncated"), std::string::npos) << why;
  writeFile(binaryPath, goodBinary);
  PipelineCacheKey otherShader = key;
  otherShader.shaderHash += 1;
  EXPECT_TRUE(svdag::render::loadShaderBinary(binaryPath, otherShader, why).empty());
  EXPECT_NE(why.find("another device, driver or build"), std::string::npos) << why;
}

TEST_F(PipelineCacheFile, DirectoryFromTheEnvironment)
{
  const char* keep = std::getenv("VTKSVDAG_PIPELINE_CACHE");
  const std::string kept = keep ? keep : "";
  setenv("XDG_CACHE_HOME", "/some/where", 1);
  unsetenv("VTKSVDAG_PIPELINE_CACHE");
  EXPECT_EQ(svdag::render::pipelineCacheDirectory(), "/some/where/vtksvdag");
  unsetenv("XDG_CACHE_HOME");
  setenv("HOME", "/home/someone", 1);
  EXPECT_EQ(svdag::render::pipelineCacheDirectory(), "/home/someone/.cache/vtksvdag");
  for (const char* off : { "0", "off", "OFF", "false", "no" })
  {
    setenv("VTKSVDAG_PIPELINE_CACHE", off, 1);
    EXPECT_EQ(svdag::render::pipelineCacheDirectory(), "") << off;
  }
  setenv("VTKSVDAG_PIPELINE_CACHE", "1", 1);
  EXPECT_EQ(svdag::render::pipelineCacheDirectory(), "/home/someone/.cache/vtksvdag");
  if (keep)
    setenv("VTKSVDAG_PIPELINE_CACHE", kept.c_str(), 1);
  else
    unsetenv("VTKSVDAG_PIPELINE_CACHE");
  // Different keys, different files.
  PipelineCacheKey other = testKey();
  other.shaderHash += 1;
  EXPECT_NE(svdag::render::pipelineCacheFileName("/d", testKey()),
    svdag::render::pipelineCacheFileName("/d", other));
}
