#include "svdag_render/ComputeProgram.h"

#include "svdag_render/PipelineCacheFile.h"

#include <string>
#include <vector>

namespace svdag
{
namespace render
{

ComputeProgram::ComputeProgram(Context& context, const uint32_t* code, size_t bytes,
  const VkSpecializationInfo* specialization, const Interface& interface, const char* what)
  : Ctx(context)
{
  if (context.shared().hasShaderObjects())
    this->createShaderObject(code, bytes, specialization, interface, what);
  else
    this->createPipeline(code, bytes, specialization, interface, what);
}

ComputeProgram::~ComputeProgram()
{
  if (this->Shader)
    this->Ctx.fn().destroyShader(this->Ctx.device(), this->Shader, nullptr);
  if (this->Pipeline)
    vkDestroyPipeline(this->Ctx.device(), this->Pipeline, nullptr);
}

uint64_t ComputeProgram::hash(
  const uint32_t* code, size_t bytes, const VkSpecializationInfo* specialization)
{
  uint64_t h = fnv1a64(code, bytes);
  if (specialization)
  {
    for (uint32_t i = 0; i < specialization->mapEntryCount; ++i)
      h = fnv1a64(&specialization->pMapEntries[i], sizeof(VkSpecializationMapEntry), h);
    h = fnv1a64(specialization->pData, specialization->dataSize, h);
  }
  return h;
}

void ComputeProgram::createShaderObject(const uint32_t* code, size_t bytes,
  const VkSpecializationInfo* specialization, const Interface& interface, const char* what)
{
  Device& device = this->Ctx.shared();
  const DeviceFunctions& fn = this->Ctx.fn();
  VkShaderCreateInfoEXT info{ VK_STRUCTURE_TYPE_SHADER_CREATE_INFO_EXT };
  info.stage = VK_SHADER_STAGE_COMPUTE_BIT;
  info.pName = "main";
  info.setLayoutCount = interface.setLayoutCount;
  info.pSetLayouts = interface.setLayouts;
  info.pushConstantRangeCount = interface.pushConstantCount;
  info.pPushConstantRanges = interface.pushConstants;
  info.pSpecializationInfo = specialization;
  const uint64_t key = hash(code, bytes, specialization);
  std::string problem;
  const std::vector<uint8_t> binary = device.loadShaderBinary(key);
  if (!binary.empty())
  {
    info.codeType = VK_SHADER_CODE_TYPE_BINARY_EXT;
    info.codeSize = binary.size();
    info.pCode = binary.data();
    const VkResult result = fn.createShaders(this->Ctx.device(), 1, &info, nullptr, &this->Shader);
    if (result == VK_SUCCESS)
    {
      device.noteShaderCreated(true, "");
      return;
    }
    // Compiled again below, and the binary replaced.
    this->Shader = VK_NULL_HANDLE;
    problem = std::string("the driver refused the binary of ") + what + " (VkResult " +
      std::to_string(int(result)) + ")";
  }
  info.codeType = VK_SHADER_CODE_TYPE_SPIRV_EXT;
  info.codeSize = bytes;
  info.pCode = code;
  check(fn.createShaders(this->Ctx.device(), 1, &info, nullptr, &this->Shader), what);
  device.noteShaderCreated(false, problem);
  size_t size = 0;
  std::vector<uint8_t> compiled;
  if (fn.getShaderBinaryData(this->Ctx.device(), this->Shader, &size, nullptr) == VK_SUCCESS)
  {
    compiled.resize(size);
    if (fn.getShaderBinaryData(this->Ctx.device(), this->Shader, &size, compiled.data()) !=
      VK_SUCCESS)
      size = 0;
    compiled.resize(size);
  }
  device.saveShaderBinary(key, compiled);
}

void ComputeProgram::createPipeline(const uint32_t* code, size_t bytes,
  const VkSpecializationInfo* specialization, const Interface& interface, const char* what)
{
  VkDevice device = this->Ctx.device();
  VkShaderModuleCreateInfo module{ VK_STRUCTURE_TYPE_SHADER_MODULE_CREATE_INFO };
  module.codeSize = bytes;
  module.pCode = code;
  VkShaderModule shader = VK_NULL_HANDLE;
  check(vkCreateShaderModule(device, &module, nullptr, &shader), what);
  VkComputePipelineCreateInfo info{ VK_STRUCTURE_TYPE_COMPUTE_PIPELINE_CREATE_INFO };
  info.stage = VkPipelineShaderStageCreateInfo{ VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO };
  info.stage.stage = VK_SHADER_STAGE_COMPUTE_BIT;
  info.stage.module = shader;
  info.stage.pName = "main";
  info.stage.pSpecializationInfo = specialization;
  info.layout = interface.layout;
  const VkResult result = vkCreateComputePipelines(
    device, this->Ctx.shared().pipelineCache(), 1, &info, nullptr, &this->Pipeline);
  vkDestroyShaderModule(device, shader, nullptr);
  check(result, what);
}

void ComputeProgram::bind(VkCommandBuffer cmd) const
{
  if (this->Shader)
  {
    const VkShaderStageFlagBits stage = VK_SHADER_STAGE_COMPUTE_BIT;
    this->Ctx.fn().cmdBindShaders(cmd, 1, &stage, &this->Shader);
  }
  else
    vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, this->Pipeline);
}

} // namespace render
} // namespace svdag
