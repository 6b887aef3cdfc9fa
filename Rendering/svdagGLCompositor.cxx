#include "svdagGLCompositor.h"

#include "vtkOpenGLError.h"
#include "vtkOpenGLQuadHelper.h"
#include "vtkOpenGLRenderUtilities.h"
#include "vtkOpenGLRenderWindow.h"
#include "vtkOpenGLShaderCache.h"
#include "vtkOpenGLState.h"
#include "vtkShaderProgram.h"
#include "vtkSmartPointer.h"
#include "vtkTextureObject.h"
#include "vtkTextureUnitManager.h"
#include "vtk_glew.h"

#include <cstring>
#include <stdexcept>
#include <string>

#include <unistd.h>

namespace svdag
{
namespace gl
{
namespace
{
// Tone curve and sRGB encoding as the core renderer's color output (GpuLayout.h), applied to the
// un-premultiplied color; the result is premultiplied again for the blend.
const char* const FragmentShader = R"(//VTK::System::Dec
//VTK::Output::Dec
in vec2 texCoord;
uniform samplerBuffer colorBuffer; // colorSize.x * colorSize.y texels, rows from the bottom
uniform ivec2 colorSize;
uniform vec4 viewport; // x, y, width, height in window pixels
uniform sampler2D depthTexture;
uniform float exposure;
uniform int writeDepth;
float srgbEncode(float linear)
{
  float c = clamp(linear, 0.0, 1.0);
  return c <= 0.0031308 ? 12.92 * c : 1.055 * pow(c, 1.0 / 2.4) - 0.055;
}
vec4 texel(ivec2 p)
{
  p = clamp(p, ivec2(0), colorSize - ivec2(1));
  return texelFetch(colorBuffer, p.x + colorSize.x * p.y);
}
// Bilinear with clamped edges (a reduced image scaled up), from the exact fragment position: at
// full size every weight is 0 or 1, so each pixel is its traced texel exactly.
vec4 tracedColor()
{
  vec2 p = (gl_FragCoord.xy - viewport.xy) * vec2(colorSize) / viewport.zw - vec2(0.5);
  vec2 i = floor(p);
  vec2 f = p - i;
  ivec2 c = ivec2(i);
  vec4 bottom = mix(texel(c), texel(c + ivec2(1, 0)), f.x);
  vec4 top = mix(texel(c + ivec2(0, 1)), texel(c + ivec2(1, 1)), f.x);
  return mix(bottom, top, f.y);
}
void main()
{
  vec4 hdr = tracedColor();
  float depth = texture(depthTexture, texCoord).r;
  // A pixel whose samples all missed may still hold the center ray's hit (a silhouette): its
  // depth is written, with no color.
  if (hdr.a <= 0.0 && (writeDepth == 0 || depth >= 1.0))
    discard;
  vec3 x = max(hdr.rgb / max(hdr.a, 1.0e-30) * exposure, vec3(0.0));
  x = x / (vec3(1.0) + x);
  float alpha = min(hdr.a, 1.0);
  gl_FragData[0] = vec4(srgbEncode(x.r) * alpha, srgbEncode(x.g) * alpha, srgbEncode(x.b) * alpha, alpha);
  gl_FragDepth = writeDepth != 0 ? depth : gl_FragCoord.z;
}
)";

// The depth format of the attachment a framebuffer reads from, for a resolve target that blits.
GLenum depthFormatOf(GLuint framebuffer)
{
  const GLenum attachment = framebuffer == 0 ? GL_DEPTH : GL_DEPTH_ATTACHMENT;
  GLint bits = 0, stencil = 0, type = 0;
  glGetFramebufferAttachmentParameteriv(
    GL_READ_FRAMEBUFFER, attachment, GL_FRAMEBUFFER_ATTACHMENT_DEPTH_SIZE, &bits);
  glGetFramebufferAttachmentParameteriv(GL_READ_FRAMEBUFFER,
    framebuffer == 0 ? GL_STENCIL : GL_DEPTH_ATTACHMENT, GL_FRAMEBUFFER_ATTACHMENT_STENCIL_SIZE,
    &stencil);
  glGetFramebufferAttachmentParameteriv(
    GL_READ_FRAMEBUFFER, attachment, GL_FRAMEBUFFER_ATTACHMENT_COMPONENT_TYPE, &type);
  if (type == GL_FLOAT)
    return stencil > 0 ? GL_DEPTH32F_STENCIL8 : GL_DEPTH_COMPONENT32F;
  if (stencil > 0)
    return GL_DEPTH24_STENCIL8;
  return bits >= 32 ? GL_DEPTH_COMPONENT32 : (bits == 16 ? GL_DEPTH_COMPONENT16 : GL_DEPTH_COMPONENT24);
}

// A Vulkan buffer imported as an OpenGL buffer object of `bytes` bytes (GL_EXT_memory_object_fd),
// the allocation `generation`.
struct Import
{
  GLuint memory = 0;
  GLuint buffer = 0;
  uint64_t generation = 0;

