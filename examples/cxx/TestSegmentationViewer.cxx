// The viewer's regression test, the pattern for a project's own tests of vtkSVDAG rendering:
//
//   TestSegmentationViewer FILE -V Baseline/TestSegmentationViewer.png -T TEMPORARY_DIR
//
// renders the viewer's scene (SegmentationScene) off screen, seeded and to a fixed sample count
// (the same image on every run), and checks
// 1. picking and depth against a CPU reference: over a grid of pixels, at LOD block, leaf and
//    voxel, the mapper's pick against vtkSegmentationSVDAGRayCaster's ray through the same pixel
//    center (hit or miss, label, world position), the depth the mapper wrote into the z-buffer
//    against the reference hit, and where the reference hits but the mapper does not, that a mesh
//    drawn nearer than the hit covers the pixel (the outline; depth compositing);
// 2. the highlight: after picking the label at the image center, that label's pixels are
//    brighter and the other labels' darker than before;
// 3. the image against the baseline (vtkRegressionTestImageThreshold: -V baseline, -T where the
//    test image and the difference go on failure; a missing baseline is written there);
// 4. hiding: after HidePickedLabel no pixel picks that label any more.
#include "SegmentationScene.h"

#include "vtkFloatArray.h"
#include "vtkRegressionTestImage.h"
#include "vtkSegmentationSVDAGRayCaster.h"
#include "vtkSegmentationSVDAGRenderSettings.h"
#include "vtkUnsignedCharArray.h"

#include <cmath>
#include <cstdio>
#include <vector>

namespace
{
int failures = 0;
void Check(bool ok, const char* what)
{
  std::printf("%s: %s\n", ok ? "ok" : "FAILED", what);
  if (!ok)
    ++failures;
}

const int Width = 300, Height = 240, Step = 6; // the window and the grid of checked pixels

// What the mapper picked at one grid pixel, and the color shown there.
struct PixelPick
{
  int X, Y;
  bool Hit;
  vtkTypeInt64 Label;
  double Luminance;
};

// Compares the mapper's last frame with the CPU ray caster at the same LOD over the grid; returns
// the picks.
std::vector<PixelPick> CompareWithRayCaster(SegmentationScene& scene, int lod)
{
  vtkNew<vtkSegmentationSVDAGRayCaster> reference;
  reference->SetInputData(scene.Mapper->GetInput());
  reference->SetLOD(lod);
  vtkNew<vtkFloatArray> depth;
  scene.Window->GetZbufferData(0, 0, Width - 1, Height - 1, depth);
  vtkNew<vtkUnsignedCharArray> rgba;
  scene.Window->GetRGBACharPixelData(0, 0, Width - 1, Height - 1, 1, rgba);
  vtkRenderer* renderer = scene.Renderer;

  std::vector<PixelPick> picks;
  int hits = 0, misses = 0, occluded = 0, wrong = 0;
  double worstPosition = 0, worstDepth = 0;
  for (int y = Step / 2; y < Height; y += Step)
    for (int x = Step / 2; x < Width; x += Step)
    {
      const double cx = x + 0.5, cy = y + 0.5; // the pixel's center, where the mapper's ray goes
      const vtkIdType pixel = x + vtkIdType(Width) * y;
      const unsigned char* c = rgba->GetPointer(4 * pixel);
      PixelPick pick{ x, y, scene.Mapper->Pick(renderer, cx, cy), 0,
        0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2] };
      if (pick.Hit)
        pick.Label = scene.Mapper->GetPickedLabel();
      picks.push_back(pick);

      // The reference ray: from the near to the far clipping plane through the pixel's center.
      double nearPoint[4], farPoint[4], direction[3];
      renderer->SetDisplayPoint(cx, cy, 0.0);
      renderer->DisplayToWorld();
      renderer->GetWorldPoint(nearPoint);
      renderer->SetDisplayPoint(cx, cy, 1.0);
      renderer->DisplayToWorld();
      renderer->GetWorldPoint(farPoint);
      for (int a = 0; a < 3; ++a)
      {
        nearPoint[a] /= nearPoint[3];
        direction[a] = farPoint[a] / farPoint[3] - nearPoint[a];
      }
      if (!reference->CastRay(nearPoint, direction))
      {
        misses += pick.Hit ? 0 : 1;
        wrong += pick.Hit ? 1 : 0;
        continue;
      }
      double* expected = reference->GetHitPosition();
      double expectedDisplay[4] = { expected[0], expected[1], expected[2], 1.0 };
      renderer->SetWorldPoint(expectedDisplay);
      renderer->WorldToDisplay();
      renderer->GetDisplayPoint(expectedDisplay);
      const double windowDepth = depth->GetValue(pixel);
      if (!pick.Hit)
      {
        // Only a mesh in front of the volume's surface may hide it.
        if (windowDepth < expectedDisplay[2] - 1e-4)
          ++occluded;
        else
          ++wrong;
        continue;
      }
      double picked[3];
      scene.Mapper->GetPickedPosition(picked);
      // The world point of the written depth at the pixel's center.
      double written[4];
      renderer->SetDisplayPoint(cx, cy, windowDepth);
      renderer->DisplayToWorld();
      renderer->GetWorldPoint(written);
      double position = 0, depthError = 0;
      for (int a = 0; a < 3; ++a)
      {
        position = std::max(position, std::abs(picked[a] - expected[a]));
        depthError = std::max(depthError, std::abs(written[a] / written[3] - expected[a]));
      }
      worstPosition = std::max(worstPosition, position);
      worstDepth = std::max(worstDepth, depthError);
      const double label = reference->GetHitLabelValue()->GetTuple1(0);
      if (double(pick.Label) == label)
        ++hits;
      else
        ++wrong;
    }
  std::printf("LOD %s: %d hits, %d misses, %d occluded by a mesh, %d wrong; worst position error "
              "%.2g, worst depth error %.2g (world units)\n",
    SegmentationScene::LODName(lod), hits, misses, occluded, wrong, worstPosition, worstDepth);
  Check(wrong == 0, "every pick agrees with the CPU ray caster");
  Check(hits > 300 && misses > 300 && occluded > 0, "the grid meets the volume, the background and the outline");
  // Positions: the GPU traces in float; depth: a 24-bit z-buffer over the clipping range.
  Check(worstPosition < 1e-3, "picked positions are the reference hits");
  Check(worstDepth < 0.05, "the written depth is the reference hit's");
  return picks;
}

