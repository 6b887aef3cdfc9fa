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
#include "vtk_glew.h"

#include <stdexcept>
#include <string>

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
uniform sampler2D colorTexture;
uniform sampler2D depthTexture;
uniform float exposure;
uniform int writeDepth;
float srgbEncode(float linear)
{
  float c = clamp(linear, 0.0, 1.0);
  return c <= 0.0031308 ? 12.92 * c : 1.055 * pow(c, 1.0 / 2.4) - 0.055;
}
void main()
{
  vec4 hdr = texture(colorTexture, texCoord);
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
} // namespace

struct Compositor::Internals
{
  std::unique_ptr<vtkOpenGLQuadHelper> Quad;
  vtkSmartPointer<vtkTextureObject> Color;
  vtkSmartPointer<vtkTextureObject> Depth;
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

Viewport Compositor::currentViewport(vtkOpenGLRenderWindow* window)
{
  int v[4] = { 0, 0, 0, 0 };
  window->GetState()->vtkglGetIntegerv(GL_VIEWPORT, v);
  return Viewport{ v[0], v[1], v[2], v[3] };
}

std::vector<float> Compositor::readDepth(vtkOpenGLRenderWindow* window, const Viewport& vp)
{
  Internals& in = *this->Internal;
  vtkOpenGLState* state = window->GetState();
  vtkOpenGLClearErrorMacro();
  GLint drawFramebuffer = 0, samples = 0;
  glGetIntegerv(GL_DRAW_FRAMEBUFFER_BINDING, &drawFramebuffer);
  state->PushFramebufferBindings();
  state->vtkglBindFramebuffer(GL_READ_FRAMEBUFFER, GLuint(drawFramebuffer));
  glGetIntegerv(GL_SAMPLES, &samples);
  std::vector<float> depth(size_t(vp.width) * size_t(vp.height), 1.0f);
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
  glReadPixels(x, y, vp.width, vp.height, GL_DEPTH_COMPONENT, GL_FLOAT, depth.data());
  const GLenum error = glGetError();
  state->PopFramebufferBindings();
  if (error != GL_NO_ERROR)
    throw std::runtime_error("reading the depth buffer failed (OpenGL error " +
      std::to_string(error) + ")");
  return depth;
}

void Compositor::draw(vtkOpenGLRenderWindow* window, const Viewport& vp, const float* rgba,
  int colorWidth, int colorHeight, const std::vector<float>& depth, float exposure)
{
  Internals& in = *this->Internal;
  vtkOpenGLState* state = window->GetState();
  if (!in.Color)
  {
    in.Color = vtkSmartPointer<vtkTextureObject>::New();
    in.Depth = vtkSmartPointer<vtkTextureObject>::New();
  }
  in.Color->SetContext(window);
  in.Depth->SetContext(window);
  // Scaled up from a reduced image: bilinear color, nearest depth (depth must not blend across
  // silhouettes).
  in.Color->SetMinificationFilter(vtkTextureObject::Linear);
  in.Color->SetMagnificationFilter(vtkTextureObject::Linear);
  in.Color->SetWrapS(vtkTextureObject::ClampToEdge);
  in.Color->SetWrapT(vtkTextureObject::ClampToEdge);
  if (!in.Color->Create2DFromRaw(colorWidth, colorHeight, 4, VTK_FLOAT, const_cast<float*>(rgba)))
    throw std::runtime_error("uploading the traced image to OpenGL failed");
  const bool writeDepth = !depth.empty();
  const float one = 1.0f;
  in.Depth->SetMinificationFilter(vtkTextureObject::Nearest);
  in.Depth->SetMagnificationFilter(vtkTextureObject::Nearest);
  in.Depth->SetWrapS(vtkTextureObject::ClampToEdge);
  in.Depth->SetWrapT(vtkTextureObject::ClampToEdge);
  if (!in.Depth->Create2DFromRaw(writeDepth ? vp.width : 1, writeDepth ? vp.height : 1, 1,
        VTK_FLOAT, writeDepth ? const_cast<float*>(depth.data()) : const_cast<float*>(&one)))
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

  in.Color->Activate();
  in.Depth->Activate();
  in.Quad->Program->SetUniformi("colorTexture", in.Color->GetTextureUnit());
  in.Quad->Program->SetUniformi("depthTexture", in.Depth->GetTextureUnit());
  in.Quad->Program->SetUniformf("exposure", exposure);
  in.Quad->Program->SetUniformi("writeDepth", writeDepth ? 1 : 0);
  in.Quad->Render();
  in.Depth->Deactivate();
  in.Color->Deactivate();
}

void Compositor::releaseGraphicsResources(vtkWindow* window)
{
  Internals& in = *this->Internal;
  if (in.Quad)
  {
    in.Quad->ReleaseGraphicsResources(window);
    in.Quad.reset();
  }
  if (in.Color)
    in.Color->ReleaseGraphicsResources(window);
  if (in.Depth)
    in.Depth->ReleaseGraphicsResources(window);
  in.releaseResolve();
}

} // namespace gl
} // namespace svdag
