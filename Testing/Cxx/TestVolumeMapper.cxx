// Image regression of vtkSegmentationSVDAGVolumeMapper in a VTK render window: a path-traced
// segmentation (a slab, label 3, and a ball, label 7) cut by an opaque mesh box, with a fixed seed
// and sample count, against Testing/Data/Baseline/TestVolumeMapper.png (vtkRegressionTestImage).
// Independent of the baseline, it checks values: the label picked where only the ball can be,
// the window depth of the slab's front face against the analytic depth of that plane, and
// occlusion both ways between the mesh and the volume (picks in front of and behind the box).
#include "vtkActor.h"
#include "vtkCamera.h"
#include "vtkCubeSource.h"
#include "vtkImageData.h"
#include "vtkImageDataToSegmentationSVDAG.h"
#include "vtkNew.h"
#include "vtkPointData.h"
#include "vtkPolyDataMapper.h"
#include "vtkProperty.h"
#include "vtkRegressionTestImage.h"
#include "vtkRenderWindow.h"
#include "vtkRenderer.h"
#include "vtkSegmentationSVDAGLabelProperties.h"
#include "vtkSegmentationSVDAGRenderSettings.h"
#include "vtkSegmentationSVDAGVolumeMapper.h"
#include "vtkUnsignedShortArray.h"
#include "vtkVolume.h"

#include <cmath>
#include <cstdio>

namespace
{
int failures = 0;
void check(bool ok, const char* what)
{
  if (!ok)
  {
    std::printf("FAILED: %s\n", what);
    ++failures;
  }
}
} // namespace

int main(int argc, char* argv[])
{
  const int n = 40;
  vtkNew<vtkImageData> image;
  image->SetDimensions(n, n, n);
  vtkNew<vtkUnsignedShortArray> labels;
  labels->SetNumberOfTuples(vtkIdType(n) * n * n);
  for (int z = 0; z < n; ++z)
    for (int y = 0; y < n; ++y)
      for (int x = 0; x < n; ++x)
      {
        const double r2 = (x - 26) * (x - 26) + (y - 20) * (y - 20) + (z - 20) * (z - 20);
        unsigned short v = 0;
        if (x < 10)
          v = 3;
        else if (r2 < 12 * 12)
          v = 7;
        labels->SetValue(x + n * (y + n * vtkIdType(z)), v);
      }
  image->GetPointData()->SetScalars(labels);
  vtkNew<vtkImageDataToSegmentationSVDAG> builder;
  builder->SetInputData(image);

  vtkNew<vtkSegmentationSVDAGVolumeMapper> mapper;
  mapper->SetInputConnection(builder->GetOutputPort());
  mapper->GetSettings()->SetSun(true);
  mapper->GetSettings()->SetSeed(7);
  mapper->GetSettings()->SetMaximumBounces(2);
  mapper->SetTargetSamplesPerPixel(16);
  mapper->GetLabelProperties()->SetColor(3, 0.3, 0.5, 0.9);
  mapper->GetLabelProperties()->SetColor(7, 0.95, 0.8, 0.2);
  vtkNew<vtkVolume> volume;
  volume->SetMapper(mapper);

  // A thin opaque box through the ball, its front face (z = 28) behind the ball's surface near
  // the ball's center and in front of it near the silhouette: depth compositing both ways.
  vtkNew<vtkCubeSource> cube;
  cube->SetBounds(14, 42, 18, 22, 2, 28);
  vtkNew<vtkPolyDataMapper> cubeMapper;
  cubeMapper->SetInputConnection(cube->GetOutputPort());
  vtkNew<vtkActor> box;
  box->SetMapper(cubeMapper);
  box->GetProperty()->SetColor(0.9, 0.2, 0.2);

  vtkNew<vtkRenderer> renderer;
  renderer->SetBackground(0.1, 0.1, 0.12);
  renderer->AddVolume(volume);
  renderer->AddActor(box);
  vtkCamera* camera = renderer->GetActiveCamera();
  camera->SetPosition(19.5, 19.5, 120);
  camera->SetFocalPoint(19.5, 19.5, 19.5);
  camera->SetViewUp(0, 1, 0);
  camera->SetViewAngle(30);
  camera->SetClippingRange(40, 200);
  vtkNew<vtkRenderWindow> window;
  window->SetSize(240, 200);
  window->SetMultiSamples(0);
  window->AddRenderer(renderer);
  window->Render();
  const int renders = mapper->RenderUntilConverged(window, 120);
  check(renders > 0 && mapper->IsConverged(), "the view converges");
  check(mapper->GetAccumulatedSamples() == 16, "16 samples per pixel accumulate");

  // A display point on the ball, away from the box: the ball's label. The ball's center
  // (x 26, y 20) projects right of the center; y 30 voxels is above the box.
  double world[4] = { 26, 28, 32, 1 };
  renderer->SetWorldPoint(world);
  renderer->WorldToDisplay();
  double display[3];
  renderer->GetDisplayPoint(display);
  check(mapper->Pick(renderer, display[0], display[1]) && mapper->GetPickedLabel() == 7,
    "the ball's label is picked on the ball");
  // The slab's front face is the plane z = 39.5 (voxel 39 spans [38.5, 39.5]); at x = 4.5 the
  // window depth there is the camera's depth of that plane.
  double face[4] = { 4.5, 25.0, 39.5, 1 };
  renderer->SetWorldPoint(face);
  renderer->WorldToDisplay();
  renderer->GetDisplayPoint(display);
  const int px = int(display[0]), py = int(display[1]);
  float depth = 0;
  window->GetZbufferData(px, py, px, py, &depth);
  const double expected = display[2];
  std::printf("slab depth %.8f expected %.8f\n", depth, expected);
  check(std::abs(depth - expected) < 2e-5, "the slab's front face writes its window depth");
  check(mapper->Pick(renderer, px + 0.5, py + 0.5) && mapper->GetPickedLabel() == 3,
    "the slab's label is picked on the slab");
  // Near the ball's silhouette the box is in front (the ball's surface at x = 36, y = 20 is at
  // z = 20 + sqrt(144 - 100) < 28): nothing of the volume is picked there. At the ball's center
  // the ball's surface (z ~ 31.5) is in front of the box: its label is picked.
  double onBox[4] = { 36, 20, 28, 1 };
  renderer->SetWorldPoint(onBox);
  renderer->WorldToDisplay();
  renderer->GetDisplayPoint(display);
  check(!mapper->Pick(renderer, display[0], display[1]), "the box occludes the volume");
  double onBall[4] = { 26.5, 20.5, 31.5, 1 };
  renderer->SetWorldPoint(onBall);
  renderer->WorldToDisplay();
  renderer->GetDisplayPoint(display);
  check(mapper->Pick(renderer, display[0], display[1]) && mapper->GetPickedLabel() == 7,
    "the ball occludes the box");

  const int result = vtkRegressionTestImageThreshold(window, 0.15);
  check(result != vtkRegressionTester::FAILED, "the image matches the baseline");
  return failures == 0 ? 0 : 1;
}
