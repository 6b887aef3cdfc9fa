// The OpenGL side of the volume mapper's selection renders (private to it): during a
// vtkHardwareSelector pass (vtkPropPicker, vtkRenderer::PickProp, area selections) the mapper
// draws, instead of the shaded image, one 24-bit id per pixel in the selector's color encoding
// (red the low byte), where the volume is hit and not farther than the depth buffer, and writes
// the hit's window depth there.
#pragma once

#include "svdagGLCompositor.h" // for Viewport

#include <cstdint>
#include <memory>
#include <vector>

class vtkOpenGLRenderWindow;
class vtkWindow;

namespace svdag
{
namespace gl
{

class SelectionDraw
{
public:
  SelectionDraw();
  ~SelectionDraw();

  // `ids` and `depth`: one value per viewport pixel, row by row from the bottom. Pixels whose
  // depth is 1 (no hit) are left as they are; the others pass the depth test GL_LEQUAL against
  // the depth buffer (the props drawn before the volume), write their id (the low 24 bits) as
  // the color and their depth. Throws std::runtime_error when OpenGL fails.
  void draw(vtkOpenGLRenderWindow* window, const Viewport& viewport,
    const std::vector<uint32_t>& ids, const std::vector<float>& depth);
  void releaseGraphicsResources(vtkWindow* window);

private:
  struct Internals;
  std::unique_ptr<Internals> Internal;
};

} // namespace gl
} // namespace svdag
