// Uses the three installed modules as a downstream application would: compresses a label image
// (vtkSVDAG::Core), writes and reads it back as .svdag bytes (vtkSVDAG::IO), checks the decoded
// voxels against the original, and path-traces one frame (vtkSVDAG::Rendering) whose centre
// pixel must see the label that fills the middle of the volume. Prints "install check passed".
#include "vtkImageData.h"
#include "vtkImageDataToSegmentationSVDAG.h"
#include "vtkDataArray.h"
#include "vtkIntArray.h"
#include "vtkNew.h"
#include "vtkPointData.h"
#include "vtkSegmentationSVDAG.h"
#include "vtkSegmentationSVDAGRenderSettings.h"
#include "vtkSegmentationSVDAGRenderer.h"
#include "vtkSegmentationSVDAGToImageData.h"
#include "vtkSegmentationSVDAGWriter.h"
#include "vtkSmartPointer.h"
#include "vtkSegmentationVolumeReader.h"
#include "vtkUnsignedShortArray.h"

#include <iostream>

namespace
{
int fail(const char* what)
{
  std::cerr << "install check failed: " << what << "\n";
  return 1;
}
}

int main()
{
  const int nx = 24, ny = 20, nz = 16;
  vtkNew<vtkImageData> image;
  image->SetDimensions(nx, ny, nz);
  image->AllocateScalars(VTK_UNSIGNED_SHORT, 1);
  auto* voxels = static_cast<unsigned short*>(image->GetScalarPointer());
  for (int z = 0; z < nz; ++z)
    for (int y = 0; y < ny; ++y)
      for (int x = 0; x < nx; ++x)
      {
        unsigned short label = 0;
        if (x >= 6 && x < 18 && y >= 5 && y < 15)
          label = 700; // a box through the whole depth, under the centre of the view
        else if ((x + 2 * y + 3 * z) % 11 == 0)
          label = 3;
        voxels[x + nx * (y + ny * z)] = label;
      }

  vtkNew<vtkImageDataToSegmentationSVDAG> compress;
  compress->SetInputData(image);
  vtkNew<vtkSegmentationSVDAGWriter> writer;
  writer->SetInputConnection(compress->GetOutputPort());
  writer->WriteToOutputStringOn();
  if (!writer->Write())
    return fail("writing .svdag bytes");
  vtkNew<vtkSegmentationVolumeReader> reader;
  reader->ReadFromInputStringOn();
  reader->SetInputArray(writer->GetOutputBytes());
  vtkNew<vtkSegmentationSVDAGToImageData> decode;
  decode->SetInputConnection(reader->GetOutputPort());
  decode->Update();
  vtkImageData* decoded = decode->GetOutput();
  auto* labels = vtkUnsignedShortArray::SafeDownCast(decoded->GetPointData()->GetScalars());
  if (!labels || labels->GetNumberOfValues() != vtkIdType(nx) * ny * nz)
    return fail("decoded volume has the wrong type or size");
  for (vtkIdType i = 0; i < labels->GetNumberOfValues(); ++i)
    if (labels->GetValue(i) != voxels[i])
      return fail("decoded voxels differ from the original");

  vtkNew<vtkSegmentationSVDAGRenderer> renderer;
  renderer->SetInputConnection(reader->GetOutputPort());
  renderer->GetSettings()->SetLODToVoxel();
  renderer->SetWidth(33);
  renderer->SetHeight(33);
  if (!renderer->ResetCamera() || !renderer->Render())
    return fail("rendering (see the error above)");
  auto* hit = vtkIntArray::SafeDownCast(renderer->GetOutput()->GetPointData()->GetArray("Label"));
  if (!hit)
    return fail("the rendered image has no Label array");
  vtkSegmentationSVDAG* volume = reader->GetOutput();
  const int centre = hit->GetValue(16 + 33 * 16); // label index + 1
  vtkSmartPointer<vtkDataArray> values = vtkSmartPointer<vtkDataArray>::Take(volume->NewLabelValues());
  if (centre < 1 || values->GetTuple1(centre - 1) != 700)
    return fail("the centre pixel does not see label 700");
  std::cout << "install check passed (" << volume->GetNumberOfLabels() << " labels, device "
            << renderer->GetDeviceName() << ")\n";
  return 0;
}