  void release()
  {
    if (this->buffer)
      glDeleteBuffers(1, &this->buffer);
    if (this->memory)
      glDeleteMemoryObjectsEXT(1, &this->memory);
    this->buffer = this->memory = 0;
    this->generation = 0;
  }
  // The buffer object of `shared` (imported now unless it is the allocation imported last),
  // created on `target`, the binding point it is used at (a driver may choose how it keeps a
  // buffer from the first one). `what` names the data in messages.
  GLuint of(const SharedBuffer& shared, GLenum target, size_t bytes, const char* what)
  {
    if (this->buffer && this->generation == shared.generation)
      return this->buffer;
    this->release();
    vtkOpenGLClearErrorMacro();
    const render::ExportedMemory memory = shared.exportMemory();
    glCreateMemoryObjectsEXT(1, &this->memory);
    if (memory.dedicated)
    {
      const GLint yes = GL_TRUE;
      glMemoryObjectParameterivEXT(this->memory, GL_DEDICATED_MEMORY_OBJECT_EXT, &yes);
    }
    // On success OpenGL owns the descriptor; on failure it is still ours to close.
    glImportMemoryFdEXT(this->memory, GLuint64(memory.bytes), GL_HANDLE_TYPE_OPAQUE_FD_EXT, memory.fd);
    GLenum error = glGetError();
    if (error != GL_NO_ERROR)
    {
      close(memory.fd);
      this->release();
      throw std::runtime_error(std::string("importing the Vulkan memory of the ") + what +
        " into OpenGL failed (OpenGL error " + std::to_string(error) + ")");
    }
    glGenBuffers(1, &this->buffer);
    glBindBuffer(target, this->buffer);
    glBufferStorageMemEXT(target, GLsizeiptr(bytes), this->memory, 0);
    glBindBuffer(target, 0);
    error = glGetError();
    if (error != GL_NO_ERROR)
    {
      this->release();
      throw std::runtime_error(std::string("a buffer on the imported Vulkan memory of the ") +
        what + " failed (OpenGL error " + std::to_string(error) + ")");
    }
    this->generation = shared.generation;
    return this->buffer;
  }
};

// Waits for a fence and deletes it: flushes on the first wait, so the fence is reached; a second
// a round, never forever (a lost context reports failure).
void waitAndDelete(GLsync& fence)
{
  if (!fence)
    return;
  GLbitfield flags = GL_SYNC_FLUSH_COMMANDS_BIT;
  for (;;)
  {
    const GLenum result = glClientWaitSync(fence, flags, GLuint64(1000000000));
    flags = 0;
    if (result != GL_TIMEOUT_EXPIRED)
      break;
  }
  glDeleteSync(fence);
  fence = nullptr;
}
} // namespace

struct Compositor::Internals
{
  std::unique_ptr<vtkOpenGLQuadHelper> Quad;
  vtkSmartPointer<vtkTextureObject> Depth;
  // The color as a texture buffer over one of two buffers: HostColor (uploaded each frame) or
  // SharedColor (Vulkan's memory). The shared path's depth: the scene depth slots read into and
  // the composited depth uploaded from. SharedReads: the fence after the last shared draw.
  GLuint ColorTexture = 0;
  GLuint HostColor = 0;
  Import SharedColor;
  Import SceneDepth[2];
  Import CompositedDepth;
  GLsync SharedReads = nullptr;
  // canImport's answer for the window it was asked for (-1: not asked).
  vtkOpenGLRenderWindow* ImportWindow = nullptr;
  int Importable = -1;

