#include "svdag_render/PipelineCacheFile.h"

#include <atomic>
#include <cctype>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>

#include <unistd.h>

namespace svdag
{
namespace render
{

namespace
{

// A pipeline cache file and a shader binary file differ in their magic: neither is ever taken for
// the other.
enum class Kind
{
  PipelineCache,
  ShaderBinary
};
constexpr char Magic[8] = { 'V', 'T', 'K', 'S', 'V', 'D', 'A', 'G' };
constexpr char ShaderBinaryMagic[8] = { 'V', 'T', 'K', 'S', 'V', 'B', 'I', 'N' };
const char* magic(Kind kind)
{
  return kind == Kind::PipelineCache ? Magic : ShaderBinaryMagic;
}
constexpr uint32_t FormatVersion = 1;
// Magic (8 bytes), version (4), key (36: vendor, device, driver, UUID, shader hash), data size
// (8), checksum (8).
constexpr size_t HeaderBytes = 64;
constexpr size_t KeyOffset = 12, KeyBytes = 36, SizeOffset = 48, ChecksumOffset = 56;
// The driver's own header (VkPipelineCacheHeaderVersionOne): length, version, vendor, device,
// UUID.
constexpr size_t DriverHeaderBytes = 32;
// Far above any pipeline cache (lavapipe's and NVIDIA's are kilobytes to a few megabytes): a
// size field beyond it is corruption, not a cache to read.
constexpr uint64_t MaxDataBytes = uint64_t(1) << 30;

void put32(std::vector<uint8_t>& out, uint32_t v)
{
  for (int i = 0; i < 4; ++i)
    out.push_back(uint8_t(v >> (8 * i)));
}

void put64(std::vector<uint8_t>& out, uint64_t v)
{
  for (int i = 0; i < 8; ++i)
    out.push_back(uint8_t(v >> (8 * i)));
}

uint32_t get32(const uint8_t* p)
{
  uint32_t v = 0;
  for (int i = 0; i < 4; ++i)
    v |= uint32_t(p[i]) << (8 * i);
  return v;
}

uint64_t get64(const uint8_t* p)
{
  uint64_t v = 0;
  for (int i = 0; i < 8; ++i)
    v |= uint64_t(p[i]) << (8 * i);
  return v;
}

std::vector<uint8_t> header(
  Kind kind, const PipelineCacheKey& key, const std::vector<uint8_t>& data)
{
  std::vector<uint8_t> h(magic(kind), magic(kind) + sizeof(Magic));
  put32(h, FormatVersion);
  put32(h, key.vendorId);
  put32(h, key.deviceId);
  put32(h, key.driverVersion);
  h.insert(h.end(), key.cacheUuid.begin(), key.cacheUuid.end());
  put64(h, key.shaderHash);
  put64(h, data.size());
  put64(h, fnv1a64(data.data(), data.size()));
  return h;
}

std::string hex(const uint8_t* bytes, size_t n)
{
  static const char digits[] = "0123456789abcdef";
  std::string s;
  for (size_t i = 0; i < n; ++i)
  {
    s += digits[bytes[i] >> 4];
    s += digits[bytes[i] & 15];
  }
  return s;
}

bool disabled(const char* value)
{
  if (!value)
    return false;
  std::string v;
  for (const char* c = value; *c; ++c)
    v += char(std::tolower(static_cast<unsigned char>(*c)));
  return v == "0" || v == "off" || v == "false" || v == "no";
}

} // namespace

uint64_t fnv1a64(const void* data, size_t bytes, uint64_t hash)
{
  const uint8_t* p = static_cast<const uint8_t*>(data);
  for (size_t i = 0; i < bytes; ++i)
  {
    hash ^= p[i];
    hash *= 1099511628211ull;
  }
  return hash;
}

std::string pipelineCacheDirectory()
{
  if (disabled(std::getenv("VTKSVDAG_PIPELINE_CACHE")))
    return "";
  const char* xdg = std::getenv("XDG_CACHE_HOME");
  if (xdg && *xdg)
    return std::string(xdg) + "/vtksvdag";
  const char* home = std::getenv("HOME");
  if (home && *home)
    return std::string(home) + "/.cache/vtksvdag";
  return "";
}

namespace
{
std::string cacheFileName(
  const std::string& directory, const char* prefix, const PipelineCacheKey& key)
{
  char ids[64];
  std::snprintf(ids, sizeof(ids), "%08x-%08x-%08x-", key.vendorId, key.deviceId,
    key.driverVersion);
  uint8_t shader[8];
  for (int i = 0; i < 8; ++i)
    shader[i] = uint8_t(key.shaderHash >> (8 * (7 - i)));
  return directory + "/" + prefix + "-" + ids + hex(key.cacheUuid.data(), key.cacheUuid.size()) +
    "-" + hex(shader, sizeof(shader)) + ".bin";
}

// The data of a file of this kind and key, checked against our header (see the header file):
// true where one was read; false for a file that does not exist (`why` empty) or one not to
// trust (`why` says why).
bool loadCacheFile(Kind kind, const std::string& path, const PipelineCacheKey& key,
  std::vector<uint8_t>& data, std::string& why)
{
  why.clear();
  std::error_code error;
  const std::filesystem::file_status status = std::filesystem::status(path, error);
  if (error || status.type() == std::filesystem::file_type::not_found)
    return false;
  if (status.type() != std::filesystem::file_type::regular)
  {
    why = "not a regular file";
    return false;
  }
  const uintmax_t size = std::filesystem::file_size(path, error);
  if (error)
  {
    why = "its size cannot be read: " + error.message();
    return false;
  }
  if (size < HeaderBytes || size - HeaderBytes > MaxDataBytes)
  {
    why = "its size (" + std::to_string(size) + " bytes) is not that of a cache file";
    return false;
  }
  std::ifstream in(path, std::ios::binary);
  std::vector<uint8_t> bytes(size_t(size), 0);
  if (!in || !in.read(reinterpret_cast<char*>(bytes.data()), std::streamsize(size)))
  {
    why = "it cannot be read";
    return false;
  }
  data.assign(bytes.begin() + HeaderBytes, bytes.end());
  if (std::memcmp(bytes.data(), magic(kind), sizeof(Magic)) != 0 ||
    get32(bytes.data() + 8) != FormatVersion)
  {
    why = kind == Kind::PipelineCache ? "not a vtkSVDAG pipeline cache of this format"
                                      : "not a vtkSVDAG shader binary of this format";
    return false;
  }
  const std::vector<uint8_t> expected = header(kind, key, data);
  if (std::memcmp(bytes.data() + KeyOffset, expected.data() + KeyOffset, KeyBytes) != 0)
  {
    why = "written for another device, driver or build";
    return false;
  }
  if (get64(bytes.data() + SizeOffset) != data.size())
  {
    why = "truncated or extended (size field " + std::to_string(get64(bytes.data() + SizeOffset)) +
      ", data " + std::to_string(data.size()) + " bytes)";
    return false;
  }
  if (get64(bytes.data() + ChecksumOffset) != get64(expected.data() + ChecksumOffset))
  {
    why = "its checksum does not match its data";
    return false;
  }
  return true;
}

bool saveCacheFile(Kind kind, const std::string& path, const PipelineCacheKey& key,
  const std::vector<uint8_t>& data, std::string& why)
{
  why.clear();
  std::error_code error;
  const std::filesystem::path target(path);
  std::filesystem::create_directories(target.parent_path(), error);
  if (error)
  {
    why = "cannot create " + target.parent_path().string() + ": " + error.message();
    return false;
  }
  static std::atomic<unsigned> counter{ 0 };
  const std::string temporary =
    path + ".tmp." + std::to_string(::getpid()) + "." + std::to_string(counter++);
  {
    std::ofstream out(temporary, std::ios::binary | std::ios::trunc);
    const std::vector<uint8_t> h = header(kind, key, data);
    out.write(reinterpret_cast<const char*>(h.data()), std::streamsize(h.size()));
    out.write(reinterpret_cast<const char*>(data.data()), std::streamsize(data.size()));
    out.close();
    if (!out)
    {
      std::filesystem::remove(temporary, error);
      why = "cannot write " + temporary;
      return false;
    }
  }
  std::filesystem::rename(temporary, target, error);
  if (error)
  {
    std::filesystem::remove(temporary, error);
    why = "cannot replace " + path;
    return false;
  }
  return true;
}
} // namespace

std::string pipelineCacheFileName(const std::string& directory, const PipelineCacheKey& key)
{
  return cacheFileName(directory, "pipelines", key);
}

std::string shaderBinaryFileName(const std::string& directory, const PipelineCacheKey& key)
{
  return cacheFileName(directory, "shader", key);
}

std::vector<uint8_t> loadPipelineCache(
  const std::string& path, const PipelineCacheKey& key, std::string& why)
{
  std::vector<uint8_t> data;
  if (!loadCacheFile(Kind::PipelineCache, path, key, data, why))
    return {};
  // The driver's header must name this device too (the driver would reject it anyway; a file
  // that passes the checksum but not this was written by something else).
  if (data.size() < DriverHeaderBytes || get32(data.data()) < DriverHeaderBytes ||
    get32(data.data() + 4) != 1u || get32(data.data() + 8) != key.vendorId ||
    get32(data.data() + 12) != key.deviceId ||
    std::memcmp(data.data() + 16, key.cacheUuid.data(), 16) != 0)
  {
    why = "the driver's header inside does not name this device";
    return {};
  }
  return data;
}

bool savePipelineCache(const std::string& path, const PipelineCacheKey& key,
  const std::vector<uint8_t>& data, std::string& why)
{
  return saveCacheFile(Kind::PipelineCache, path, key, data, why);
}

std::vector<uint8_t> loadShaderBinary(
  const std::string& path, const PipelineCacheKey& key, std::string& why)
{
  std::vector<uint8_t> data;
  if (!loadCacheFile(Kind::ShaderBinary, path, key, data, why))
    return {};
  return data;
}

bool saveShaderBinary(const std::string& path, const PipelineCacheKey& key,
  const std::vector<uint8_t>& data, std::string& why)
{
  return saveCacheFile(Kind::ShaderBinary, path, key, data, why);
}

} // namespace render
} // namespace svdag
