#include "svdagSelectionDraw.h"

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

namespace svdag
{
namespace gl
{
namespace
{
// The ids arrive as RGBA8 (the uint32's bytes, red the lowest): an 8-bit color buffer stores
// each normalized channel back as the same byte, which is what vtkHardwareSelector decodes.
const char* const FragmentShader = R"(//VTK::System::Dec
//VTK::Output::Dec
in vec2 texCoord;
uniform sampler2D idTexture;
uniform sampler2D depthTexture;
void main()
{
  float depth = texture(depthTexture, texCoord).r;
  if (depth >= 1.0)
    discard;
  gl_FragData[0] = vec4(texture(idTexture, texCoord).rgb, 1.0);
  gl_FragDepth = depth;
}
)";

vtkSmartPointer<vtkTextureObject> nearestTexture(vtkOpenGLRenderWindow* window)
{
  auto texture = vtkSmartPointer<vtkTextureObject>::New();
  texture->SetContext(window);
  texture->SetMinificationFilter(vtkTextureObject::Nearest);
  texture->SetMagnificationFilter(vtkTextureObject::Nearest);
  texture->SetWrapS(vtkTextureObject::ClampToEdge);
  texture->SetWrapT(vtkTextureObject::ClampToEdge);
  return texture;
}
} // namespace

struct SelectionDraw::Internals
{
  std::unique_ptr<vtkOpenGLQuadHelper> Quad;
  vtkSmartPointer<vtkTextureObject> Ids;
  vtkSmartPointer<vtkTextureObject> Depth;
};

SelectionDraw::SelectionDraw()
  : Internal(new Internals)
{
}

SelectionDraw::~SelectionDraw() = default;

void SelectionDraw::draw(vtkOpenGLRenderWindow* window, const Viewport& vp,
  const std::vector<uint32_t>& ids, const std::vector<float>& depth)
{
  Internals& in = *this->Internal;
  const size_t pixels = size_t(vp.width) * size_t(vp.height);
  if (ids.size() != pixels || depth.size() != pixels)
    throw std::runtime_error("selection ids and depth must cover the viewport");
  if (!in.Ids)
  {
    in.Ids = nearestTexture(window);
    in.Depth = nearestTexture(window);
  }
  in.Ids->SetContext(window);
  in.Depth->SetContext(window);
  if (!in.Ids->Create2DFromRaw(vp.width, vp.height, 4, VTK_UNSIGNED_CHAR,
        const_cast<uint32_t*>(ids.data())) ||
    !in.Depth->Create2DFromRaw(vp.width, vp.height, 1, VTK_FLOAT, const_cast<float*>(depth.data())))
    throw std::runtime_error("uploading the selection ids to OpenGL failed");

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
    throw std::runtime_error("the selection shader did not compile");

  vtkOpenGLState* state = window->GetState();
  vtkOpenGLState::ScopedglEnableDisable blend(state, GL_BLEND);
  vtkOpenGLState::ScopedglEnableDisable depthTest(state, GL_DEPTH_TEST);
  vtkOpenGLState::ScopedglDepthFunc depthFunc(state);
  vtkOpenGLState::ScopedglDepthMask depthMask(state);
  // Ids must reach the color buffer unchanged; the nearer of the volume and what is drawn wins.
  state->vtkglDisable(GL_BLEND);
  state->vtkglEnable(GL_DEPTH_TEST);
  state->vtkglDepthFunc(GL_LEQUAL);
  state->vtkglDepthMask(GL_TRUE);

  in.Ids->Activate();
  in.Depth->Activate();
  in.Quad->Program->SetUniformi("idTexture", in.Ids->GetTextureUnit());
  in.Quad->Program->SetUniformi("depthTexture", in.Depth->GetTextureUnit());
  in.Quad->Render();
  in.Depth->Deactivate();
  in.Ids->Deactivate();
}

void SelectionDraw::releaseGraphicsResources(vtkWindow* window)
{
  Internals& in = *this->Internal;
  if (in.Quad)
  {
    in.Quad->ReleaseGraphicsResources(window);
    in.Quad.reset();
  }
  if (in.Ids)
    in.Ids->ReleaseGraphicsResources(window);
  if (in.Depth)
    in.Depth->ReleaseGraphicsResources(window);
}

} // namespace gl
} // namespace svdag