// Mean luminance of the grid pixels that show `label` (inside == true) or another label.
double MeanLuminance(const std::vector<PixelPick>& picks, vtkTypeInt64 label, bool inside)
{
  double sum = 0;
  int n = 0;
  for (const PixelPick& p : picks)
    if (p.Hit && (p.Label == label) == inside)
    {
      sum += p.Luminance;
      ++n;
    }
  return n > 0 ? sum / n : 0.0;
}
} // namespace

int main(int argc, char* argv[])
{
  if (argc < 2)
  {
    std::fprintf(stderr, "usage: %s FILE -V BASELINE.png -T TEMPORARY_DIR\n", argv[0]);
    return 1;
  }
  SegmentationScene scene;
  scene.Window->SetSize(Width, Height);
  scene.Window->SetMultiSamples(0); // mesh edges the same on every OpenGL
  scene.Window->SetOffScreenRendering(true);
  scene.Mapper->SetTargetSamplesPerPixel(16);
  std::string error;
  if (!scene.Load(argv[1], error))
  {
    std::fprintf(stderr, "TestSegmentationViewer: %s\n", error.c_str());
    return 1;
  }
  vtkSegmentationSVDAGRenderSettings* settings = scene.Mapper->GetSettings();

  // 1. One full frame per LOD is enough for picking (the labels do not depend on the samples).
  for (int lod : { vtkSegmentationSVDAGRenderSettings::LOD_BLOCK,
         vtkSegmentationSVDAGRenderSettings::LOD_LEAF,
         vtkSegmentationSVDAGRenderSettings::LOD_VOXEL })
  {
    settings->SetLOD(lod);
    scene.Window->Render();
    Check(scene.Mapper->GetLastLOD() == lod && scene.Mapper->GetLastReductionFactor() == 1,
      "a still frame is traced at full resolution at the LOD set");
    CompareWithRayCaster(scene, lod);
  }

  // 2. The highlight, on converged images before and after.
  Check(scene.Mapper->RenderUntilConverged(scene.Window) > 0 && scene.Mapper->IsConverged() &&
      scene.Mapper->GetAccumulatedSamples() == 16,
    "the view converges to 16 samples per pixel");
  const std::vector<PixelPick> before =
    CompareWithRayCaster(scene, vtkSegmentationSVDAGRenderSettings::LOD_VOXEL);
  Check(scene.PickAndHighlight(Width / 2 + 0.5, Height / 2 + 0.5), "a label at the center");
  const vtkTypeInt64 picked = scene.PickedLabel;
  std::printf("picked label %lld at (%.3f, %.3f, %.3f)\n", static_cast<long long>(picked),
    scene.PickedPosition[0], scene.PickedPosition[1], scene.PickedPosition[2]);
  scene.Mapper->RenderUntilConverged(scene.Window);
  // The marker now hides the pick; the comparison checks that occlusion too.
  const std::vector<PixelPick> after =
    CompareWithRayCaster(scene, vtkSegmentationSVDAGRenderSettings::LOD_VOXEL);
  const double litBefore = MeanLuminance(before, picked, true);
  const double litAfter = MeanLuminance(after, picked, true);
  const double othersBefore = MeanLuminance(before, picked, false);
  const double othersAfter = MeanLuminance(after, picked, false);
  std::printf("mean luminance of label %lld %.1f -> %.1f, of the others %.1f -> %.1f\n",
    static_cast<long long>(picked), litBefore, litAfter, othersBefore, othersAfter);
  Check(litAfter > litBefore + 20, "the highlighted label is brighter");
  Check(othersAfter < 0.8 * othersBefore, "the other labels are dimmed");

  // 3. The image: seeded and deterministic, so VTK's usual threshold leaves no room for a change.
  const int regression = vtkRegressionTestImageThreshold(scene.Window, 0.15);
  Check(regression == vtkTesting::PASSED, "the image matches the baseline");

  // 4. Hiding the picked label.
  Check(scene.HidePickedLabel(), "the picked label can be hidden");
  scene.Window->Render();
  int stillShown = 0, uncovered = 0;
  for (const PixelPick& p : after)
  {
    const bool hit = scene.Mapper->Pick(scene.Renderer, p.X + 0.5, p.Y + 0.5);
    stillShown += hit && scene.Mapper->GetPickedLabel() == picked;
    uncovered += p.Hit && p.Label == picked;
  }
  Check(uncovered > 0 && stillShown == 0, "the hidden label is picked nowhere");
  return failures == 0 ? 0 : 1;
}