  void releaseShared()
  {
    if (this->SharedReads)
      glDeleteSync(this->SharedReads);
    this->SharedReads = nullptr;
    this->SharedColor.release();
    this->SceneDepth[0].release();
    this->SceneDepth[1].release();
    this->CompositedDepth.release();
  }
  // The MSAA resolve target: a framebuffer with one depth renderbuffer.
  GLuint ResolveFramebuffer = 0;
  GLuint ResolveDepth = 0;
  int ResolveWidth = 0, ResolveHeight = 0;
  GLenum ResolveFormat = 0;

  void releaseResolve()
  {
    if (this->ResolveFramebuffer)
      glDeleteFramebuffers(1, &this->ResolveFramebuffer);
    if (this->ResolveDepth)
      glDeleteRenderbuffers(1, &this->ResolveDepth);
    this->ResolveFramebuffer = this->ResolveDepth = 0;
    this->ResolveWidth = this->ResolveHeight = 0;
  }
};

Compositor::Compositor()
  : Internal(new Internals)
{
}

Compositor::~Compositor() = default;

bool Compositor::canImport(vtkOpenGLRenderWindow* window, const render::DeviceUuids& uuids)
{
  Internals& in = *this->Internal;
  if (in.ImportWindow == window && in.Importable >= 0)
    return in.Importable == 1;
  in.ImportWindow = window;
  in.Importable = 0;
  vtkOpenGLClearErrorMacro();
  bool memoryObject = false, memoryObjectFd = false;
  GLint extensions = 0;
  glGetIntegerv(GL_NUM_EXTENSIONS, &extensions);
  for (GLint i = 0; i < extensions; ++i)
  {
    const char* name = reinterpret_cast<const char*>(glGetStringi(GL_EXTENSIONS, GLuint(i)));
    memoryObject = memoryObject || (name && std::strcmp(name, "GL_EXT_memory_object") == 0);
    memoryObjectFd = memoryObjectFd || (name && std::strcmp(name, "GL_EXT_memory_object_fd") == 0);
  }
  // The entry points too: GLEW loads them only where the context listed the extensions.
  if (!memoryObject || !memoryObjectFd || !glCreateMemoryObjectsEXT || !glImportMemoryFdEXT ||
    !glBufferStorageMemEXT || !glDeleteMemoryObjectsEXT || !glGetUnsignedBytevEXT ||
    !glGetUnsignedBytei_vEXT)
    return false;
  GLubyte uuid[GL_UUID_SIZE_EXT];
  glGetUnsignedBytevEXT(GL_DRIVER_UUID_EXT, uuid);
  bool sameDriver = std::memcmp(uuid, uuids.driver.data(), GL_UUID_SIZE_EXT) == 0;
  bool sameDevice = false;
  GLint devices = 0;
  glGetIntegerv(GL_NUM_DEVICE_UUIDS_EXT, &devices);
  for (GLint i = 0; i < devices; ++i)
  {
    glGetUnsignedBytei_vEXT(GL_DEVICE_UUID_EXT, GLuint(i), uuid);
    sameDevice = sameDevice || std::memcmp(uuid, uuids.device.data(), GL_UUID_SIZE_EXT) == 0;
  }
  if (glGetError() != GL_NO_ERROR)
    return false;
  in.Importable = sameDriver && sameDevice ? 1 : 0;
  return in.Importable == 1;
}

Viewport Compositor::currentViewport(vtkOpenGLRenderWindow* window)
{
  int v[4] = { 0, 0, 0, 0 };
  window->GetState()->vtkglGetIntegerv(GL_VIEWPORT, v);
  return Viewport{ v[0], v[1], v[2], v[3] };
}

std::vector<float> Compositor::readDepth(vtkOpenGLRenderWindow* window, const Viewport& vp)
{
  std::vector<float> depth(size_t(vp.width) * size_t(vp.height), 1.0f);
  this->readDepthInto(window, vp, depth.data());
  return depth;
}

void Compositor::readDepthShared(
  vtkOpenGLRenderWindow* window, const Viewport& vp, int slot, const SharedBuffer& depth)
{
  Internals& in = *this->Internal;
  const GLuint buffer = in.SceneDepth[slot & 1].of(depth, GL_PIXEL_PACK_BUFFER,
    size_t(vp.width) * size_t(vp.height) * sizeof(float), "scene depth");
  // glReadPixels writes into the bound pack buffer, at offset 0 (the null pointer): no host copy.
  glBindBuffer(GL_PIXEL_PACK_BUFFER, buffer);
  try
  {
    this->readDepthInto(window, vp, nullptr);
  }
  catch (...)
  {
    glBindBuffer(GL_PIXEL_PACK_BUFFER, 0);
    throw;
  }
  glBindBuffer(GL_PIXEL_PACK_BUFFER, 0);
  // Vulkan and the host read it next.
  GLsync written = glFenceSync(GL_SYNC_GPU_COMMANDS_COMPLETE, 0);
  waitAndDelete(written);
}

void Compositor::readDepthInto(vtkOpenGLRenderWindow* window, const Viewport& vp, float* pixels)
{
  Internals& in = *this->Internal;
  vtkOpenGLState* state = window->GetState();
  vtkOpenGLClearErrorMacro();
  GLint drawFramebuffer = 0, samples = 0;
  glGetIntegerv(GL_DRAW_FRAMEBUFFER_BINDING, &drawFramebuffer);
  state->PushFramebufferBindings();
  state->vtkglBindFramebuffer(GL_READ_FRAMEBUFFER, GLuint(drawFramebuffer));
  glGetIntegerv(GL_SAMPLES, &samples);
  int x = vp.x, y = vp.y;
  if (samples > 0)
  {
    // A multisampled depth buffer cannot be read: resolve it by a blit into a single-sample
    // buffer of the same format and the same rectangle (both required by glBlitFramebuffer).
    const GLenum format = depthFormatOf(GLuint(drawFramebuffer));
    const int width = vp.x + vp.width, height = vp.y + vp.height;
    if (!in.ResolveFramebuffer || in.ResolveWidth < width || in.ResolveHeight < height ||
      in.ResolveFormat != format)
    {
      in.releaseResolve();
      glGenFramebuffers(1, &in.ResolveFramebuffer);
      glGenRenderbuffers(1, &in.ResolveDepth);
      glBindRenderbuffer(GL_RENDERBUFFER, in.ResolveDepth);
      glRenderbufferStorage(GL_RENDERBUFFER, format, width, height);
      state->vtkglBindFramebuffer(GL_DRAW_FRAMEBUFFER, in.ResolveFramebuffer);
      const bool withStencil = format == GL_DEPTH24_STENCIL8 || format == GL_DEPTH32F_STENCIL8;
      glFramebufferRenderbuffer(GL_DRAW_FRAMEBUFFER,
        withStencil ? GL_DEPTH_STENCIL_ATTACHMENT : GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER,
        in.ResolveDepth);
      in.ResolveWidth = width;
      in.ResolveHeight = height;
      in.ResolveFormat = format;
    }
    state->vtkglBindFramebuffer(GL_DRAW_FRAMEBUFFER, in.ResolveFramebuffer);
    glBlitFramebuffer(vp.x, vp.y, width, height, vp.x, vp.y, width, height, GL_DEPTH_BUFFER_BIT,
      GL_NEAREST);
    state->vtkglBindFramebuffer(GL_READ_FRAMEBUFFER, in.ResolveFramebuffer);
  }
  state->vtkglPixelStorei(GL_PACK_ALIGNMENT, 4);
  glReadPixels(x, y, vp.width, vp.height, GL_DEPTH_COMPONENT, GL_FLOAT, pixels);
  const GLenum error = glGetError();
  state->PopFramebufferBindings();
  if (error != GL_NO_ERROR)
    throw std::runtime_error("reading the depth buffer failed (OpenGL error " +
      std::to_string(error) + ")");
}

void Compositor::draw(vtkOpenGLRenderWindow* window, const Viewport& vp, const float* rgba,
  int colorWidth, int colorHeight, const std::vector<float>& depth, float exposure)
{
  Internals& in = *this->Internal;
  vtkOpenGLClearErrorMacro();
  if (!in.HostColor)
    glGenBuffers(1, &in.HostColor);
  glBindBuffer(GL_TEXTURE_BUFFER, in.HostColor);
  glBufferData(GL_TEXTURE_BUFFER, GLsizeiptr(size_t(colorWidth) * size_t(colorHeight) * 4 * sizeof(float)),
    rgba, GL_STREAM_DRAW);
  glBindBuffer(GL_TEXTURE_BUFFER, 0);
  if (glGetError() != GL_NO_ERROR)
    throw std::runtime_error("uploading the traced image to OpenGL failed");
  this->drawColor(window, vp, in.HostColor, colorWidth, colorHeight,
    depth.empty() ? nullptr : depth.data(), 0, exposure);
}

void Compositor::drawShared(vtkOpenGLRenderWindow* window, const Viewport& vp,
  const SharedBuffer& color, int colorWidth, int colorHeight, const std::vector<float>& depth,
  float exposure)
{
  this->drawSharedColor(window, vp, color, colorWidth, colorHeight,
    depth.empty() ? nullptr : depth.data(), nullptr, exposure);
}

void Compositor::drawShared(vtkOpenGLRenderWindow* window, const Viewport& vp,
  const SharedBuffer& color, int colorWidth, int colorHeight, const SharedBuffer& depth,
  float exposure)
{
  this->drawSharedColor(window, vp, color, colorWidth, colorHeight, nullptr, &depth, exposure);
}

void Compositor::drawSharedColor(vtkOpenGLRenderWindow* window, const Viewport& vp,
  const SharedBuffer& color, int colorWidth, int colorHeight, const float* depth,
  const SharedBuffer* sharedDepth, float exposure)
{
  Internals& in = *this->Internal;
  const GLuint colorBuffer = in.SharedColor.of(color, GL_TEXTURE_BUFFER,
    size_t(colorWidth) * size_t(colorHeight) * 4 * sizeof(float), "traced image");
  const GLuint depthBuffer = sharedDepth
    ? in.CompositedDepth.of(*sharedDepth, GL_PIXEL_UNPACK_BUFFER, size_t(vp.width) * size_t(vp.height) * sizeof(float),
        "composited depth")
    : 0;
  this->waitForSharedReads(); // a fence of an earlier draw, if any, is replaced below
  this->drawColor(window, vp, colorBuffer, colorWidth, colorHeight, depth, depthBuffer, exposure);
  in.SharedReads = glFenceSync(GL_SYNC_GPU_COMMANDS_COMPLETE, 0);
}

void Compositor::waitForSharedReads()
{
  waitAndDelete(this->Internal->SharedReads);
}

void Compositor::drawColor(vtkOpenGLRenderWindow* window, const Viewport& vp, unsigned int buffer,
  int colorWidth, int colorHeight, const float* depth, unsigned int depthBuffer, float exposure)
{
  Internals& in = *this->Internal;
  vtkOpenGLState* state = window->GetState();
  if (!in.Depth)
    in.Depth = vtkSmartPointer<vtkTextureObject>::New();
  in.Depth->SetContext(window);
  // Depth nearest: it must not blend across silhouettes (the color is filtered in the shader).
  const bool writeDepth = depth || depthBuffer;
  const float one = 1.0f;
  in.Depth->SetMinificationFilter(vtkTextureObject::Nearest);
  in.Depth->SetMagnificationFilter(vtkTextureObject::Nearest);
  in.Depth->SetWrapS(vtkTextureObject::ClampToEdge);
  in.Depth->SetWrapT(vtkTextureObject::ClampToEdge);
  // From a buffer object: the texture is filled from the bound unpack buffer at offset 0 (the
  // null pointer), the same floats into the same texture as from the host.
  if (depthBuffer)
    glBindBuffer(GL_PIXEL_UNPACK_BUFFER, depthBuffer);
  const float* texels = depthBuffer ? nullptr : (depth ? depth : &one);
  const bool uploaded = in.Depth->Create2DFromRaw(writeDepth ? vp.width : 1,
    writeDepth ? vp.height : 1, 1, VTK_FLOAT, const_cast<float*>(texels));
  if (depthBuffer)
    glBindBuffer(GL_PIXEL_UNPACK_BUFFER, 0);
  if (!uploaded)
    throw std::runtime_error("uploading the traced depth to OpenGL failed");

  if (!in.Quad)
  {
    in.Quad.reset(new vtkOpenGLQuadHelper(window,
      vtkOpenGLRenderUtilities::GetFullScreenQuadVertexShader().c_str(), FragmentShader, ""));
  }
  else
  {
    window->GetShaderCache()->ReadyShaderProgram(in.Quad->Program);
  }
  if (!in.Quad->Program || !in.Quad->Program->GetCompiled())
    throw std::runtime_error("the compositing shader did not compile");

  vtkOpenGLState::ScopedglEnableDisable blend(state, GL_BLEND);
  vtkOpenGLState::ScopedglEnableDisable depthTest(state, GL_DEPTH_TEST);
  vtkOpenGLState::ScopedglBlendFuncSeparate blendFunc(state);
  vtkOpenGLState::ScopedglDepthFunc depthFunc(state);
  vtkOpenGLState::ScopedglDepthMask depthMask(state);
  state->vtkglEnable(GL_BLEND);
  // Premultiplied alpha over what is drawn; the window's alpha accumulates coverage.
  state->vtkglBlendFuncSeparate(GL_ONE, GL_ONE_MINUS_SRC_ALPHA, GL_ONE, GL_ONE_MINUS_SRC_ALPHA);
  // The rays already ended at the depth read before, so the written depth is the nearer of the
  // two by construction: always pass, write where asked.
  state->vtkglEnable(GL_DEPTH_TEST);
  state->vtkglDepthFunc(GL_ALWAYS);
  state->vtkglDepthMask(writeDepth ? GL_TRUE : GL_FALSE);

  vtkTextureUnitManager* units = window->GetTextureUnitManager();
  const int colorUnit = units->Allocate();
  if (colorUnit < 0)
    throw std::runtime_error("no texture unit is free for the traced image");
  if (!in.ColorTexture)
    glGenTextures(1, &in.ColorTexture);
  state->vtkglActiveTexture(GL_TEXTURE0 + colorUnit);
  glBindTexture(GL_TEXTURE_BUFFER, in.ColorTexture);
  glTexBuffer(GL_TEXTURE_BUFFER, GL_RGBA32F, buffer);
  in.Depth->Activate();
  in.Quad->Program->SetUniformi("colorBuffer", colorUnit);
  const int size[2] = { colorWidth, colorHeight };
  in.Quad->Program->SetUniform2i("colorSize", size);
  const float viewport[4] = { float(vp.x), float(vp.y), float(vp.width), float(vp.height) };
  in.Quad->Program->SetUniform4f("viewport", viewport);
  in.Quad->Program->SetUniformi("depthTexture", in.Depth->GetTextureUnit());
  in.Quad->Program->SetUniformf("exposure", exposure);
  in.Quad->Program->SetUniformi("writeDepth", writeDepth ? 1 : 0);
  in.Quad->Render();
  in.Depth->Deactivate();
  state->vtkglActiveTexture(GL_TEXTURE0 + colorUnit);
  glBindTexture(GL_TEXTURE_BUFFER, 0);
  units->Free(colorUnit);
}

void Compositor::releaseGraphicsResources(vtkWindow* window)
{
  Internals& in = *this->Internal;
  if (in.Quad)
  {
    in.Quad->ReleaseGraphicsResources(window);
    in.Quad.reset();
  }
  in.releaseShared();
  if (in.HostColor)
    glDeleteBuffers(1, &in.HostColor);
  if (in.ColorTexture)
    glDeleteTextures(1, &in.ColorTexture);
  in.HostColor = in.ColorTexture = 0;
  in.ImportWindow = nullptr;
  in.Importable = -1;
  if (in.Depth)
    in.Depth->ReleaseGraphicsResources(window);
  in.releaseResolve();
}

} // namespace gl
} // namespace svdag
