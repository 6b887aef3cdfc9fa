// The device's Vulkan pipeline cache kept on disk between processes, so that a second process
// (or the same one after its device went) does not compile the pipelines again where the driver
// can reuse what its cache holds.
//
// Location: $XDG_CACHE_HOME/vtksvdag, else $HOME/.cache/vtksvdag; VTKSVDAG_PIPELINE_CACHE=0
// (or off/false/no) keeps the cache in memory only. One file per key (device, driver, and the
// hash of the path tracer's SPIR-V), so two builds or two GPUs never overwrite each other's file:
//   pipelines-<vendor>-<device>-<driver version>-<pipeline cache UUID>-<shader hash>.bin
//
// File: a header of our own (magic, format version, the key, the data's size and FNV-1a 64-bit
// checksum) and the driver's cache data. A file is used only when its header, key, size and
// checksum all match and the driver's own header (VkPipelineCacheHeaderVersionOne) names this
// device; anything else (truncated, corrupt, foreign, unreadable, a directory) is ignored with a
// reason, never handed to the driver, and replaced by the next save. Saves write a temporary
// file beside it and rename it, so a reader never sees half a file.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace svdag
{
namespace render
{

// What a cache file must have been written for.
struct PipelineCacheKey
{
  uint32_t vendorId = 0;
  uint32_t deviceId = 0;
  uint32_t driverVersion = 0;
  std::array<uint8_t, 16> cacheUuid{}; // VkPhysicalDeviceProperties::pipelineCacheUUID
  // Of the path tracer's SPIR-V modules (PipelineLibrary::shaderHash): a build with other
  // shaders writes a file of its own. The depth pass and the denoiser share the file; the driver
  // keys every pipeline in it by its own code anyway.
  uint64_t shaderHash = 0;
};

// FNV-1a, 64 bits (the shader hash and the data checksum).
uint64_t fnv1a64(const void* data, size_t bytes, uint64_t hash = 14695981039346656037ull);

// The cache directory from the environment ("" when disabled or when neither variable is set).
std::string pipelineCacheDirectory();
// The file of this key in `directory`.
std::string pipelineCacheFileName(const std::string& directory, const PipelineCacheKey& key);

// The driver's cache data stored in `path` for `key`; empty (with `why` saying what was wrong,
// "" for a file that does not exist) when there is none to trust.
std::vector<uint8_t> loadPipelineCache(
  const std::string& path, const PipelineCacheKey& key, std::string& why);
// Writes `data` for `key` to `path` (creating its directory). False, with `why`, on failure.
bool savePipelineCache(const std::string& path, const PipelineCacheKey& key,
  const std::vector<uint8_t>& data, std::string& why);

// Compute shader binaries (VK_EXT_shader_object; ComputeProgram.h) live beside it in files of the
// same form with a magic of their own, one per compiled shader:
//   shader-<vendor>-<device>-<driver version>-<shader binary UUID>-<shader hash>.bin
// where the key's cacheUuid is the device's shaderBinaryUUID and its shaderHash covers the
// SPIR-V, the specialization and the device's shaderBinaryVersion. The same checks apply but the
// driver's own header: the driver checks a binary itself, and one it refuses is compiled again.
std::string shaderBinaryFileName(const std::string& directory, const PipelineCacheKey& key);
std::vector<uint8_t> loadShaderBinary(
  const std::string& path, const PipelineCacheKey& key, std::string& why);
bool saveShaderBinary(const std::string& path, const PipelineCacheKey& key,
  const std::vector<uint8_t>& data, std::string& why);

} // namespace render
} // namespace svdag
